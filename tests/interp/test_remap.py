"""Remapping and the embedded Python where we go beyond (or away from) LinuxCNC on purpose:
start-up checks of REMAP= lines, the recursion rule, the yield rules, Python's self.execute(),
[PYTHON] settings and [EMC]DEBUG traces (issue 16; REMAP-*, PY-*)."""

from __future__ import annotations

import os
import sys
import textwrap
from pathlib import Path

import pytest

from iocontrol.tooltable import ToolTable
from task.interp import cli
from task.interp.canon import PrintingCanon
from task.interp.errors import INTERP_ENDFILE, INTERP_EXECUTE_FINISH, INTERP_EXIT, InterpError
from task.interp.interp import Interpreter

from .harness import run_rs274_inprocess


def make_config(folder: Path, ini: str, files: dict[str, str] | None = None) -> Path:
    (folder / "test.ini").write_text(textwrap.dedent(ini))
    for name, text in (files or {}).items():
        (folder / name).write_text(textwrap.dedent(text))
    return folder / "test.ini"


def interpreter(folder: Path, ini: str, files: dict[str, str] | None = None):
    """An interpreter set up with the INI (run in ``folder``), and its printed calls."""
    from cnc.ini import IniFile

    path = make_config(folder, ini, files)
    (folder / "t.var").write_text("")
    lines: list[str] = []
    tools = ToolTable()
    tools.load_lines(["T1 P1 Z1 D0.5", "T2 P2 Z2 D0.25"])
    canon = PrintingCanon(lines.append, tools)
    interp = Interpreter(canon, ini=IniFile.load(path), parameter_file=str(folder / "t.var"))
    reports: list[str] = []
    interp.report = reports.append
    _INTERPRETERS.append(interp)
    return interp, lines, reports


def run(interp: Interpreter, program: str, folder: Path) -> list[str]:
    """Run a program; returns the statuses of execute (errors raise)."""
    path = folder / "prog.ngc"
    path.write_text(textwrap.dedent(program))
    interp.open(str(path))
    statuses = []
    while interp.read() != INTERP_ENDFILE:
        status = interp.execute()
        statuses.append(status)
        if status == INTERP_EXIT:
            break
    return statuses


_INTERPRETERS: list[Interpreter] = []


@pytest.fixture
def in_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    yield tmp_path
    # the test's Python modules and folders go, whatever happened to the test
    while _INTERPRETERS:
        _INTERPRETERS.pop().release_python()


M400 = "o<m400> sub\n(debug, p=#<p>)\no<m400> endsub\nM2\n"


# ------------------------------------------------------------ start-up checks
@pytest.mark.parametrize(
    ("line", "cause"),
    [
        ("modalgroup=10 ngc=m400", "the code to remap is missing"),
        ("M400 modalgroup=10 bogus=1 ngc=m400", "unknown option 'bogus'"),
        ("M400 modalgroup=3 ngc=m400", "M codes can be remapped in groups 4 to 10"),
        ("G88.5 modalgroup=2 ngc=m400", "G codes can only be remapped in group 1"),
        ("M0400 ngc=m400", "without leading zeros (M400)"),
        ("M01 modalgroup=4 ngc=m400", "without leading zeros (M1)"),
        ("M400 modalgroup=10 argspec=Pq%", "'%' is not a word letter"),
        ("M400 modalgroup=10", "no procedure: give ngc=<basename> or python=<function>"),
        ("M400 modalgroup=10 ngc=nosuch", "nosuch.ngc not found"),
        ("M400 modalgroup=10 python=foo", "needs the Python plug-in"),
        ("M400 modalgroup=10 ngc=m400 argspec", "option 'argspec' needs '=<value>'"),
        ("M400 modalgroup=10 ngc=", "option 'ngc' has an empty value"),
        ("X400 ngc=m400", "cannot remap this code"),
    ],
)
def test_bad_remap_lines_stop_start_up_with_file_and_line(in_folder, line, cause) -> None:
    interp, _, _ = interpreter(
        in_folder,
        f"[RS274NGC]\nSUBROUTINE_PATH = .\nREMAP={line}\n",
        {"m400.ngc": M400},
    )
    with pytest.raises(InterpError) as error:
        interp.init()
    assert f"test.ini:3: REMAP={line}: " in error.value.message
    assert cause in error.value.message


