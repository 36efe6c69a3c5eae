"""halcmd's ``show``, ``list`` and ``save`` output, laid out like LinuxCNC 2.9's.

Listings are sorted by name so related items group together (HAL-006). Pins and
parameters with an alias are listed under their alias, as LinuxCNC does.
"""

from __future__ import annotations

from typing import Any

from hal.core import (
    DIR_NAMES,
    HAL_IN,
    HAL_IO,
    HAL_OUT,
    HAL_RO,
    TYPE_NAMES,
    Hal,
    HalError,
    format_value,
)

_ARROW = {HAL_IN: "<==", HAL_OUT: "==>", HAL_IO: "<=>"}
_SIG_ARROW = {HAL_IN: "==>", HAL_OUT: "<==", HAL_IO: "<=>"}


def _match(pattern: str | None, name: str) -> bool:
    from hal.halcmd import match

    return match(pattern, name)


def _owner_ids(meta: dict[str, Any]) -> dict[str, int]:
    return {name: comp["id"] for name, comp in meta["comps"].items()}


def _aliased(meta: dict[str, Any], table: str, objects: str) -> list[tuple[str, str]]:
    """(shown name, real name) for pins or params, aliases replacing real names."""
    by_real = {real: alias for alias, real in meta[table].items()}
    return sorted((by_real.get(name, name), name) for name in meta[objects])


