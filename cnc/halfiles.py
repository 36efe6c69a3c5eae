"""The launcher's HAL steps: its halcmd session and the ``[HAL]HALFILE`` entries.

- ``run_halfiles``: each ``[HAL]HALFILE`` found by LinuxCNC's search (``hal.hallib``), run
  by halcmd (``.hal``) or by a Tcl interpreter (``.tcl``, ``hal.haltcl``, with the entry's
  arguments as ``::argv``), or all of them in two passes with ``[HAL]TWOPASS``
  (``hal.twopass``).
- ``LauncherHalCmd``: halcmd as the launcher runs it, for a machine that may have no
  display. ``loadusr`` of a GUI program (pyvcp, gladevcp and qtvcp panels, halshow,
  halmeter, halscope, classicladder's editor, vismach models, and any script that imports a
  GUI toolkit) is skipped with a warning naming it when the machine runs headless. A later
  ``net`` naming a pin of a skipped component gets a *placeholder*: an input pin of the
  signal's type, owned by a stand-in component of that name, so the net is made with every
  other pin in it and the signal holds what it would hold with the panel present and
  untouched (an input pin never conflicts with the signal's writer; a panel's output left
  alone drives nothing either). Each placeholder is reported. ``setp`` of such a pin is
  skipped with a warning. ``hal_manualtoolchange`` (AXIS's tool-change dialog) runs as
  ``cnc.manualtoolchange``, which confirms each change at once, and ``linuxcncrsh`` as
  ``cnc rsh``: LinuxCNC's own programs cannot join this HAL.
"""

from __future__ import annotations

import os
import re
import shutil
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from hal.core import HAL_IN, HalError
from hal.halcmd import HalCmd
from hal.hallib import HalFile, find_halfile

# LinuxCNC programs that open windows, and what they are (for the warning)
GUI_PROGRAMS = {
    "pyvcp": "PyVCP panel",
    "gladevcp": "GladeVCP panel",
    "qtvcp": "QtVCP panel",
    "halshow": "halshow window",
    "halmeter": "halmeter window",
    "halscope": "halscope window",
    "halconfig": "halconfig window",
    "classicladder": "classicladder editor",
    "moveoff_gui": "moveoff panel",
    "sim_pin": "sim_pin window",
    "simulate_probe": "probe simulation window",
    "gremlin_view": "gremlin view window",
    "tooledit": "tool editor window",
    "axis": "AXIS display",
    "touchy": "Touchy display",
    "gmoccapy": "gmoccapy display",
    "gscreen": "gscreen display",
    "tklinuxcnc": "tklinuxcnc display",
    "pyngcgui": "ngcgui window",
    "image-to-gcode": "image-to-gcode window",
    "linuxcnctop": "linuxcnctop window",
}
# LinuxCNC's vismach models (3D views of machines), started by sim configs' HAL files
VISMACH_MODELS = [
    "5axisgui",
    "hbmgui",
    "hexagui",
    "lineardelta",
    "maho600gui",
    "max5gui",
    "melfagui",
    "millturngui",
    "puma560gui",
    "pumagui",
    "rotarydelta",
    "scaragui",
    "xyzab-tdr-gui",
    "xyzac-trt-gui",
    "xyzbc-trt-gui",
    "vmcgui",
]
GUI_PROGRAMS.update(dict.fromkeys(VISMACH_MODELS, "vismach model"))
# our programs standing in for LinuxCNC's (theirs cannot join this HAL)
STAND_INS = {
    "hal_manualtoolchange": [sys.executable, "-m", "cnc.manualtoolchange"],
    "linuxcncrsh": [sys.executable, "-m", "cnc", "rsh"],
}
# a script using a GUI toolkit: Python imports, Tcl's Tk, a wish interpreter
_TOOLKIT_IMPORT = re.compile(
    rb"^\s*(?:import|from)\s+(tkinter|Tkinter|gi|gtk|PyQt5|PyQt6|PySide2|PySide6|qtvcp|"
    rb"gladevcp|pyvcp|vismach|OpenGL)\b|^#!.*\bwish|^\s*package\s+require\s+Tk\b",
    re.MULTILINE,
)
_SCRIPT_BYTES = 65536


