"""An exception nothing expected (a bug) inside task fails what it was doing and says so;
task itself goes on: its crash would take the whole machine down (the launcher stops
everything when task exits)."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from cnc.ini import IniFile
from nml import emc
from nml.channels import EMC_ERROR, Nml, load_config
from nml.message import RCS_STATUS
from task.__main__ import BUFFERS, NML_PROCESS
from task.controller import Task
from tests.task.test_machine import MACHINE


@pytest.fixture
def task(tmp_path: Path) -> Iterator[tuple[Task, Nml]]:
    """Task in this process on its NML buffers (no motion or iocontrol: none is needed
    here), and a UI's connection to the error channel."""
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    config = load_config()
    master = Nml(config, "cnc", BUFFERS)
    own = Nml(config, NML_PROCESS, BUFFERS)
    ui = Nml(config, "xemc", [EMC_ERROR])
    try:
        yield Task(IniFile.load(str(folder / "mill.ini")), own), ui
    finally:
        for nml in (ui, own, master):
            nml.close()


def errors(ui: Nml) -> list[str]:
    found = []
    while (msg := ui[EMC_ERROR].read()) is not None:
        found.append(msg.error)
    return found


def test_an_exception_in_a_command_fails_that_command_only(task, monkeypatch) -> None:
    controller, ui = task

    def broken(_cmd: emc.NMLmsg) -> None:
        raise KeyError("spindle")

    with monkeypatch.context() as patched:
        patched.setitem(controller.handlers, emc.EMC_TASK_SET_MODE, broken)
        mdi = emc.EMC_TASK_SET_MODE(serial_number=7, mode=emc.EMC_TASK_MODE_ENUM.MDI)
        controller.handle(mdi)
    assert (controller.stat.echo_serial_number, controller.stat.status) == (7, RCS_STATUS.ERROR)
    assert errors(ui) == ["task: internal error in EMC_TASK_SET_MODE: KeyError: 'spindle'"]
    controller.handle(emc.EMC_TASK_SET_MODE(serial_number=8, mode=emc.EMC_TASK_MODE_ENUM.MDI))
    assert (controller.stat.echo_serial_number, controller.stat.status) == (8, RCS_STATUS.DONE)


def test_an_exception_while_running_stops_the_run_and_says_so(task, monkeypatch) -> None:
    controller, ui = task

    def broken() -> None:
        raise IndexError("list index out of range")

    with monkeypatch.context() as patched:
        patched.setattr(controller, "_plan", broken)
        controller.cycle()
    assert errors(ui) == [
        "task: internal error running the program: IndexError: list index out of range"
    ]
    controller.cycle()  # and the loop goes on
    assert errors(ui) == []
