"""Files the controller writes are replaced atomically, and not rewritten when unchanged."""

import os
from pathlib import Path

from cnc.atomicfile import atomic_write_text


def test_replaces_content_and_keeps_a_backup(tmp_path: Path) -> None:
    target = tmp_path / "params.var"
    target.write_text("old\n")
    os.chmod(target, 0o640)
    atomic_write_text(target, "new\n", keep_backup=True)
    assert target.read_text() == "new\n"
    assert (tmp_path / "params.var.bak").read_text() == "old\n"
    assert target.stat().st_mode & 0o777 == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.var", "params.var.bak"]


def test_unchanged_content_is_not_rewritten(tmp_path: Path) -> None:
    target = tmp_path / "tool.tbl"
    atomic_write_text(target, "T1 P1\n")
    inode = target.stat().st_ino
    atomic_write_text(target, "T1 P1\n")
    assert target.stat().st_ino == inode  # same file: no replacement happened
    atomic_write_text(target, "T1 P2\n")
    assert target.stat().st_ino != inode and target.read_text() == "T1 P2\n"