def show_comps(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    meta = hal.meta
    lines = (
        []
        if is_script
        else [
            "Loaded HAL Components:",
            "ID      Type  Name                                            PID   State",
        ]
    )
    for name, comp in sorted(meta["comps"].items(), key=lambda item: -item[1]["id"]):
        if not _match(pattern, name):
            continue
        kind = "RT" if comp["kind"] == "rt" else "User"
        pid = "" if comp["kind"] == "rt" else str(comp["pid"])
        state = "ready" if comp["is_ready"] else "initializing"
        lines.append(f"{comp['id']:>6}  {kind:<4}  {name:<48}{pid:>5} {state}")
    return lines


def show_pins(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    meta = hal.meta
    ids = _owner_ids(meta)
    lines = [] if is_script else ["Component Pins:", "Owner   Type  Dir         Value  Name"]
    for shown, real in _aliased(meta, "pin_alias", "pins"):
        if not (_match(pattern, shown) or _match(pattern, real)):
            continue
        pin = meta["pins"][real]
        value = format_value(pin["type"], hal.pin_value(pin))
        link = f" {_ARROW[pin['dir']]} {pin['sig']}" if pin["sig"] else ""
        type_name, dir_name = TYPE_NAMES[pin["type"]], DIR_NAMES[pin["dir"]]
        if is_script:
            lines.append(f"{pin['owner']} {type_name:<5} {dir_name} {value} {shown}{link}")
        else:
            owner = ids.get(pin["owner"], 0)
            lines.append(f"{owner:>6}  {type_name:<5} {dir_name:<5}{value:>12}  {shown}{link}")
    return lines


def show_params(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    meta = hal.meta
    ids = _owner_ids(meta)
    lines = [] if is_script else ["Parameters:", "Owner   Type  Dir         Value  Name"]
    for shown, real in _aliased(meta, "param_alias", "params"):
        if not (_match(pattern, shown) or _match(pattern, real)):
            continue
        param = meta["params"][real]
        value = format_value(param["type"], hal.read_slot(param["type"], param["slot"]))
        type_name, dir_name = TYPE_NAMES[param["type"]], DIR_NAMES[param["dir"]]
        if is_script:
            lines.append(f"{param['owner']} {type_name:<5} {dir_name} {value} {shown}")
        else:
            owner = ids.get(param["owner"], 0)
            lines.append(f"{owner:>6}  {type_name:<5} {dir_name:<5}{value:>12}  {shown}")
    return lines


def show_sigs(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    meta = hal.meta
    lines = [] if is_script else ["Signals:", "Type          Value  Name     (linked to)"]
    linked: dict[str, list[tuple[str, int]]] = {}
    for name, pin in sorted(meta["pins"].items()):
        if pin["sig"]:
            linked.setdefault(pin["sig"], []).append((name, pin["dir"]))
    for name, sig in sorted(meta["sigs"].items()):
        if not _match(pattern, name):
            continue
        value = format_value(sig["type"], hal.read_slot(sig["type"], sig["slot"]))
        type_name = TYPE_NAMES[sig["type"]]
        links = [f"{_SIG_ARROW[d]} {p}" for p, d in linked.get(name, [])]
        if is_script:
            lines.append(" ".join([f"{type_name:<6} {value}  {name}", *links]))
        else:
            lines.append(f"{type_name:<5}{value:>14}  {name}")
            lines.extend(f"{'':25}{link}" for link in links)
    return lines


def show_functs(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    meta = hal.meta
    ids = _owner_ids(meta)
    lines = (
        []
        if is_script
        else [
            "Exported Functions:",
            "Owner   CodeAddr  Arg       FP   Users  Name",
        ]
    )
    for index, (name, funct) in enumerate(sorted(meta["functs"].items())):
        if not _match(pattern, name):
            continue
        fp = "YES" if funct["fp"] else "NO"
        owner = ids.get(funct["owner"], 0)
        code, arg = f"{0x7F0000000000 + owner * 0x1000:012x}", f"{0x7F0001000000 + index * 32:012x}"
        if is_script:
            lines.append(f"{funct['owner']} {code} {arg} {fp:<5}{funct['users']} {name}")
        else:
            lines.append(f" {owner:05d}  {code}  {arg}  {fp:<5}{funct['users']:>5}   {name}")
    return lines


def show_threads(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    meta = hal.meta
    lines = (
        []
        if is_script
        else [
            "Realtime Threads:",
            "     Period  FP     Name               (     Time, Max-Time )",
        ]
    )
    for name, thread in reversed(meta["threads"].items()):  # newest first, like LinuxCNC
        if not _match(pattern, name):
            continue
        fp = "YES" if thread["fp"] else "NO"
        spent = _value_of(hal, meta, "pins", f"{name}.time")
        tmax = _value_of(hal, meta, "params", f"{name}.tmax")
        if is_script:
            head = f"{thread['period']} {fp} {name} {spent:>8} {tmax}"
            lines.append(" ".join([head, *thread["functs"]]))
            continue
        lines.append(f"{thread['period']:>11}  {fp:<3}  {name:>20} ( {spent:>8}, {tmax:>8} )")
        for index, funct in enumerate(thread["functs"], 1):
            lines.append(f"{index:>19} {funct}")
    return lines


def _value_of(hal: Hal, meta: dict[str, Any], table: str, name: str) -> int:
    item = meta[table].get(name)
    if item is None:
        return 0
    slot = hal.ptr[item["slot"]] if table == "pins" else item["slot"]
    return int(hal.read_slot(item["type"], slot))


def _alias_table(hal: Hal, pattern: str | None, table: str, *, is_script: bool) -> list[str]:
    title = "Pin Aliases:" if table == "pin_alias" else "Parameter Aliases:"
    lines = [] if is_script else [title, f" {'Alias':<48} Original Name"]
    for alias, real in sorted(hal.meta[table].items()):
        if _match(pattern, alias):
            lines.append(f" {alias}  {real}" if is_script else f" {alias:<48} {real}")
    return lines


def show_pin_aliases(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    return _alias_table(hal, pattern, "pin_alias", is_script=is_script)


def show_param_aliases(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    return _alias_table(hal, pattern, "param_alias", is_script=is_script)


def show_aliases(hal: Hal, pattern: str | None, *, is_script: bool) -> list[str]:
    pins = show_pin_aliases(hal, pattern, is_script=is_script)
    params = show_param_aliases(hal, pattern, is_script=is_script)
    return [*pins, *([] if is_script else [""]), *params]


_SECTIONS = {
    "comp": show_comps,
    "pin": show_pins,
    "sig": show_sigs,
    "signal": show_sigs,
    "param": show_params,
    "parameter": show_params,
    "funct": show_functs,
    "function": show_functs,
    "thread": show_threads,
    "alias": show_aliases,
}


def show(hal: Hal, kind: str, pattern: str | None, *, is_script: bool = False) -> str:
    """The text of ``show KIND [PATTERN]``, ending with a blank line like halcmd."""
    if kind == "all":
        meta = hal.meta
        parts = [
            show_comps,
            show_pins,
            *([show_pin_aliases] if meta["pin_alias"] else []),
            show_sigs,
            show_params,
            *([show_param_aliases] if meta["param_alias"] else []),
            show_functs,
            show_threads,
        ]
        return "".join(
            "\n".join(section(hal, pattern, is_script=is_script)) + "\n\n" for section in parts
        )
    section = _SECTIONS.get(kind)
    if section is None:
        if pattern is None:
            # 'show NAME' with no kind shows everything matching NAME
            return show(hal, "all", kind, is_script=is_script)
        raise HalError(f"Unknown 'show' type '{kind}'")
    return "\n".join(section(hal, pattern, is_script=is_script)) + "\n\n"


def listing(hal: Hal, kind: str, pattern: str | None) -> str:
    """``list KIND [PATTERN]``: names separated by spaces."""
    meta = hal.meta
    tables = {
        "comp": "comps",
        "pin": "pins",
        "sig": "sigs",
        "signal": "sigs",
        "param": "params",
        "parameter": "params",
        "funct": "functs",
        "function": "functs",
        "thread": "threads",
    }
    if kind not in tables:
        raise HalError(f"Unknown 'list' type '{kind}'")
    names = sorted(meta[tables[kind]])
    if kind == "comp":  # newest first, as LinuxCNC lists them
        names = sorted(names, key=lambda name: -meta["comps"][name]["id"])
    if kind in ("pin", "param", "parameter"):
        table = "pin_alias" if kind == "pin" else "param_alias"
        names = [shown for shown, _ in _aliased(meta, table, tables[kind])]
    return " ".join(n for n in names if _match(pattern, n)) + " "


def save(hal: Hal, kind: str, modules: dict[str, str]) -> str:
    """HAL commands that rebuild the current configuration (``save all``)."""
    meta = hal.meta
    out: list[str] = []
    if kind in ("all", "comp"):
        out.append("# components")
        for name, comp in sorted(meta["comps"].items(), key=lambda item: item[1]["id"]):
            if name in modules:
                out.append(f"loadrt {name} {modules[name]}")
            elif comp["kind"] == "rt":
                out.append(f"#loadrt {name}  (not loaded by loadrt, no args saved)")
            else:
                out.append(f"#loadusr {name}")
    if kind in ("all", "alias"):
        out.append("# pin aliases")
        out += [f"alias pin {r} {a}" for a, r in sorted(meta["pin_alias"].items())]
        out.append("# param aliases")
        out += [f"alias param {r} {a}" for a, r in sorted(meta["param_alias"].items())]
    linked: dict[str, list[tuple[str, int]]] = {}
    for name, pin in sorted(meta["pins"].items()):
        if pin["sig"]:
            linked.setdefault(pin["sig"], []).append((name, pin["dir"]))
    if kind in ("all", "sig", "signal"):
        out.append("# signals")
        for name, sig in sorted(meta["sigs"].items()):
            if name not in linked:
                out.append(f"newsig {name} {TYPE_NAMES[sig['type']]}")
    if kind in ("all", "net", "netl", "link"):
        out.append("# nets")
        for name, pins in sorted(linked.items()):
            writers = [p for p, d in pins if d == HAL_OUT]
            bidirs = [p for p, d in pins if d == HAL_IO]
            readers = [p for p, d in pins if d == HAL_IN]
            words = [f"net {name}", *writers, *(["=>"] if writers else []), *readers]
            words += [f"<=> {p}" for p in bidirs]
            out.append(" ".join(words))
    if kind in ("all", "param", "parameter"):
        out.append("# parameter values")
        for name, param in sorted(meta["params"].items()):
            if param["dir"] != HAL_RO:
                value = format_value(
                    param["type"], hal.read_slot(param["type"], param["slot"]), is_show=False
                )
                out.append(f"setp {name} {value:>12}")
    if kind == "unconnectedinpins":
        out.append("# unconnected input pin values")
        for name, pin in sorted(meta["pins"].items()):
            if pin["dir"] != HAL_OUT and not pin["sig"]:
                value = format_value(pin["type"], hal.pin_value(pin), is_show=False)
                out.append(f"setp {name} {value:>12}")
    if kind in ("all", "thread"):
        out.append("# realtime thread/function links")
        for name, thread in meta["threads"].items():
            out += [f"addf {funct} {name}" for funct in thread["functs"]]
    return "\n".join(out) + "\n"
