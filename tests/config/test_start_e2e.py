"""``cnc run`` refuses a machine with a bad INI value, tool table or .var file before it
starts anything: the message names the file, line, key and allowed range; nothing runs
afterwards, no shared memory is left, and not one of the user's files is changed or added.
And a machine whose INI file is reached through a symlink and split by #INCLUDE starts."""

from __future__ import annotations

import re
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

import cnc
from nml.ipcnames import instance_objects
from tests.task.test_machine import MACHINE, Machine


def edit(name: str, old: str, new: str) -> Callable[[Path], None]:
    """Replace the first ``old`` in file ``name`` of the machine folder by ``new``."""

    def change(folder: Path) -> None:
        path = folder / name
        text = path.read_text()
        assert old in text, (name, old)
        path.write_text(text.replace(old, new, 1))

    return change


def write(name: str, content: bytes) -> Callable[[Path], None]:
    return lambda folder: (folder / name).write_bytes(content)


JOINT_0_LIMIT = "MAX_LIMIT = 100\nMAX_VELOCITY = 50\nMAX_ACCELERATION = 1000\nFERROR"
# case -> (change, the file at fault, the text of the line at fault (None: no line), cause)
CASES = {
    "nan limit": (
        edit("mill.ini", JOINT_0_LIMIT, JOINT_0_LIMIT.replace("100", "nan")),
        "mill.ini", "MAX_LIMIT = nan",
        "[JOINT_0]MAX_LIMIT = 'nan' is not a finite number; allowed: a number",
    ),
    "inf limit": (
        edit("mill.ini", "[AXIS_X]\nMIN_LIMIT = -100\nMAX_LIMIT = 100",
             "[AXIS_X]\nMIN_LIMIT = -100\nMAX_LIMIT = inf"),
        "mill.ini", "MAX_LIMIT = inf",
        "[AXIS_X]MAX_LIMIT = 'inf' is not a finite number; allowed: a number",
    ),
    "zero acceleration": (
        edit("mill.ini", "MAX_ACCELERATION = 1000\nFERROR", "MAX_ACCELERATION = 0\nFERROR"),
        "mill.ini", "MAX_ACCELERATION = 0",
        "[JOINT_0]MAX_ACCELERATION = '0' is out of range; allowed: a number > 0",
    ),
    "negative task cycle": (
        edit("mill.ini", "CYCLE_TIME = 0.005", "CYCLE_TIME = -5"),
        "mill.ini", "CYCLE_TIME = -5",
        "[TASK]CYCLE_TIME = '-5' is out of range; allowed: a number > 0 and <= 1",
    ),
    "zero task cycle": (
        edit("mill.ini", "CYCLE_TIME = 0.005", "CYCLE_TIME = 0"),
        "mill.ini", "CYCLE_TIME = 0",
        "[TASK]CYCLE_TIME = '0' is out of range; allowed: a number > 0 and <= 1",
    ),
    "unknown axis letter": (
        edit("mill.ini", "COORDINATES = X Y Z", "COORDINATES = X Y Q"),
        "mill.ini", "COORDINATES = X Y Q",
        "[TRAJ]COORDINATES = 'X Y Q' names no axis Q; allowed: axis letters",
    ),
    "empty ini": (
        write("mill.ini", b""),
        "mill.ini", None,
        "[TRAJ]LINEAR_UNITS is missing (required: one of mm, metric, in, inch",
    ),
    "nan tool offset": (
        edit("test.tbl", "T2 P2 Z20.0", "T2 P2 Z+nan"),
        "test.tbl", "T2 P2 Z+nan",
        "Z = nan is not a finite number",
    ),
    "bad tool line": (
        edit("test.tbl", "T2 P2 Z20.0", "T2 P2 Z2O.0"),  # LinuxCNC would read Z2
        "test.tbl", "Z2O.0",
        "bad number in word 'Z2O.0'",
    ),
    "var out of order": (
        write("test.var", b"5220\t1.000000\n5161\t2.000000\n"),
        "test.var", "5161",
        "parameter 5161 after 5220: the numbers must be in ascending order",
    ),
    "var out of range": (
        write("test.var", b"5220\t1.000000\n9999\t2.000000\n"),
        "test.var", "9999",
        "parameter number 9999 out of range 1 to 5601",
    ),
    "var garbage": (
        write("test.var", b"5220\t1.000000\nhello there\n"),
        "test.var", "hello there",
        "not '<parameter number> <value>': hello there",
    ),
    "var binary": (
        write("test.var", b"5220\t1.000000\n\x7fELF\x02\x01\x01\x00\xff\xfe\n"),
        "test.var", "ELF",
        "not a text file (binary data)",
    ),
}  # fmt: skip


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(path.relative_to(folder)): path.read_bytes() for path in folder.rglob("*")}


@pytest.mark.parametrize("case", CASES)
def test_a_bad_file_is_refused_before_anything_starts(
    case: str, procs, tmp_path: Path, cnc_instance: str
) -> None:
    change, file, at, cause = CASES[case]
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    change(folder)
    before = snapshot(folder)
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 1
    found = [line for line in err.splitlines() if cause in line]
    assert found, err
    match = re.fullmatch(rf"cnc: {re.escape(str(folder / file))}(?::(\d+))?: .*", found[0])
    assert match, found[0]
    if at is None:
        assert match.group(1) is None
    else:
        lines = (folder / file).read_text(errors="replace").splitlines()
        assert at in lines[int(match.group(1)) - 1]
    assert "starting" not in err  # refused before the buffers, the host or any process
    assert instance_objects(cnc_instance) == []
    assert not subprocess.run(["pgrep", "-f", str(folder)], capture_output=True).stdout
    assert snapshot(folder) == before  # nothing changed, nothing added (no .bak, no temp)


@pytest.mark.slow
def test_a_symlinked_ini_file_split_by_includes_finds_its_files_beside_the_link(
    procs, tmp_path: Path
) -> None:
    """As LinuxCNC: relative names in the INI file, #INCLUDE's too, are relative to the
    folder the INI path names, not to where a symlink points."""
    shared = tmp_path / "shared"
    shared.mkdir()
    text = (MACHINE / "mill.ini").read_text()
    head, joints = text.split("[AXIS_X]", 1)
    (shared / "mill.ini").write_text(head + "#INCLUDE limits/axes.inc\n")
    machine_folder = tmp_path / "machine"
    (machine_folder / "limits").mkdir(parents=True)
    (machine_folder / "limits" / "axes.inc").write_text("[AXIS_X]" + joints)
    for name in ("mill.hal", "test.tbl", "test.var"):  # only beside the link
        shutil.copy(MACHINE / name, machine_folder / name)
    (machine_folder / "mill.ini").symlink_to(shared / "mill.ini")
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=machine_folder)
    machine = Machine(proc, machine_folder)
    try:
        machine.wait_ready()
        machine.stat.poll()
        assert machine.stat.ini_filename == str(machine_folder / "mill.ini")
        assert [tool.id for tool in machine.stat.tool_table[1:3]] == [1, 2]  # test.tbl's
        assert machine.stat.joint[0]["max_position_limit"] == 100  # from the included file
        assert cnc.ini(str(machine_folder / "mill.ini")).find("AXIS_Z", "MIN_LIMIT") == "-50"
    finally:
        machine.stop()
    assert not (shared / "position.txt").exists()  # written beside the link, not the target
    assert (machine_folder / "position.txt").exists()