def test_every_bad_line_is_reported_at_once(in_folder) -> None:
    interp, _, _ = interpreter(
        in_folder,
        "[RS274NGC]\nSUBROUTINE_PATH = .\nREMAP=M400 ngc=m400 modalgroup=10\n"
        "REMAP=M401 foo=1 ngc=m400\nREMAP=m400 ngc=m400 modalgroup=10\n",
        {"m400.ngc": M400},
    )
    with pytest.raises(InterpError) as error:
        interp.init()
    lines = error.value.message.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith(f"{in_folder}/test.ini:4: REMAP=M401")
    assert "m400 is already remapped at" in lines[1] and lines[1].endswith("test.ini:3")


@pytest.mark.parametrize(
    ("code", "why"),
    [("M150", "M100..M199 are user-defined"), ("M3", "built-in M code"), ("G1", "allocated G")],
)
def test_codes_that_cannot_be_remapped_are_ignored_with_a_warning(in_folder, code, why):
    interp, _, reports = interpreter(
        in_folder,
        f"[RS274NGC]\nSUBROUTINE_PATH = .\nREMAP={code} modalgroup=10 ngc=m400\n",
        {"m400.ngc": M400},
    )
    interp.init()
    assert any(f"test.ini:3: REMAP={code}" in r and why in r and "ignored" in r for r in reports)
    assert interp.remaps is None or code not in interp.remaps.by_name


def test_missing_modalgroup_gets_the_default_and_linuxcncs_warning(in_folder) -> None:
    interp, _, reports = interpreter(
        in_folder, "[RS274NGC]\nSUBROUTINE_PATH = .\nREMAP=M400 ngc=m400\n", {"m400.ngc": M400}
    )
    interp.init()
    assert interp.remaps.m[400].modal_group == 10
    assert reports == [
        "warning: code 'M400' : no modalgroup=<int> given, using default group 10 : "
        "3:REMAP = M400 ngc=m400\n"
    ]


def test_python_handlers_must_exist_at_start_up(in_folder) -> None:
    interp, _, _ = interpreter(
        in_folder,
        """\
        [RS274NGC]
        REMAP=M400 modalgroup=10 prolog=missing ngc=m400
        SUBROUTINE_PATH = .
        [PYTHON]
        PATH_PREPEND = .
        TOPLEVEL = toplevel.py
        """,
        {"m400.ngc": M400, "toplevel.py": "import remap\n", "remap.py": "x = 1\n"},
    )
    with pytest.raises(InterpError, match=r"test.ini:2: .*prolog=missing: not a function"):
        interp.init()


def test_a_failing_toplevel_stops_start_up_with_its_traceback(in_folder) -> None:
    interp, _, _ = interpreter(
        in_folder,
        "[PYTHON]\nTOPLEVEL = toplevel.py\n",
        {"toplevel.py": "import nosuchmodule_anywhere\n"},
    )
    with pytest.raises(InterpError) as error:
        interp.init()
    assert "TOPLEVEL=" in error.value.message
    assert "ModuleNotFoundError: No module named 'nosuchmodule_anywhere'" in error.value.message


