"""Programs where we follow LinuxCNC 2.9.10 rather than the installed 2.9 pre-release rs274.

``lcnc2910/README.md`` names, for each program, the 2.9.10 change it shows. Our output must
be the recorded one, and the installed rs274's recording must differ from it (else the
program no longer shows a difference and belongs in ``corpus/``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from .harness import HERE, compare

FOLDER = HERE / "lcnc2910"
PROGRAMS = sorted(FOLDER.glob("*.ngc"))


@pytest.mark.parametrize("program", PROGRAMS, ids=lambda p: p.stem)
def test_follows_2_9_10(program: Path) -> None:
    problems = compare(program, FOLDER)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("program", PROGRAMS, ids=lambda p: p.stem)
def test_differs_from_installed_rs274(program: Path) -> None:
    ours = [program.with_suffix(s).read_bytes() for s in (".out", ".rc")]
    base = [program.with_suffix(".rs274" + s).read_bytes() for s in (".out", ".rc")]
    assert ours != base
    assert program.stem in (FOLDER / "README.md").read_text()
