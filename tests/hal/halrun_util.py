"""Running ``cnc halrun`` / ``cnc halcmd`` as real processes in tests."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
FILES = Path(__file__).resolve().parent / "files"


def without_halcmd(names: list[str]) -> list[str]:
    """Component names without ``halcmd<pid>``, the component every halcmd is while it
    runs (as in LinuxCNC)."""
    return [name for name in names if not re.fullmatch(r"halcmd\d+", name)]


def run_cnc(
    *args: str, text_in: str | None = None, cwd: Path | None = None, timeout: float = 60
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cnc", *args],
        input=text_in,
        capture_output=True,
        text=True,
        cwd=cwd or REPO,
        timeout=timeout,
    )


def halrun_text(tmp_path: Path, hal_text: str, *options: str) -> subprocess.CompletedProcess[str]:
    """Write ``hal_text`` to a file and run it with ``cnc halrun``."""
    path = tmp_path / "test.hal"
    path.write_text(hal_text)
    return run_cnc("halrun", *options, "-f", str(path), cwd=tmp_path)
