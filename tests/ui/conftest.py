"""Fixtures of the UI tests: the controller's buffers, a fake task, and running a UI.

``controller`` creates emcCommand, emcStatus and emcError as their master (what the
launcher does) and removes them afterwards; ``fake_task`` starts ``fake_task.py`` (a real
process answering commands and publishing a machine's status); ``run_ui`` runs ``cnc top``
or ``cnc sh`` in a real process and returns its exit status and output.
"""

from __future__ import annotations

import os
import select
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass

import pytest

from tests.api.conftest import FakeTask, controller, runtime_dir  # noqa: F401 (fixtures)
from tests.conftest import Processes

WAIT_S = 20.0  # generous: only reached when something is broken
# How the lead's `cnc top` / `cnc sh` subcommands call the UIs.
# Ctrl-C at its default, as a terminal starts a program: a test run started in the
# background by a script (``pytest &``) ignores SIGINT, and its children would inherit that.
UI_MAIN = (
    "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "from cnc.ui.{name} import main; sys.exit(main(sys.argv[1:]))"
)


@pytest.fixture
def fake_task(request: pytest.FixtureRequest, procs: Processes) -> Callable[..., FakeTask]:
    """Start the fake task with a whole machine's status (tests/api/fake_task.py
    --machine; call it with its other options); killed at teardown."""
    request.getfixturevalue("controller")  # the buffers exist before the task attaches

    def start(*args: str) -> FakeTask:
        return FakeTask(procs, "--machine", *args)

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