class LauncherHalCmd(HalCmd):
    """halcmd as the launcher runs it: GUI programs skipped when there is no display."""

    def __init__(
        self,
        *,
        is_headless: bool,
        warn: Callable[[str], None] | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(**kwargs)
        self.is_headless = is_headless
        self.warn = warn or (lambda text: print(f"cnc: {text}", file=sys.stderr, flush=True))
        self.skipped: dict[str, str] = {}  # component name -> what was skipped
        self.placeholder_comps: set[str] = set()

    # ------------------------------------------------------------ loadusr
    def do_loadusr(self, args: list[str]) -> None:
        flags, comp_name, program, rest = parse_loadusr(args)
        stem = Path(program).name
        if stem in STAND_INS:
            wait = [f for f in flags if f not in ("-W", "-Wn", "-nW", "-n")]
            if any(f in ("-W", "-Wn", "-nW") for f in flags):
                wait.insert(0, "-W")
            super().do_loadusr([*wait, "-n", comp_name or stem, *STAND_INS[stem], *rest])
            return
        toolkit = gui_toolkit(program, rest)
        if toolkit and self.is_headless:
            name = comp_name or gui_component_name(program, rest)
            self.skipped[name] = f"{toolkit} '{' '.join([program, *rest])}'"
            self.warn(
                f"{self.where + ': ' if self.where else ''}skipping loadusr of the {toolkit} "
                f"'{stem}' (no display); its pins, '{name}.*', get placeholders if nets need them"
            )
            return
        super().do_loadusr(args)

    def do_waitusr(self, args: list[str]) -> None:
        if args and args[0] in self.skipped:
            return
        super().do_waitusr(args)

    # ------------------------------------------------------------ pins of skipped programs
    def do_net(self, args: list[str]) -> None:
        if args and self.skipped:
            sig = args[0]
            pins = [a for a in args[1:] if a not in ("=>", "<=", "<=>")]
            missing = [p for p in pins if self._skipped_owner(p) and not self.hal.find_pin(p)]
            for pin in missing:
                if not self._make_placeholder(pin, sig, pins):
                    args = [a for a in args if a != pin]
            if missing and len(args) == 1 and sig not in self.hal.meta["sigs"]:
                return  # nothing but placeholders whose type nothing tells
        super().do_net(args)

    def do_linkps(self, args: list[str]) -> None:
        words = [a for a in args if a not in ("=>", "<=", "<=>")]
        if len(words) == 2 and not self._link_placeholder(words[0], words[1]):
            return
        super().do_linkps(args)

    def do_linksp(self, args: list[str]) -> None:
        words = [a for a in args if a not in ("=>", "<=", "<=>")]
        if len(words) == 2 and not self._link_placeholder(words[1], words[0]):
            return
        super().do_linksp(args)

    def do_setp(self, args: list[str]) -> None:
        owner = self._skipped_owner(args[0]) if args else ""
        if owner and not self.hal.find_pin(args[0]) and not self.hal.find_param(args[0]):
            self.warn(f"{self._place()}setp {args[0]}: skipped ({self.skipped[owner]})")
            return
        super().do_setp(args)

    def do_unload(self, args: list[str]) -> None:
        super().do_unload(args)
        if args and args[0] == "all":
            self.remove_placeholders()

    def remove_placeholders(self) -> None:
        for comp in sorted(self.placeholder_comps):
            if comp in self.hal.meta["comps"]:
                self.hal.remove_component(comp)
        self.placeholder_comps.clear()

    def _link_placeholder(self, pin: str, sig: str) -> bool:
        """Before linkps/linksp: a placeholder for a skipped program's pin; False when the
        command is to be skipped (the pin's type cannot be known)."""
        if not self._skipped_owner(pin) or self.hal.find_pin(pin):
            return True
        return self._make_placeholder(pin, sig, [])

    def _skipped_owner(self, pin: str) -> str:
        for comp in self.skipped:
            if pin.startswith(comp + "."):
                return comp
        return ""

    def _make_placeholder(self, pin: str, sig: str, others: Sequence[str]) -> bool:
        """An input pin standing in for ``pin`` of a skipped program, typed after the
        signal or the other pins of the net; False (and a warning) when neither exists."""
        owner = self._skipped_owner(pin)
        meta = self.hal.meta
        hal_type = meta["sigs"][sig]["type"] if sig in meta["sigs"] else None
        for other in others:
            found = self.hal.find_pin(other) if other != pin else None
            if hal_type is None and found is not None:
                hal_type = found[1]["type"]
        if hal_type is None:
            self.warn(
                f"{self._place()}pin '{pin}' of the skipped {self.skipped[owner]}: left out "
                f"of signal '{sig}' (its type is unknown)"
            )
            return False
        with self.hal.edit():
            if owner not in self.hal.meta["comps"]:
                self.hal.new_component(owner, "user")
                self.hal.ready(owner)
                self.placeholder_comps.add(owner)
            self.hal.new_pin(owner, pin, hal_type, HAL_IN)
        from hal.core import TYPE_NAMES

        self.warn(
            f"{self._place()}pin '{pin}' of the skipped {self.skipped[owner]}: a placeholder "
            f"{TYPE_NAMES[hal_type]} input pin stands in for it on signal '{sig}'"
        )
        return True

    def _place(self) -> str:
        return f"{self.where}: " if self.where else ""


def parse_loadusr(args: Sequence[str]) -> tuple[list[str], str | None, str, list[str]]:
    """loadusr's words -> (flags, component name of -n/-Wn, program, its arguments)."""
    words = list(args)
    flags: list[str] = []
    comp_name = None
    while words and words[0].startswith("-"):
        flag = words.pop(0)
        flags.append(flag)
        if flag in ("-n", "-Wn", "-nW") and words:
            comp_name = words.pop(0)
    if not words:
        raise HalError("loadusr: no program given")
    return flags, comp_name, words[0], words[1:]


def gui_toolkit(program: str, args: Sequence[str]) -> str:
    """What GUI ``program`` opens ("" for none): a known LinuxCNC GUI program, or a script
    importing a GUI toolkit (a vismach model, a user's Tk panel)."""
    name = Path(program).name
    if name == "classicladder" and "--nogui" in args:
        return ""
    if name in GUI_PROGRAMS:
        return GUI_PROGRAMS[name]
    path = program if "/" in program else shutil.which(program)
    if not path or not os.path.isfile(path):
        return ""
    try:
        with open(path, "rb") as handle:
            head = handle.read(_SCRIPT_BYTES)
    except OSError:
        return ""
    if b"\0" in head[:1024]:
        return ""  # a compiled program: it says nothing
    found = _TOOLKIT_IMPORT.search(head)
    return f"GUI program ({found.group(1).decode() if found.group(1) else 'Tk'})" if found else ""


def gui_component_name(program: str, args: Sequence[str]) -> str:
    """The HAL component a GUI program would make: ``-c NAME`` of pyvcp, gladevcp and
    qtvcp, else pyvcp's default ``pyvcp``, else the program's name."""
    words = list(args)
    for index, word in enumerate(words[:-1]):
        if word == "-c":
            return words[index + 1]
    name = Path(program).name
    if name == "gladevcp":
        panels = [w for w in words if w.endswith((".ui", ".glade"))]
        return Path(panels[-1]).stem if panels else "gladevcp"
    return Path(name).stem if name != "pyvcp" else "pyvcp"


# ---------------------------------------------------------------- the HALFILE entries
def find_halfiles(ini: Any, config_dir: Path, extra_dirs: Sequence[str] = ()) -> list[HalFile]:
    """Every ``[HAL]HALFILE`` entry, found; HalError ``file:line: cause`` for one that is
    not there."""
    found = []
    for entry in ini.entries("HAL", "HALFILE"):
        try:
            found.append(find_halfile(entry.value, config_dir, extra_dirs))
        except HalError as exc:
            raise HalError(f"{entry.file}:{entry.line}: [HAL]HALFILE: {exc}") from None
    return found


def run_halfiles(
    session: HalCmd,
    ini: Any,
    halfiles: Sequence[HalFile],
    *,
    say: Callable[[str], None],
    twopass: str = "",
) -> bool:
    """Run the HAL files in order, or in two passes when ``twopass`` (the value of
    ``[HAL]TWOPASS``) is set; errors are printed as ``file:line: cause``. With
    ``session.is_keep_going`` (``cnc run -k``) a failing file does not stop the others.
    True when every file ran without error."""
    if twopass:
        from hal.twopass import TwoPass

        say(f"running {len(halfiles)} HAL files in two passes ([HAL]TWOPASS = {twopass})")
        return TwoPass(session, ini, halfiles, twopass).run()
    is_ok = True
    for halfile in halfiles:
        say(f"running {halfile.path.name}" + (f" {' '.join(halfile.args)}" if halfile.args else ""))
        if halfile.is_tcl:
            from hal.haltcl import HalTcl

            is_file_ok = HalTcl(session, ini).run_file(halfile.path, halfile.args)
        else:
            is_file_ok = session.run_file(str(halfile.path)) == 0
        is_ok = is_ok and is_file_ok
        if not is_file_ok and not session.is_keep_going:
            return False
    return is_ok