# -------------------------------------------------------- recursion, nesting
def test_a_new_code_inside_its_own_procedure_is_a_recursion_error(in_folder) -> None:
    interp, lines, _ = interpreter(
        in_folder,
        "[RS274NGC]\nSUBROUTINE_PATH = .\nREMAP=M400 modalgroup=10 ngc=m400\n",
        {"m400.ngc": "o<m400> sub\n(debug, in m400)\nM400\no<m400> endsub\nM2\n"},
    )
    interp.init()
    with pytest.raises(InterpError, match="remapping recursion: M400 is used in its own"):
        run(interp, "M400\nM2\n", in_folder)
    assert sum("in m400" in line for line in lines) == 1  # stopped at once, not 9 deep
    assert interp.remap_level == 0 and interp.call_level == 0


def test_m6_inside_its_own_procedure_is_the_builtin(in_folder) -> None:
    interp, lines, _ = interpreter(
        in_folder,
        """\
        [RS274NGC]
        SUBROUTINE_PATH = .
        REMAP=M6 modalgroup=6 ngc=change
        """,
        {"change.ngc": "o<change> sub\nM6\n(debug, measured)\no<change> endsub\nM2\n"},
    )
    interp.init()
    run(interp, "T1 M6\nM2\n", in_folder)
    text = "".join(lines)
    assert "CHANGE_TOOL(" in text and text.index("CHANGE_TOOL(") < text.index("measured")


# ----------------------------------------------------------- yield rules
PYTHON_INI = """\
[RS274NGC]
SUBROUTINE_PATH = .
{remaps}
[PYTHON]
PATH_PREPEND = .
TOPLEVEL = toplevel.py
"""


def python_interpreter(folder: Path, remaps: str, remap_py: str, **files):
    return interpreter(
        folder,
        PYTHON_INI.format(remaps=remaps),
        {"toplevel.py": "import remap\nimport oword\n", "remap.py": remap_py, **files}
        | ({} if "oword.py" in files else {"oword.py": ""}),
    )


def test_yield_stops_the_interpreter_and_execute_resumes_the_handler(in_folder) -> None:
    interp, lines, _ = python_interpreter(
        in_folder,
        "REMAP=M430 modalgroup=10 python=body",
        """\
        import emccanon
        from interpreter import *
        def body(self, **words):
            emccanon.MESSAGE("before")
            yield INTERP_EXECUTE_FINISH
            emccanon.MESSAGE("after")
        """,
    )
    interp.init()
    (in_folder / "prog.ngc").write_text("M430\n(debug, next line)\nM2\n")
    interp.open(str(in_folder / "prog.ngc"))
    interp.read()
    assert interp.execute() == INTERP_EXECUTE_FINISH
    assert "before" in lines[-1] and interp.call_state != 0
    interp.read()  # keeps the block: the handler resumes
    assert interp.execute() == 0
    assert "after" in lines[-1] and interp.call_state == 0 and interp.call_level == 0
    interp.read()
    interp.execute()
    assert "next line" in lines[-1]


@pytest.mark.parametrize(
    ("remap_py", "oword_py", "program", "message"),
    [
        (
            "def body(self, **w):\n    return 0\n",
            "from interpreter import *\ndef gen(self):\n    yield INTERP_EXECUTE_FINISH\n",
            "o<gen> call\nM2\n",
            "O<gen>: yield is not possible in a Python O-word procedure",
        ),
        (
            "from interpreter import *\n"
            "def body(self, **w):\n    yield INTERP_EXECUTE_FINISH\n    return 3\n",
            "",
            "M430\nM2\n",
            "M430/body: a handler that yields cannot return a value (returned 3)",
        ),
        (
            "from interpreter import *\n"
            "def body(self, **w):\n    self.execute('M431')\n    return INTERP_OK\n"
            "def inner(self, **w):\n    yield INTERP_EXECUTE_FINISH\n",
            "",
            "M430\nM2\n",
            "M431/inner: cannot yield INTERP_EXECUTE_FINISH inside self.execute()",
        ),
        (
            "from interpreter import *\ndef body(self, **w):\n    return INTERP_EXECUTE_FINISH\n",
            "",
            "M430\nM2\n",
            "M430/body: returned INTERP_EXECUTE_FINISH; a handler must yield it",
        ),
    ],
)
def test_yield_violations_are_clear_errors(in_folder, remap_py, oword_py, program, message):
    interp, _, _ = python_interpreter(
        in_folder,
        "REMAP=M430 modalgroup=10 python=body\nREMAP=M431 modalgroup=10 python=inner",
        remap_py + "def inner(self, **w):\n    return 0\n" * ("def inner" not in remap_py),
        **{"oword.py": oword_py},
    )
    interp.init()
    with pytest.raises(InterpError) as error:
        run(interp, program, in_folder)
    assert message in error.value.message
    assert interp.call_level == 0 and interp.remap_level == 0


