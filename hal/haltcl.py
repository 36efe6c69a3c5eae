"""Tcl HAL files, as LinuxCNC's ``haltcl`` runs them.

A ``.tcl`` ``[HAL]HALFILE`` is a Tcl script run by a real Tcl interpreter (Python's
``tkinter.Tcl()``, which needs no display), in which:

- every halcmd verb is a Tcl command (``loadrt``, ``net``, ``setp``, ``addf``, ``getp`` ...)
  whose result is what halcmd prints (``set v [getp pid.0.Pgain]``) and whose failure is a
  Tcl error carrying halcmd's message (so ``catch {loadrt foo} msg`` works); Tcl's own
  ``list``, ``gets`` and ``source`` keep their Tcl meaning, as in LinuxCNC (``hal list``
  reaches halcmd's); ``show`` prints; ``setp`` and ``sets`` evaluate their value with
  ``expr`` (``setp pid.0.Pgain 2*50``);
- ``hal VERB ARGS...`` runs any verb, ``hal --commands`` lists them;
- the INI file's values are global arrays, one per section: ``$::KINS(JOINTS)``, each
  element a Tcl list of the key's values in file order (a repeated key such as
  ``$::HAL(HALFILE)`` has several; LinuxCNC's ``parse_ini``), so a value with blanks is
  read with ``[lindex $::KINS(KINEMATICS) 0]``;
- ``::env`` is the environment (``$::env(HALLIB_DIR)``, ``$::env(INI_FILE_NAME)``);
- ``::argv`` holds the arguments after the file name in the ``HALFILE`` entry;
- ``package require Hal`` and ``package require Linuxcnc`` succeed (``parse_ini`` exists);
- ``exit N`` ends the file: 0 is success, anything else a failure.

Each file runs in a fresh interpreter, as each ``haltcl`` of LinuxCNC's launcher is a new
process. An error is reported as ``file:line: cause``, the line being that of the failing
command (inside a procedure too).
"""

from __future__ import annotations

import io
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hal.core import HAL_IN, HAL_IO, HAL_OUT, TYPE_NAMES, HalError, format_value

if TYPE_CHECKING:
    from cnc.ini import IniFile
    from hal.halcmd import HalCmd

#: halcmd's commands, as LinuxCNC's ``hal --commands`` lists them
HALCMD_VERBS = [
    "addf",
    "alias",
    "delf",
    "delsig",
    "debug",
    "echo",
    "getp",
    "gets",
    "print",
    "ptype",
    "stype",
    "help",
    "linkpp",
    "linkps",
    "linksp",
    "list",
    "loadrt",
    "loadusr",
    "lock",
    "net",
    "newsig",
    "save",
    "setexact_for_test_suite_only",
    "setp",
    "sets",
    "show",
    "source",
    "start",
    "status",
    "stop",
    "unalias",
    "unecho",
    "unlinkp",
    "unload",
    "unloadrt",
    "unloadusr",
    "unlock",
    "waitusr",
]
INSTALL_HINT = (
    "Tcl HAL files need Tcl for Python (tkinter): on Debian, apt-get install python3-tk "
    "(or libtcl8.6 libtk8.6 for a Python built with _tkinter)"
)
_EXIT_CODE = "HALTCL_EXIT"
_DIRECTIONS = {HAL_IN: "IN", HAL_OUT: "OUT", HAL_IO: "I/O"}
# Tcl's "(file "x.tcl" line 12)" in ::errorInfo, for errors Tcl itself raises
_ERRORINFO_PLACE = re.compile(r'\(file "([^"]*)" line (\d+)\)')

# What haltcl adds to a plain Tcl interpreter. ::haltcl::call is the Python side.
_PRELUDE = r"""
namespace eval ::haltcl {}
proc hal {args} {
    if {[llength $args] == 0} {
        return -code error {wrong # args: should be "hal command ..."}
    }
    if {[lindex $args 0] eq "--commands"} {
        return $::haltcl::verbs
    }
    lassign [::haltcl::call {*}$args] failed text
    if {$failed} {
        return -code error $text
    }
    return $text
}
foreach ::haltcl::verb $::haltcl::verbs {
    if {[info commands $::haltcl::verb] eq {}} {
        proc $::haltcl::verb args "eval hal $::haltcl::verb \$args"
    }
}
unset ::haltcl::verb
proc setp {name value} {
    hal setp $name [uplevel 1 [list expr $value]]
}
proc sets {name value} {
    hal sets $name [uplevel 1 [list expr $value]]
}
proc show args {
    puts [eval hal show $args]
}
proc parse_ini {filename} {
    set problem [::haltcl::parse_ini $filename]
    if {$problem ne ""} {
        return -code error $problem
    }
}

proc exit {{status 0}} {
    return -code error -errorcode [list HALTCL_EXIT $status] "exit $status"
}
package provide Hal 1.0
package provide Linuxcnc 1.0
"""


