"""halcmd's ``show``, ``list`` and ``save`` output, byte for byte as LinuxCNC 2.9 prints it.

LinuxCNC keeps pins, parameters, signals and functions in lists sorted by name (an alias
replaces the name it aliases), components and threads newest first; every listing here walks
the same order. Patterns follow halcmd: none matches everything, otherwise a name matches
when a pattern is a prefix of it or a shell glob matching it.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Sequence
from typing import Any

from hal.core import (
    DIR_NAMES,
    HAL_BIT,
    HAL_FLOAT,
    HAL_IN,
    HAL_IO,
    HAL_NAME_LEN,
    HAL_OUT,
    HAL_RO,
    HAL_S32,
    HAL_U32,
    HAL_U64,
    TYPE_NAMES,
    TYPES_BY_NAME,
    Hal,
    HalError,
    format_value,
)

# halcmd's name column is as wide as the longest name
NAME_COLUMN = HAL_NAME_LEN
_PIN_ARROW = {HAL_IN: "<==", HAL_OUT: "==>", HAL_IO: "<=>"}
_SIG_ARROW = {HAL_IN: "==>", HAL_OUT: "<==", HAL_IO: "<=>"}
# ``show pin -t TYPE``: LinuxCNC's type words
_TYPE_WORDS = {**TYPES_BY_NAME, "signed": HAL_S32, "unsigned": HAL_U32}

Patterns = Sequence[str] | str | None


def matches(patterns: Patterns, name: str) -> bool:
    """halcmd's rule: no pattern matches all; a pattern matches as a prefix or as a glob."""
    if not patterns:
        return True
    if isinstance(patterns, str):
        patterns = [patterns]
    for pattern in patterns:
        if not pattern:
            return True  # (halcmd stops at the first empty pattern)
        if name.startswith(pattern) or fnmatch.fnmatchcase(name, pattern):
            return True
    return False


def type_column(hal_type: int) -> str:
    """The type padded to five characters, as halcmd's tables and ``save`` print it."""
    return f"{TYPE_NAMES[hal_type]:<5}"


def value_column(hal_type: int, value: int | float) -> str:
    """A value in halcmd's 12-character column (u32 in hex)."""
    if hal_type == HAL_BIT:
        return f"{'TRUE' if value else 'FALSE':>12}"
    if hal_type == HAL_FLOAT:
        return f"{value:12.7g}"
    if hal_type == HAL_U32:
        return f"  0x{int(value):08X}"
    if hal_type == HAL_U64:
        return f"  0x{int(value):016X}"
    return f"  {int(value):>10}"


def packed_value(hal_type: int, value: int | float) -> str:
    """A value without padding (script mode, ``-s``): u32 in decimal."""
    return format_value(hal_type, value, is_show=False)


# ---------------------------------------------------------------- ordering
def pins_in_order(meta: dict[str, Any]) -> list[tuple[str, str, dict[str, Any]]]:
    """(shown name, real name, pin) sorted by shown name, an alias replacing its pin's name."""
    alias_of = {real: alias for alias, real in meta["pin_alias"].items()}
    rows = [(alias_of.get(name, name), name, pin) for name, pin in meta["pins"].items()]
    return sorted(rows, key=lambda row: row[0])


def params_in_order(meta: dict[str, Any]) -> list[tuple[str, str, dict[str, Any]]]:
    alias_of = {real: alias for alias, real in meta["param_alias"].items()}
    rows = [(alias_of.get(name, name), name, param) for name, param in meta["params"].items()]
    return sorted(rows, key=lambda row: row[0])


