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


def test_every_save_with_a_backup_leaves_the_previous_content_as_bak(tmp_path: Path) -> None:
    """As LinuxCNC's save of the .var file (a link of the old file, at every save): the
    first save has no previous file, and an unchanged save's previous content is its own;
    the file itself is still not rewritten then."""
    target, backup = tmp_path / "sim.var", tmp_path / "sim.var.bak"
    atomic_write_text(target, "5220\t1.000000\n", keep_backup=True)
    assert not backup.exists()
    inode = target.stat().st_ino
    atomic_write_text(target, "5220\t1.000000\n", keep_backup=True)
    assert backup.read_text() == "5220\t1.000000\n"
    assert target.stat().st_ino == inode
    atomic_write_text(target, "5220\t2.000000\n", keep_backup=True)
    assert backup.read_text() == "5220\t1.000000\n"
    atomic_write_text(target, "5220\t2.000000\n", keep_backup=True)
    assert backup.read_text() == "5220\t2.000000\n"
    backup.unlink()  # (a script removed it)
    atomic_write_text(target, "5220\t2.000000\n", keep_backup=True)
    assert backup.read_text() == "5220\t2.000000\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sim.var", "sim.var.bak"]


def test_a_new_file_gets_the_umask_mode_not_0600(tmp_path: Path) -> None:
    old = os.umask(0o027)
    try:
        atomic_write_text(tmp_path / "position.txt", "1.0\n")
    finally:
        os.umask(old)
    assert (tmp_path / "position.txt").stat().st_mode & 0o777 == 0o640


def test_a_full_disk_leaves_the_old_file_and_no_stray_files(tmp_path: Path, monkeypatch) -> None:
    import errno

    import pytest

    target = tmp_path / "sim.var"
    target.write_text("5220 1.0\n")

    def full(_fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OSError, match="No space"):
        atomic_write_text(target, "5220 2.0\n", keep_backup=True)
    assert target.read_text() == "5220 1.0\n"
    assert [p.name for p in tmp_path.iterdir()] == ["sim.var"]


def test_a_backup_that_cannot_be_written_leaves_nothing(tmp_path: Path, monkeypatch) -> None:
    import errno

    import pytest

    target = tmp_path / "sim.var"
    target.write_text("5220 1.0\n")
    real_fdopen = os.fdopen

    def full_for_backups(fd: int, mode: str = "r", *args, **kwargs):  # type: ignore[no-untyped-def]
        handle = real_fdopen(fd, mode, *args, **kwargs)
        if "b" in mode:  # the backup copy is written in binary
            handle.close()
            raise OSError(errno.ENOSPC, "No space left on device")
        return handle

    monkeypatch.setattr(os, "fdopen", full_for_backups)
    with pytest.raises(OSError, match="No space"):
        atomic_write_text(target, "5220 2.0\n", keep_backup=True)
    assert target.read_text() == "5220 1.0\n"
    assert [p.name for p in tmp_path.iterdir()] == ["sim.var"]
