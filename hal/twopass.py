"""``[HAL]TWOPASS``: LinuxCNC's two-pass processing of the ``[HAL]HALFILE`` entries.

With ``TWOPASS`` set (to anything; ``verbose`` in it prints what is done), every HAL file,
``.hal`` or ``.tcl``, is read twice by one Tcl interpreter (LinuxCNC's ``twopass.tcl``):

- **pass 0** collects the ``loadrt`` commands of all files, runs ``loadusr`` commands (so
  what a later ``loadrt`` needs exists), and ignores every other halcmd verb; then each
  module is loaded once, with its instances merged: ``count=`` and ``num_chan=`` added up,
  ``names=`` and ``personality=`` joined with commas, ``debug=`` OR-ed, other arguments
  kept. A module may use only one of the ``count=``, ``num_chan=``, ``names=`` forms;
- **pass 1** runs every file again, for real, except ``loadrt`` of the modules loaded in
  pass 0 and ``loadusr`` (done already); ``addf`` runs where it stands.

So several files may each ``loadrt and2 names=...`` with names of their own. A ``.hal``
file with a ``#NOTWOPASS`` comment line (blanks and case ignored) is left out: it runs
once, at the start, keeping going past errors. ``.hal`` files are read as halcmd reads
them (``[SECTION]KEY`` substituted, then split into words) and each command is run as the
Tcl command of that verb, so ``setp`` values go through ``expr`` as in LinuxCNC.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from hal.core import HalError
from hal.halcmd import logical_lines, strip_comment, tokenize
from hal.haltcl import HalTcl

if TYPE_CHECKING:
    from cnc.ini import IniFile
    from hal.halcmd import HalCmd
    from hal.hallib import HalFile

# the verbs pass 0 does not hide (Tcl's own list, gets, source are not halcmd's here)
_PASS0_VERBS = ("loadrt", "loadusr", "addf")
_TCL_BUILTINS = ("list", "gets", "source")
_MERGED_FORMS = ("count", "num_chan", "names")

_TCL_PASSES = r"""
proc ::haltcl::hide_verbs {} {
    foreach verb $::haltcl::verbs {
        if {$verb in {list gets source}} continue
        if {[info commands ::$verb] eq ""} continue
        rename ::$verb ::haltcl::shown_$verb
        if {$verb in {loadrt loadusr addf}} {
            proc ::$verb args "::haltcl::check \[::haltcl::pass0 $verb {*}\$args\]"
        } else {
            proc ::$verb args return
        }
    }
}
proc ::haltcl::check {reply} {
    lassign $reply failed text
    if {$failed} {
        return -code error $text
    }
    return $text
}
proc ::haltcl::show_verbs {} {
    foreach verb $::haltcl::verbs {
        if {[info commands ::haltcl::shown_$verb] eq ""} continue
        rename ::$verb {}
        rename ::haltcl::shown_$verb ::$verb
    }
}
proc ::tp::passnumber {} {
    return $::TP(passnumber)
}
"""


@dataclass
class _Module:
    """What pass 0 collected for one realtime module."""

    name: str
    form: str = ""  # count, num_chan or names
    count: int = 0
    names: list[str] = field(default_factory=list)
    personality: list[str] = field(default_factory=list)
    debug: int | None = None
    other: list[str] = field(default_factory=list)

    def loadrt_words(self) -> list[str]:
        words = ["loadrt", self.name]
        if self.form in ("count", "num_chan"):
            words.append(f"{self.form}={self.count}")
        elif self.form == "names":
            words.append(f"names={','.join(self.names)}")
        if self.personality:
            words.append(f"personality={','.join(self.personality)}")
        if self.debug is not None:
            words.append(f"debug={self.debug}")
        return words + self.other


class TwoPass:
    """Runs the HAL files of one machine in two passes, in ``session``."""

    def __init__(
        self, session: HalCmd, ini: IniFile, files: Sequence[HalFile], options: str = "on"
    ) -> None:
        self.session = session
        self.ini = ini
        self.files = list(files)
        self.is_verbose = "verbose" in options.lower()
        self.options = [word for word in ("verbose", "nodelete") if word in options.lower()]
        self.haltcl = HalTcl(session, ini)
        self.haltcl.tcl.eval("namespace eval ::tp {}")
        self.haltcl.tcl.createcommand("::haltcl::pass0", self._pass0_verb)
        self.haltcl.tcl.eval(_TCL_PASSES)
        self.modules: dict[str, _Module] = {}
        self.loaded: set[str] = set()
        self.place = ""  # file:line of the .hal line being run

    def run(self) -> bool:
        """Both passes; False (errors printed as ``file:line: cause``) when one failed."""
        # what LinuxCNC's twopass always prints (its tests compare it)
        print(f"twopass:invoked with <{' '.join(self.options)}> options")
        for halfile in self.files:
            print(f"twopass:found {_as_found(halfile.path)}")
        runnable = []
        for halfile in self.files:
            if halfile.path.suffix == ".hal" and _is_excluded(halfile.path):
                print(f"twopass: running {halfile.path} without twopass processing")
                self._run_excluded(halfile.path)
            else:
                runnable.append(halfile)
        tcl = self.haltcl.tcl
        tcl.call("set", "::TP(passnumber)", 0)
        tcl.eval("::haltcl::hide_verbs")
        try:
            is_ok = self._source_all(runnable)
        finally:
            tcl.eval("::haltcl::show_verbs")
        if not is_ok or not self._load_modules():
            return False
        tcl.call("set", "::TP(passnumber)", 1)
        self.haltcl.verb_runner = self._pass1_verb
        return self._source_all(runnable)

    # ------------------------------------------------------------ the files
    def _source_all(self, files: Sequence[HalFile]) -> bool:
        errors = 0
        for halfile in files:
            self._verbose(f"pass{self._pass()}: {halfile.path}")
            if halfile.is_tcl:
                is_ok = self.haltcl.run_file(halfile.path, halfile.args)
            else:
                is_ok = self._run_hal_file(halfile.path)
            errors += not is_ok
        return errors == 0

    def _run_hal_file(self, path: Path) -> bool:
        """A .hal file, each command run as the Tcl command of its verb."""
        try:
            lines = path.read_text(encoding="utf-8", errors="replace").splitlines(True)
        except OSError as exc:
            print(f"{path}: cannot read: {exc.strerror}", file=sys.stderr)
            return False
        for number, text in logical_lines(lines):
            self.place = f"{path}:{number}"
            try:
                words = tokenize(self.session.substitute(strip_comment(text)))
            except HalError as exc:
                print(f"{self.place}: {exc}", file=sys.stderr)
                return False
            if not words:
                continue
            if len(words) == 3 and words[1] == "=":
                words = ["setp", words[0], words[2]]
            verb = words[0].lower()
            try:
                if verb == "source":
                    if not self._run_hal_file(Path(words[1]) if len(words) > 1 else Path()):
                        return False
                elif verb in _TCL_BUILTINS:
                    print(self.haltcl.tcl.call("hal", verb, *words[1:]))
                else:
                    self.haltcl.failed_at = ""
                    self.haltcl.tcl.call(verb, *words[1:])
            except Exception as exc:  # tkinter.TclError: the command failed
                print(f"{self.haltcl.failed_at or self.place}: {exc}", file=sys.stderr)
                return False
        self.place = ""
        return True

    def _run_excluded(self, path: Path) -> None:
        """A #NOTWOPASS file: run once, now, past its errors (LinuxCNC: halcmd -k)."""
        was_keep_going = self.session.is_keep_going
        self.session.is_keep_going = True
        try:
            self.session.run_file(str(path))
        finally:
            self.session.is_keep_going = was_keep_going

    # ------------------------------------------------------------ pass 0
    def _pass0_verb(self, verb: str, *args: str) -> tuple[int, str]:
        """loadrt (collected), loadusr (run now), addf (left for pass 1) during pass 0;
        (failed, text) as ``::haltcl::check`` takes it."""
        is_ok, text = True, ""
        if verb == "loadusr":
            is_ok, text = self.haltcl.run_verb(["loadusr", *args])
        elif verb == "loadrt":
            text = self._collect(self._loadrt_words(args))
            is_ok = not text
        if not is_ok:
            self.haltcl.failed_at = self.haltcl.caller()
        return (0 if is_ok else 1), text

    def _loadrt_words(self, args: Sequence[str]) -> list[str]:
        """loadrt's words; a first argument holding blanks is an INI value list
        (``loadrt $::KINS(KINEMATICS)`` gives ``{trivkins coordinates=XYZ}``): split it."""
        if args and any(ch.isspace() for ch in args[0]):
            inner = self.haltcl.tcl.splitlist(args[0])
            first = " ".join(inner) if len(inner) > 1 else (inner[0] if inner else "")
            return [*first.split(), *args[1:]]
        return list(args)

    def _collect(self, words: list[str]) -> str:
        """Record one pass-0 loadrt; returns a problem, or ""."""
        if not words:
            return "loadrt: no module given"
        name, pairs = words[0], words[1:]
        module = self.modules.setdefault(name, _Module(name))
        for pair in pairs:
            item, _, value = pair.partition("=")
            if item in _MERGED_FORMS:
                form = "count" if item == "num_chan" and module.form == "count" else item
                if module.form and module.form != form:
                    return (
                        f"loadrt {name}: cannot mix count=, num_chan= and names= "
                        f"(first used: {module.form}=)"
                    )
                module.form = form
                if item == "names":
                    module.names.extend(v for v in value.split(",") if v)
                else:
                    try:
                        module.count += int(value, 0)
                    except ValueError:
                        return f"loadrt {name}: {item}={value} is not a number"
            elif item == "personality":
                module.personality.append(value)
            elif item == "debug":
                try:
                    module.debug = (module.debug or 0) | int(value, 0)
                except ValueError:
                    return f"loadrt {name}: debug={value} is not a number"
            else:
                module.other.append(pair)
        self._verbose(f"pass0: deferred loadrt {' '.join(words)}")
        return ""

    def _load_modules(self) -> bool:
        for module in self.modules.values():
            words = module.loadrt_words()
            self._verbose(" ".join(words))
            is_ok, text = self.haltcl.run_verb(words)
            if not is_ok:
                print(f"twopass: {' '.join(words)}: {text}", file=sys.stderr)
                return False
            if text:
                print(text)
            self.loaded.add(module.name)
        return True

    # ------------------------------------------------------------ pass 1
    def _pass1_verb(self, words: list[str]) -> tuple[bool, str]:
        verb = words[0].lower() if words else ""
        if verb == "loadusr":
            return True, ""  # ran in pass 0
        if verb == "loadrt":
            loadrt = self._loadrt_words(words[1:])
            if loadrt and loadrt[0] in self.loaded:
                return True, ""
            words = ["loadrt", *loadrt]
        return self.haltcl.run_verb(words)

    # ------------------------------------------------------------ helpers
    def _pass(self) -> str:
        return self.haltcl.tcl.eval("set ::TP(passnumber)")

    def _verbose(self, text: str) -> None:
        if self.is_verbose:
            print(f"twopass: {text}", flush=True)


def _as_found(path: Path) -> str:
    """A HAL file's path as LinuxCNC's search names it: ``./NAME`` in the current folder
    (the configuration's), else the full path."""
    try:
        return os.path.join(".", path.absolute().relative_to(Path.cwd().absolute()))
    except ValueError:
        return str(path)


def _is_excluded(path: Path) -> bool:
    """A .hal file with a ``#NOTWOPASS`` line (blanks and case ignored) at its start."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return False
    return any(line.replace(" ", "").lower().startswith("#notwopass") for line in lines)