def comps_newest_first(meta: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    return sorted(meta["comps"].items(), key=lambda item: -item[1]["id"])


def threads_newest_first(meta: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    return list(reversed(meta["threads"].items()))


def pins_of_signals(meta: dict[str, Any]) -> dict[str, list[tuple[str, int]]]:
    """Signal name -> [(shown pin name, direction)] in pin-list order."""
    linked: dict[str, list[tuple[str, int]]] = {}
    for shown, _real, pin in pins_in_order(meta):
        if pin["sig"]:
            linked.setdefault(pin["sig"], []).append((shown, pin["dir"]))
    return linked


def _pin_value(hal: Hal, pin: dict[str, Any]) -> int | float:
    return hal.pin_value(pin)


def _slot_value(hal: Hal, item: dict[str, Any]) -> int | float:
    return hal.read_slot(item["type"], item["slot"])


def _type_filter(patterns: list[str]) -> tuple[int | None, list[str]]:
    """``-t TYPE`` / ``-tTYPE`` at the start of a show pin/sig/param pattern list."""
    if not patterns or not patterns[0].startswith("-t"):
        return None, patterns
    if patterns[0] != "-t":
        word, rest = patterns[0][2:], patterns[1:]
    elif len(patterns) > 1:
        word, rest = patterns[1], patterns[2:]
    else:
        return None, patterns
    return _TYPE_WORDS.get(word), rest


# ---------------------------------------------------------------- show
def show_comps(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    meta = hal.meta
    lines = []
    if not is_script:
        lines += ["Loaded HAL Components:", f"ID      Type  {'Name':<{NAME_COLUMN}} PID   State"]
    for name, comp in comps_newest_first(meta):
        if not matches(patterns, name):
            continue
        kind = "RT" if comp["kind"] == "rt" else "User"
        pid = "" if comp["kind"] == "rt" else str(comp["pid"])
        state = "ready" if comp["is_ready"] else "initializing"
        lines.append(f" {comp['id']:5d}  {kind:<4}  {name:<{NAME_COLUMN}} {pid:>5} {state}")
    return lines


def show_pins(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    hal_type, patterns = _type_filter(list(patterns or []))
    meta = hal.meta
    lines = [] if is_script else ["Component Pins:", "Owner   Type  Dir         Value  Name"]
    for shown, _real, pin in pins_in_order(meta):
        if hal_type is not None and pin["type"] != hal_type:
            continue
        if not matches(patterns, shown):
            continue
        value = _pin_value(hal, pin)
        link = f" {_PIN_ARROW[pin['dir']]} {pin['sig']}" if pin["sig"] else ""
        type_name, dir_name = type_column(pin["type"]), DIR_NAMES[pin["dir"]]
        if is_script:
            words = (pin["owner"], type_name, dir_name, packed_value(pin["type"], value), shown)
            lines.append(" ".join(words) + link)
        else:
            owner = meta["comps"].get(pin["owner"], {}).get("id", 0)
            lines.append(
                f" {owner:5d}  {type_name:>5} {dir_name:<3}  "
                f"{value_column(pin['type'], value):>9}  {shown}{link}"
            )
    return lines


def show_params(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    # (halcmd accepts -t for parameters but, by a slip in its code, does not filter on it)
    _hal_type, patterns = _type_filter(list(patterns or []))
    meta = hal.meta
    lines = [] if is_script else ["Parameters:", "Owner   Type  Dir         Value  Name"]
    for shown, _real, param in params_in_order(meta):
        if not matches(patterns, shown):
            continue
        value = _slot_value(hal, param)
        type_name, dir_name = type_column(param["type"]), DIR_NAMES[param["dir"]]
        if is_script:
            packed = packed_value(param["type"], value)
            lines.append(f"{param['owner']} {type_name} {dir_name} {packed} {shown}")
        else:
            owner = meta["comps"].get(param["owner"], {}).get("id", 0)
            lines.append(
                f" {owner:5d}  {type_name:>5} {dir_name:<3}  "
                f"{value_column(param['type'], value):>9}  {shown}"
            )
    return lines


def show_sigs(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    hal_type, patterns = _type_filter(list(patterns or []))
    meta = hal.meta
    lines = [] if is_script else ["Signals:", "Type          Value  Name     (linked to)"]
    linked = pins_of_signals(meta)
    for name, sig in sorted(meta["sigs"].items()):
        if hal_type is not None and sig["type"] != hal_type:
            continue
        if not matches(patterns, name):
            continue
        value = _slot_value(hal, sig)
        links = [f"{_SIG_ARROW[d]} {p}" for p, d in linked.get(name, [])]
        if is_script:
            head = f"{type_column(sig['type'])}  {packed_value(sig['type'], value)}  {name}"
            lines.append(" ".join([head, *links]))
        else:
            lines.append(f"{type_column(sig['type'])}  {value_column(sig['type'], value)}  {name}")
            lines.extend(f"{'':25}{link}" for link in links)
    return lines


def show_functs(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    meta = hal.meta
    lines = []
    if not is_script:
        lines += ["Exported Functions:", "Owner   CodeAddr  Arg       FP   Users  Name"]
    for index, (name, funct) in enumerate(sorted(meta["functs"].items())):
        if not matches(patterns, name):
            continue
        fp = "YES" if funct["fp"] else "NO"
        owner = meta["comps"].get(funct["owner"], {}).get("id", 0)
        # no code addresses here: stable made-up ones keep the layout
        code, arg = f"{0x7F0000000000 + owner * 0x1000:08x}", f"{0x7F0001000000 + index * 32:08x}"
        if is_script:
            lines.append(f"{funct['owner']} {code} {arg} {fp} {funct['users']:3d} {name}")
        else:
            lines.append(f" {owner:05d}  {code}  {arg}  {fp:<3}  {funct['users']:5d}   {name}")
    return lines


def show_threads(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    meta = hal.meta
    lines = []
    if not is_script:
        lines += [
            "Realtime Threads:",
            "     Period  FP     Name               (     Time, Max-Time )",
        ]
    for name, thread in threads_newest_first(meta):
        if not matches(patterns, name):
            continue
        fp = "YES" if thread["fp"] else "NO"
        spent = _named_value(hal, meta, "pins", f"{name}.time")
        tmax = _named_value(hal, meta, "params", f"{name}.tmax")
        if is_script:
            head = f"{thread['period']} {fp} {name} {spent:8d} {tmax}"
            lines.append("".join([head, *(f" {funct}" for funct in thread["functs"])]))
            continue
        lines.append(f"{thread['period']:11d}  {fp:<3}  {name:>20} ( {spent:8d}, {tmax:8d} )")
        for index, funct in enumerate(thread["functs"], 1):
            lines.append(f"{'':17}{index:2d} {funct}")
    return lines


def _named_value(hal: Hal, meta: dict[str, Any], table: str, name: str) -> int:
    item = meta[table].get(name)
    if item is None:
        return 0
    slot = hal.ptr[item["slot"]] if table == "pins" else item["slot"]
    return int(hal.read_slot(item["type"], slot))


def _alias_table(hal: Hal, patterns: Patterns, table: str, *, is_script: bool) -> list[str]:
    title = "Pin Aliases:" if table == "pin_alias" else "Parameter Aliases:"
    lines = [] if is_script else [title, f" {'Alias':<{NAME_COLUMN}}  Original Name"]
    for alias, real in sorted(hal.meta[table].items()):
        if matches(patterns, alias) or matches(patterns, real):
            lines.append(f" {alias}  {real}" if is_script else f" {alias:<{NAME_COLUMN}}  {real}")
    return lines


def show_pin_aliases(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    return _alias_table(hal, patterns, "pin_alias", is_script=is_script)


def show_param_aliases(hal: Hal, patterns: Patterns, *, is_script: bool) -> list[str]:
    return _alias_table(hal, patterns, "param_alias", is_script=is_script)


_ALL = (
    show_comps,
    show_pins,
    show_pin_aliases,
    show_sigs,
    show_params,
    show_param_aliases,
    show_functs,
    show_threads,
)
_SECTIONS: dict[str, tuple[Any, ...]] = {
    "all": _ALL,
    "comp": (show_comps,),
    "pin": (show_pins,),
    "sig": (show_sigs,),
    "signal": (show_sigs,),
    "param": (show_params,),
    "parameter": (show_params,),
    "funct": (show_functs,),
    "function": (show_functs,),
    "thread": (show_threads,),
    "alias": (show_pin_aliases, show_param_aliases),
}


def show(hal: Hal, kind: str | None, patterns: Patterns = None, *, is_script: bool = False) -> str:
    """The text of ``show [KIND [PATTERN...]]``: each table ends with a blank line."""
    sections = _SECTIONS.get(kind or "all")
    if sections is None:
        raise HalError(f"Unknown 'show' type '{kind}'")
    return "".join(
        "".join(f"{line}\n" for line in section(hal, patterns, is_script=is_script)) + "\n"
        for section in sections
    )


# ---------------------------------------------------------------- list
def listing(hal: Hal, kind: str, patterns: Patterns = None) -> str:
    """``list KIND [PATTERN...]``: each matching name followed by a space, then a newline."""
    meta = hal.meta
    if kind == "comp":
        names = [name for name, _ in comps_newest_first(meta)]
    elif kind == "pin":
        names = [shown for shown, _, _ in pins_in_order(meta)]
    elif kind in ("sig", "signal"):
        names = sorted(meta["sigs"])
    elif kind in ("param", "parameter"):
        names = [shown for shown, _, _ in params_in_order(meta)]
    elif kind in ("funct", "function"):
        names = sorted(meta["functs"])
    elif kind == "thread":
        names = [name for name, _ in threads_newest_first(meta)]
    else:
        raise HalError(f"Unknown 'list' type '{kind}'")
    return "".join(f"{name} " for name in names if matches(patterns, name)) + "\n"


# ---------------------------------------------------------------- save
def save(hal: Hal, kind: str = "all") -> str:
    """``save [KIND]``: HAL commands that rebuild the current configuration."""
    kind = kind or "all"
    meta = hal.meta
    savers = {
        "comp": lambda: _save_comps(meta),
        "alias": lambda: _save_aliases(meta),
        "sig": lambda: _save_signals(meta, is_unlinked_only=False),
        "signal": lambda: _save_signals(meta, is_unlinked_only=False),
        "sigu": lambda: _save_signals(meta, is_unlinked_only=True),
        "link": lambda: _save_links(meta, is_arrowed=False),
        "linka": lambda: _save_links(meta, is_arrowed=True),
        "net": lambda: _save_signal_links(meta, is_arrowed=False),
        "neta": lambda: _save_signal_links(meta, is_arrowed=True),
        "netl": lambda: _save_nets(meta, is_arrowed=False),
        "netla": lambda: _save_nets(meta, is_arrowed=True),
        "netal": lambda: _save_nets(meta, is_arrowed=True),
        "param": lambda: _save_params(hal, meta),
        "parameter": lambda: _save_params(hal, meta),
        "thread": lambda: _save_threads(meta),
        "unconnectedinpins": lambda: _save_unconnected_pins(hal, meta),
    }
    if kind in ("all", "allu"):
        lines = [
            *_save_comps(meta),
            *_save_aliases(meta),
            *_save_signals(meta, is_unlinked_only=True),
            *_save_nets(meta, is_arrowed=True),
            *_save_params(hal, meta),
            *(_save_unconnected_pins(hal, meta) if kind == "allu" else []),
            *_save_threads(meta),
        ]
    elif kind in savers:
        lines = savers[kind]()
    else:
        raise HalError(f"Unknown 'save' type '{kind}'")
    return "".join(f"{line}\n" for line in lines)


def _save_comps(meta: dict[str, Any]) -> list[str]:
    lines = ["# components"]
    for name, comp in sorted(meta["comps"].items(), key=lambda item: item[1]["id"]):
        if comp["kind"] != "rt":
            continue
        args = comp.get("insmod_args")
        if args is None:
            lines.append(f"#loadrt {name}  (not loaded by loadrt, no args saved)")
        else:
            lines.append(f"loadrt {name} {args}")
    return lines


def _save_aliases(meta: dict[str, Any]) -> list[str]:
    lines = ["# pin aliases"]
    lines += [
        f"alias pin {real} {shown}" for shown, real, _ in pins_in_order(meta) if shown != real
    ]
    lines.append("# param aliases")
    lines += [
        f"alias param {real} {shown}" for shown, real, _ in params_in_order(meta) if shown != real
    ]
    return lines


def _save_signals(meta: dict[str, Any], *, is_unlinked_only: bool) -> list[str]:
    linked = pins_of_signals(meta)
    return ["# signals"] + [
        f"newsig {name} {type_column(sig['type'])}"
        for name, sig in sorted(meta["sigs"].items())
        if not (is_unlinked_only and name in linked)
    ]


def _save_links(meta: dict[str, Any], *, is_arrowed: bool) -> list[str]:
    lines = ["# links"]
    for shown, _real, pin in pins_in_order(meta):
        if pin["sig"]:
            arrow = _PIN_ARROW[pin["dir"]] if is_arrowed else ""
            lines.append(f"linkps {shown} {arrow} {pin['sig']}")
    return lines


def _save_signal_links(meta: dict[str, Any], *, is_arrowed: bool) -> list[str]:
    """``save net``/``neta``: each signal as newsig plus one linksp per pin."""
    lines = ["# nets"]
    linked = pins_of_signals(meta)
    for name, sig in sorted(meta["sigs"].items()):
        lines.append(f"newsig {name} {type_column(sig['type'])}")
        for pin, direction in linked.get(name, []):
            arrow = _SIG_ARROW[direction] if is_arrowed else ""
            lines.append(f"linksp {name} {arrow} {pin}")
    return lines


def _save_nets(meta: dict[str, Any], *, is_arrowed: bool) -> list[str]:
    """``save netl``/``netla``: one ``net`` line per linked signal."""
    lines = ["# nets"]
    linked = pins_of_signals(meta)
    for name in sorted(meta["sigs"]):
        pins = linked.get(name)
        if not pins:
            continue
        if not is_arrowed:
            lines.append(" ".join([f"net {name}", *(p for p, _ in pins)]))
            continue
        # the writer, then the I/O pins, then the readers, with halcmd's arrows
        text = f"net {name}"
        is_after_writer = False
        writers = [p for p, d in pins if d == HAL_OUT]
        for pin in writers:
            text += f" {pin}"
            is_after_writer = True
        bidirs = [p for p, d in pins if d == HAL_IO]
        for index, pin in enumerate(bidirs):
            if is_after_writer:
                text += f" => {pin}"
                is_after_writer = False
            elif index:
                text += f" <=> {pin}"
            else:
                text += f" {pin}"
        if bidirs:
            is_after_writer = True
        for pin in (p for p, d in pins if d == HAL_IN):
            if is_after_writer:
                text += f" => {pin}"
                is_after_writer = False
            else:
                text += f" {pin}"
        lines.append(text)
    return lines


def _save_params(hal: Hal, meta: dict[str, Any]) -> list[str]:
    lines = ["# parameter values"]
    for shown, _real, param in params_in_order(meta):
        if param["dir"] != HAL_RO:
            lines.append(f"setp {shown} {value_column(param['type'], _slot_value(hal, param))}")
    return lines


def _save_unconnected_pins(hal: Hal, meta: dict[str, Any]) -> list[str]:
    lines = ["# unconnected pin values"]
    for shown, _real, pin in pins_in_order(meta):
        if not pin["sig"] and pin["dir"] in (HAL_IN, HAL_IO):
            lines.append(f"setp {shown} {value_column(pin['type'], _pin_value(hal, pin))}")
    return lines


def _save_threads(meta: dict[str, Any]) -> list[str]:
    lines = ["# realtime thread/function links"]
    for name, thread in threads_newest_first(meta):
        lines += [f"addf {funct} {name}" for funct in thread["functs"]]
    return lines
