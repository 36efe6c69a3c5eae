"""Fixtures of the UI tests: the controller's buffers, a fake task, and running a UI.

``controller`` creates emcCommand, emcStatus and emcError as their master (what the
launcher does) and removes them afterwards; ``fake_task`` starts ``fake_task.py`` (a real
process answering commands and publishing a machine's status); ``run_ui`` runs ``cnc top``
or ``cnc sh`` in a real process and returns its exit status and output.
"""

from __future__ import annotations

import json
import os
import queue
import select
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from nml.channels import DEFAULT_NML_FILE, EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config
from tests.conftest import Processes

FAKE_TASK = str(Path(__file__).with_name("fake_task.py"))
WAIT_S = 20.0  # generous: only reached when something is broken
# How the lead's `cnc top` / `cnc sh` subcommands call the UIs.
UI_MAIN = "import sys; from cnc.ui.{name} import main; sys.exit(main(sys.argv[1:]))"


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
    """A running fake_task.py and the commands it received."""

    def __init__(self, procs: Processes, *args: str) -> None:
        self.proc = procs.python(FAKE_TASK, str(DEFAULT_NML_FILE), *args)
        self._lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._collect, daemon=True).start()
        assert self._next_line() == "ready"

    def _collect(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self._lines.put(line.rstrip("\n"))

    def _next_line(self) -> str:
        try:
            return self._lines.get(timeout=WAIT_S)
        except queue.Empty:
            raise AssertionError("fake task printed nothing") from None

    def next_command(self) -> dict[str, Any]:
        """The next command received: {"type": name, "fields": {...}}."""
        return json.loads(self._next_line())

    def received(self) -> list[dict[str, Any]]:
        """Every command received so far and not yet taken by next_command."""
        found = []
        while not self._lines.empty():
            found.append(json.loads(self._lines.get()))
        return found


@pytest.fixture
def fake_task(controller: Nml, procs: Processes) -> Callable[..., FakeTask]:
    """Start a fake task (call it with fake_task.py's options); killed at teardown."""

    def start(*args: str) -> FakeTask:
        return FakeTask(procs, *args)

    return start


@dataclass
class Result:
    returncode: int
    stdout: str
    stderr: str

    @property
    def lines(self) -> list[str]:
        return self.stdout.splitlines()


@pytest.fixture
def run_ui(procs: Processes) -> Callable[..., Result]:
    """Run ``cnc top`` or ``cnc sh`` (name "top" or "sh") with arguments, to its end."""

    def run(name: str, *args: str, stdin: str = "") -> Result:
        proc = procs.python("-c", UI_MAIN.format(name=name), *args, stdin=subprocess.PIPE)
        stdout, stderr = proc.communicate(stdin, timeout=WAIT_S)
        assert "Traceback" not in stderr, stderr
        return Result(proc.returncode, stdout, stderr)

    return run


def read_until(master: int, wanted: bytes) -> bytes:
    """What a program wrote to a pseudo-terminal, up to and including ``wanted``."""
    seen = b""
    deadline = time.monotonic() + WAIT_S
    while wanted not in seen:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([master], [], [], left)[0]:
            raise AssertionError(f"never saw {wanted!r}; saw {seen!r}")
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the program closed the terminal
            chunk = b""
        if not chunk:
            raise AssertionError(f"the program ended before {wanted!r}; saw {seen!r}")
        seen += chunk
    return seen