def make_interpreter() -> Any:
    """A new Tcl interpreter (no display needed); HalError with the install hint if Python
    has no Tcl."""
    try:
        import tkinter

        return tkinter.Tcl()
    except (ImportError, RuntimeError) as exc:  # no _tkinter, or no Tcl library found
        raise HalError(f"{INSTALL_HINT} ({exc})") from None


def is_available() -> bool:
    try:
        make_interpreter()
    except HalError:
        return False
    return True


class HalTcl:
    """One haltcl interpreter running halcmd verbs in ``session``.

    ``verb_runner`` (words -> (is_ok, text)) may be replaced to give verbs another meaning
    (twopass does, per pass); by default each verb runs in ``session``.
    """

    def __init__(self, session: HalCmd, ini: IniFile | None = None) -> None:
        self.session = session
        self.ini = ini
        self.tcl = make_interpreter()
        self.verb_runner: Callable[[list[str]], tuple[bool, str]] = self.run_verb
        self.failed_at = ""  # where the last failing halcmd verb was called, file:line
        self.tcl.createcommand("::haltcl::call", self._call)
        self.tcl.createcommand("::haltcl::parse_ini", self._parse_ini)
        self.tcl.createcommand("::haltcl::pin_info", self._pin_info)
        self.tcl.createcommand("::haltcl::signal_info", self._signal_info)
        self.tcl.createcommand("::haltcl::thread_info", self._thread_info)
        self.tcl.call("set", "::haltcl::verbs", tuple(HALCMD_VERBS))
        self.tcl.eval(_PRELUDE)
        if ini is not None:
            self.set_ini_arrays(ini)

    # ------------------------------------------------------------ INI values
    def set_ini_arrays(self, ini: IniFile) -> None:
        """``::SECTION(KEY)``: the list of the key's values, as LinuxCNC's parse_ini."""
        for section in ini.sections():
            self.tcl.call("array", "unset", f"::{section}")
            for key, value in ini.items(section):
                self.tcl.call("lappend", f"::{section}({key})", value)

    def _parse_ini(self, filename: str) -> str:
        """``parse_ini FILE``: the arrays of another INI file; returns the problem, if any."""
        from cnc.ini import IniFile

        try:
            self.set_ini_arrays(IniFile.load(filename))
        except (OSError, ValueError) as exc:
            return str(exc)
        return ""

    # ------------------------------------------------------------ HAL as Tcl data
    # (for hal_procs_lib.tcl: what LinuxCNC's version reads out of ``show`` text)
    def _pin_info(self, name: str) -> tuple[str, ...]:
        """``::haltcl::pin_info NAME``: {owner type direction value signal}, {} if none."""
        found = self.session.hal.find_pin(name)
        if found is None:
            return ()
        pin = found[1]
        value = format_value(pin["type"], self.session.hal.pin_value(pin), is_show=False)
        direction = _DIRECTIONS.get(pin["dir"], "?")
        return pin["owner"], TYPE_NAMES[pin["type"]], direction, value, pin["sig"] or ""

    def _signal_info(self, name: str) -> tuple[Any, ...]:
        """``::haltcl::signal_info NAME``: {type inputs outputs ios}, {} if none."""
        meta = self.session.hal.meta
        signal = meta["sigs"].get(name)
        if signal is None:
            return ()
        linked = {HAL_IN: [], HAL_OUT: [], HAL_IO: []}
        for pin_name, pin in sorted(meta["pins"].items()):
            if pin["sig"] == name:
                linked[pin["dir"]].append(pin_name)
        kind = TYPE_NAMES[signal["type"]]
        return kind, tuple(linked[HAL_IN]), tuple(linked[HAL_OUT]), tuple(linked[HAL_IO])

    def _thread_info(self) -> tuple[Any, ...]:
        """``::haltcl::thread_info``: {name period uses-fp {functions in order}} each."""
        threads = self.session.hal.meta["threads"]
        return tuple(
            (name, thread["period"], int(bool(thread["fp"])), tuple(thread["functs"]))
            for name, thread in threads.items()
        )

    # ------------------------------------------------------------ running files
    def run_file(self, path: str | Path, args: Sequence[str] = ()) -> bool:
        """Source a Tcl HAL file with ``::argv`` = ``args``; False (the error printed as
        ``file:line: cause``) when it fails or calls ``exit`` with a status other than 0."""
        self.tcl.call("set", "::argv", tuple(args))
        self.tcl.call("set", "::argc", len(args))
        self.tcl.call("set", "::argv0", str(path))
        self.failed_at = ""
        try:
            self.tcl.call("source", str(path))
        except Exception as exc:  # tkinter.TclError: the script failed
            return self._report(path, str(exc))
        return True

    def _report(self, path: str | Path, message: str) -> bool:
        code = self.tcl.eval("set ::errorCode")
        if code.startswith(_EXIT_CODE):
            status = code.split()[1] if len(code.split()) > 1 else "1"
            if status == "0":
                return True
            message = f"exit {status}"
        place = self.failed_at or _place_in_errorinfo(self.tcl.eval("set ::errorInfo"))
        print(f"{place or path}: {message}", file=sys.stderr, flush=True)
        return False

    # ------------------------------------------------------------ verbs
    def run_verb(self, words: list[str]) -> tuple[bool, str]:
        """Run one halcmd verb in the session; (is_ok, what it printed or its error)."""
        session = self.session
        saved = session.out, session.err, session.where
        out, err = io.StringIO(), io.StringIO()
        session.out, session.err, session.where = out, err, ""
        try:
            is_ok = session.run_words(words)
        finally:
            session.out, session.err, session.where = saved
        if not is_ok:
            return False, err.getvalue().strip() or f"{words[0]} failed"
        if err.getvalue().strip():  # warnings of a command that worked: shown, not returned
            for line in err.getvalue().strip().splitlines():
                print(f"{self.caller()}: {line}", file=sys.stderr, flush=True)
        return True, out.getvalue().rstrip("\n")

    def _call(self, *words: str) -> tuple[int, str]:
        try:
            is_ok, text = self.verb_runner(list(words))
        except HalError as exc:
            is_ok, text = False, str(exc)
        if not is_ok:
            self.failed_at = self.caller()
        return (0 if is_ok else 1), text

    def caller(self) -> str:
        """``file:line`` of the innermost command being run from a file (procedures defined
        in a file report their absolute line); "" when none is."""
        depth = int(self.tcl.eval("info frame"))
        for level in range(depth, 0, -1):
            words = self.tcl.splitlist(self.tcl.eval(f"info frame {level}"))
            frame = dict(zip(words[0::2], words[1::2], strict=False))
            if "file" in frame:
                return f"{frame['file']}:{frame.get('line', '?')}"
        return ""