def test_python_execute_raises_interpreter_exception_unless_told_not_to(in_folder) -> None:
    interp, lines, _ = python_interpreter(
        in_folder,
        "REMAP=M430 modalgroup=10 python=body",
        """\
        import emccanon
        import interpreter
        from interpreter import *
        def body(self, **words):
            try:
                self.execute("G1 X[1/0]", 7)
            except InterpreterException as e:
                emccanon.MESSAGE("caught %d: %s" % (e.line_number, e.error_message))
            interpreter.throw_exceptions = 0
            status = self.execute("G1 X[1/0]")
            interpreter.throw_exceptions = 1
            emccanon.MESSAGE("status %d > %d: %s" % (status, INTERP_MIN_ERROR, self.get_errormsg()))
            return INTERP_OK
        """,
    )
    interp.init()
    run(interp, "M430\nM2\n", in_folder)
    text = "".join(lines)
    assert 'MESSAGE("caught 7: Attempt to divide by zero")' in text
    assert 'MESSAGE("status 5 > 3: Attempt to divide by zero")' in text
    assert interp.call_level == 0 and interp.remap_level == 0


# ------------------------------------------------------------ [PYTHON]
def test_path_prepend_and_append_keep_linuxcncs_order(in_folder) -> None:
    for folder in ("a", "b", "c", "d"):
        (in_folder / folder).mkdir()
        (in_folder / folder / "where.py").write_text(f"NAME = {folder!r}\n")
    interp, _, _ = interpreter(
        in_folder,
        """\
        [PYTHON]
        PATH_PREPEND = a
        PATH_PREPEND = b
        PATH_APPEND = c
        PATH_APPEND = d
        TOPLEVEL = toplevel.py
        """,
        {"toplevel.py": "import sys\nimport where\nPATHS = list(sys.path)\n"},
    )
    interp.init()
    try:
        paths = interp.python.namespace["PATHS"]
        # each PATH_PREPEND goes to the front in turn (the last one first), as in LinuxCNC
        assert paths[:2] == ["b", "a"]
        assert paths.index("c") < paths.index("d") == len(paths) - 2  # our glue is last
        assert interp.python.namespace["where"].NAME == "b"
    finally:
        interp.exit()
    assert "a" not in sys.path and "where" not in sys.modules


def test_reload_on_change_reloads_toplevel_and_its_modules(in_folder) -> None:
    interp, lines, _ = python_interpreter(
        in_folder,
        "REMAP=M430 modalgroup=10 python=body",
        "import emccanon\ndef body(self, **w):\n    emccanon.MESSAGE('first')\n",
    )
    with open(in_folder / "test.ini", "a") as ini:
        ini.write("RELOAD_ON_CHANGE = 1\n")
    from cnc.ini import IniFile

    interp.ini = IniFile.load(in_folder / "test.ini")
    interp.init()
    run(interp, "M430\nM2\n", in_folder)
    remap_py = in_folder / "remap.py"
    remap_py.write_text("import emccanon\ndef body(self, **w):\n    emccanon.MESSAGE('second')\n")
    os.utime(remap_py, (1e9, 1e9))  # surely another time than the first version's
    interp.close()
    run(interp, "M430\nM2\n", in_folder)
    messages = [line for line in lines if "MESSAGE" in line]
    assert 'MESSAGE("first")' in messages[0] and 'MESSAGE("second")' in messages[1]
    interp.exit()


