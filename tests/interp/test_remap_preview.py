"""Previews run remapped codes and their Python without a machine (REMAP-057, PY-024):
the web UI's preview (cnc/ui/web/preview.py) and LinuxCNC's ``gcode`` module of UIs load
the INI's remaps; there ``#<_task>`` is 0 and there is no ``emctask`` module."""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

from cnc.ini import IniFile
from cnc.ui.web.preview import decode, preview
from task.interp.python import gcode

INI = """\
[RS274NGC]
SUBROUTINE_PATH = nc_subs
REMAP=M6 modalgroup=6 prolog=change_prolog ngc=rack_change epilog=change_epilog
REMAP=M450 modalgroup=10 ngc=probe_part
REMAP=M451 modalgroup=10 python=on_the_machine

[PYTHON]
PATH_PREPEND = python
TOPLEVEL = python/toplevel.py

[EMCIO]
TOOL_TABLE = tool.tbl
"""
FILES = {
    "tool.tbl": "T1 P1 Z10 D6\nT2 P2 Z20 D3\n",
    "python/toplevel.py": "import remap\n",
    "python/remap.py": """\
        from stdglue import *


        def on_the_machine(self, **words):
            try:
                import emctask  # noqa: F401 (task only)
            except ImportError:
                self.execute("G0 Y7")  # a preview: draw something else
            return INTERP_OK
        """,
    "nc_subs/rack_change.ngc": """\
        o<rack_change> sub
        G53 G0 X[20 + #<selected_tool> * 10] Y50
        o<rack_change> endsub [1]
        M2
        """,
    "nc_subs/probe_part.ngc": """\
        o<probe_part> sub
        o1 if [#<_task> EQ 0]
          G0 X7 (a preview: no probing)
        o1 else
          G38.2 Z-10 F100
        o1 endif
        o<probe_part> endsub
        M2
        """,
    "prog.ngc": "G21 G90\nT2 M6\nM450\nM451\nG0 X1 Y1\nM2\n",
}


@pytest.fixture
def config(tmp_path: Path, monkeypatch) -> Path:
    for name, text in FILES.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    (tmp_path / "test.ini").write_text(INI)
    monkeypatch.chdir(tmp_path)  # (the INI's folders are relative to it, as in LinuxCNC)
    return tmp_path


def test_the_web_preview_runs_remapped_codes_and_their_python(config: Path) -> None:
    chunks: list[bytes] = []
    result = preview(
        str(config / "prog.ngc"),
        chunks.append,
        tool_table=str(config / "tool.tbl"),
        ini=IniFile.load(config / "test.ini"),
    )
    assert result["error"] is None
    ends = [tuple(point[:2]) for point in decode(b"".join(chunks))]
    # the procedure's move to pocket 2, the preview branch of M450, M451's Python, the end
    assert ends[-4:] == [(40.0, 50.0), (7.0, 50.0), (7.0, 7.0), (1.0, 1.0)]
    assert "remap" not in sys.modules  # the plug-in's modules are gone with it


class Recorder:
    """A UI's canon for ``gcode.parse``: records the traverses, ignores the rest."""

    parameter_file = ""

    def __init__(self) -> None:
        self.moves: list[tuple[str, float, float]] = []
        self.messages: list[str] = []

    def straight_traverse(self, x, y, *rest) -> None:
        self.moves.append(("traverse", round(x * 25.4, 6), round(y * 25.4, 6)))

    def message(self, text: str) -> None:
        self.messages.append(text)

    # what the preview asks of a UI (an inch preview of a machine with T1 and T2)
    def get_external_length_units(self) -> float:
        return 1 / 25.4

    def get_external_angular_units(self) -> float:
        return 1.0

    def get_axis_mask(self) -> int:
        return 7

    def get_block_delete(self) -> bool:
        return False

    def get_tool(self, idx: int) -> tuple:
        toolno = idx if idx in (1, 2) else -1
        return (toolno, *[0.0] * 9, 0.0, 0.0, 0.0, 0)

    def __getattr__(self, name: str):
        return lambda *args: None


def test_the_gcode_module_of_uis_runs_remapped_codes(config: Path, monkeypatch) -> None:
    monkeypatch.setenv("INI_FILE_NAME", str(config / "test.ini"))
    canon = Recorder()
    status, _ = gcode.parse(str(config / "prog.ngc"), canon, "G21", "")
    assert status < gcode.MIN_ERROR, gcode.strerror(status)
    assert canon.moves[-4:] == [
        ("traverse", 40.0, 50.0),
        ("traverse", 7.0, 50.0),
        ("traverse", 7.0, 7.0),
        ("traverse", 1.0, 1.0),
    ]
