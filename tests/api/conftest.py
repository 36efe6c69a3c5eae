"""Fixtures of the API tests: the controller's buffers, and a fake task process.

``controller`` creates emcCommand, emcStatus and emcError as their master (what the launcher
does) and removes them afterwards. ``fake_task`` starts ``fake_task.py`` (a real process
answering commands as task does) and collects what it prints.
"""

from __future__ import annotations

import json
import queue
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from nml.channels import DEFAULT_NML_FILE, EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config
from tests.conftest import Processes

FAKE_TASK = str(Path(__file__).with_name("fake_task.py"))
WAIT_S = 20.0  # generous: only reached when something is broken


@pytest.fixture(autouse=True)
def runtime_dir(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """Runtime-info files go to a private folder (never a running machine's)."""
    folder = tmp_path / "run"
    folder.mkdir()
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(folder))
    return folder


@pytest.fixture
def controller() -> Iterator[Nml]:
    nml = Nml(load_config(), "cnc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR])
    yield nml
    nml.close()


class FakeTask:
    """A running fake_task.py and the lines it printed."""

    def __init__(self, procs: Processes, *args: str) -> None:
        self.proc = procs.python(FAKE_TASK, str(DEFAULT_NML_FILE), *args)
        self._lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._collect, daemon=True).start()
        assert self.next_line() == "ready"

    def _collect(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self._lines.put(line.rstrip("\n"))

    def next_line(self) -> str:
        try:
            return self._lines.get(timeout=WAIT_S)
        except queue.Empty:
            stderr = self.proc.stderr.read() if self.proc.poll() is not None else ""
            raise AssertionError(f"fake task printed nothing; stderr: {stderr}") from None

    def next_command(self) -> dict[str, Any]:
        """The next command the fake task received: {"type": name, "fields": {...}}."""
        return json.loads(self.next_line())

    def received(self) -> list[dict[str, Any]]:
        """Every command received so far and not yet taken by next_command."""
        found = []
        while not self._lines.empty():
            found.append(json.loads(self._lines.get()))
        return found


@pytest.fixture
def fake_task(controller: Nml, procs: Processes) -> Iterator[Callable[..., FakeTask]]:
    """Start a fake task (call it with fake_task.py's options); killed at teardown."""

    def start(*args: str) -> FakeTask:
        return FakeTask(procs, *args)

    yield start