def test_debug_flags_trace_remaps_and_python_calls(in_folder) -> None:
    interp, _, reports = python_interpreter(
        in_folder,
        "REMAP=M430 modalgroup=10 python=body",
        "def body(self, **w):\n    return 0\n",
    )
    ini_path = in_folder / "test.ini"  # (a second [RS274NGC] would not be read, as LinuxCNC)
    text = ini_path.read_text().replace("[RS274NGC]\n", "[RS274NGC]\nLOG_LEVEL = 2\n", 1)
    ini_path.write_text(text + "[EMC]\nDEBUG = 0x0000C000\n")
    from cnc.ini import IniFile

    interp.ini = IniFile.load(in_folder / "test.ini")
    interp.init()
    assert interp.debugmask == 0x4000C000
    run(interp, "M430\nM2\n", in_folder)
    text = "".join(reports)
    assert "remap: M430 (level 1) calls body" in text
    assert "python: M430/body()" in text
    assert "remap: M430 finished" in text
    interp.exit()


def test_emcdebug_user_flags_reach_python(in_folder) -> None:
    interp, lines, _ = python_interpreter(
        in_folder,
        "REMAP=M430 modalgroup=10 python=body",
        "import emccanon\ndef body(self, **w):\n"
        "    if self.debugmask & 0x10000000:\n        emccanon.MESSAGE('USER1 trace')\n",
    )
    with open(in_folder / "test.ini", "a") as ini:
        ini.write("[EMC]\nDEBUG = 0x10008000\n")
    from cnc.ini import IniFile

    interp.ini = IniFile.load(in_folder / "test.ini")
    interp.init()
    run(interp, "M430\nM2\n", in_folder)
    assert any("USER1 trace" in line for line in lines)
    interp.exit()


def test_minimal_configuration_finds_the_standard_glue(in_folder) -> None:
    """REMAP-053: TOPLEVEL imports remap, remap.py imports stdglue: no path needed for it."""
    interp, _, reports = python_interpreter(
        in_folder,
        "REMAP=M6 modalgroup=6 prolog=change_prolog ngc=change epilog=change_epilog",
        "from stdglue import *\n",
        **{"change.ngc": "o<change> sub\no<change> endsub [1]\nM2\n"},
    )
    interp.init()
    assert reports == []
    assert interp.python.find("remap", "change_epilog") is not None
    interp.exit()


# ----------------------------------------------------------- cnc rs274
def test_rs274_takes_options_after_the_file_name(tmp_path) -> None:
    (tmp_path / "test.ngc").write_text("G0 X1\nM2\n")
    (tmp_path / "test.tbl").write_text("T1 P1 Z1\n")
    out, err, rc = run_rs274_inprocess(["-g", "test.ngc", "-t", "test.tbl"], tmp_path)
    assert rc == 0 and "STRAIGHT_TRAVERSE(1.0000" in out and "Usage" not in err


def test_rs274_sets_ini_file_name_for_python_code(tmp_path, monkeypatch) -> None:
    monkeypatch.delenv("INI_FILE_NAME", raising=False)
    make_config(
        tmp_path,
        "[PYTHON]\nPATH_PREPEND = .\nTOPLEVEL = toplevel.py\n",
        {"toplevel.py": "import os\nprint('ini:', os.environ.get('INI_FILE_NAME'))\n"},
    )
    (tmp_path / "test.ngc").write_text("M2\n")
    out, _, rc = run_rs274_inprocess(["-g", "-i", "test.ini", "test.ngc"], tmp_path)
    assert rc == 0 and "ini: test.ini" in out
    assert "INI_FILE_NAME" not in os.environ
    assert cli is not None