def _place_in_errorinfo(info: str) -> str:
    found = _ERRORINFO_PLACE.search(info)
    return f"{found.group(1)}:{found.group(2)}" if found else ""


def main(argv: list[str] | None = None) -> int:
    """``cnc haltcl [-i INI] [FILE [ARGS...]]``: LinuxCNC's haltcl; without FILE, Tcl
    commands from standard input (``haltcl:`` prompt on a terminal)."""
    from hal.halcmd import HalCmd

    args = list(sys.argv[1:] if argv is None else argv)
    ini = None
    if len(args) >= 2 and args[0] in ("-i", "-ini"):
        from cnc.ini import IniError, IniFile

        try:
            ini = IniFile.load(args[1])
        except IniError as exc:
            print(f"haltcl: {exc}", file=sys.stderr)
            return 1
        args = args[2:]
    session = HalCmd(ini=ini)
    try:
        haltcl = HalTcl(session, ini)
        if args:
            return 0 if haltcl.run_file(args[0], args[1:]) else 1
        return _interactive(haltcl)
    except HalError as exc:
        print(f"haltcl: {exc}", file=sys.stderr)
        return 1
    finally:
        session.hal.close()


def _interactive(haltcl: HalTcl) -> int:
    is_tty = sys.stdin.isatty()
    pending = ""
    while True:
        if is_tty:
            print("haltcl: " if not pending else "> ", end="", flush=True)
        line = sys.stdin.readline()
        if not line:
            return 0
        pending += line
        if not haltcl.tcl.call("info", "complete", pending):
            continue
        script, pending = pending, ""
        try:
            result = haltcl.tcl.eval(script)
        except Exception as exc:  # tkinter.TclError: show it, go on
            print(exc, file=sys.stderr)
            continue
        if result and is_tty:
            print(result)
