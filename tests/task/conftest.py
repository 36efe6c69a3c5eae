"""Fixtures for task's end-to-end tests."""

from __future__ import annotations

import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.task.test_machine import MACHINE, Machine, launched


@pytest.fixture
def machine(procs, tmp_path: Path) -> Iterator[Machine]:
    """The test mill (tests/task/machine, copied to a scratch folder), started headless."""
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    with launched(procs, folder) as machine:
        yield machine


@pytest.fixture
def start_machine(procs, tmp_path: Path) -> Iterator[Callable[..., Machine]]:
    """Start the test mill (tests/task/machine, copied to a scratch folder) with extra INI
    lines per section, e.g. ``start_machine(EMCIO=["TOOL_CHANGE_QUILL_UP = 1"])``, and extra
    files in its folder (``files={"nc/M101": "#!/bin/sh ..."}``); the
    machine comes back reset, on, homed and in MDI mode. Stopped at the end of the test."""
    started: list[Machine] = []

    def start(files: dict[str, str] | None = None, **sections: list[str]) -> Machine:
        folder = tmp_path / "machine"
        shutil.copytree(MACHINE, folder)
        for name, content in (files or {}).items():  # scripts ("#!...") are made executable
            path = folder / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(content)
            if content.startswith("#!"):
                path.chmod(0o755)
        ini = folder / "mill.ini"
        text = ini.read_text()
        for section, lines in sections.items():
            extra = "".join(f"{line}\n" for line in lines)
            header = f"[{section}]\n"
            text = text.replace(header, header + extra) if header in text else text + header + extra
        ini.write_text(text)
        proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
        machine = Machine(proc, folder)
        started.append(machine)
        machine.wait_ready()
        machine.ready_to_move()
        return machine

    yield start
    for machine in started:
        machine.stop()
