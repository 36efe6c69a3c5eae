"""Shared fixtures: every test gets its own IPC instance and leaves nothing behind.

- Each test runs with a unique ``CNC_INSTANCE``, so its shared-memory segments and
  semaphores are named apart from any running machine and from other tests; whatever the
  test leaves in /dev/shm is removed afterwards, and reported as a failure of the test.
- ``procs`` starts real OS processes and kills any still running at teardown.
- Tests marked ``slow`` run first; before any test, the project's modules are compiled to
  bytecode (``compile_packages``).
- ``collector_off`` runs a test as the realtime host runs: no automatic garbage collection.
- The realtime hosts the tests start do not spin before each period (``CNC_HAL_SPIN_US``
  0): tests assert behaviour, not timing, and each idle machine's host took a tenth of a
  core more spinning (30 % against 20 %), on CI's two cores shared by four test workers.
"""

from __future__ import annotations

import contextlib
import gc
import itertools
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from nml.ipcnames import INSTANCE_ENV, remove_instance_objects

REPO = Path(__file__).resolve().parent.parent
_counter = itertools.count()
os.environ.setdefault("CNC_HAL_SPIN_US", "0")


@pytest.fixture(autouse=True)
def cnc_instance(monkeypatch: pytest.MonkeyPatch, request: pytest.FixtureRequest) -> Iterator[str]:
    instance = f"t{os.getpid()}-{next(_counter)}"
    monkeypatch.setenv(INSTANCE_ENV, instance)
    yield instance
    leftovers = remove_instance_objects(instance)
    if leftovers and not request.node.get_closest_marker("allow_leftovers"):
        pytest.fail(f"test left IPC objects behind (now removed): {leftovers}", pytrace=False)


class Processes:
    """Real OS processes started by a test; all are killed at teardown."""

    def __init__(self) -> None:
        self.started: list[subprocess.Popen[str]] = []

    def start(
        self, *args: str, env: dict[str, str] | None = None, **kwargs
    ) -> subprocess.Popen[str]:
        full_env = dict(os.environ)
        full_env["PYTHONPATH"] = str(REPO) + os.pathsep + full_env.get("PYTHONPATH", "")
        full_env.update(env or {})
        proc = subprocess.Popen(
            list(args),
            env=full_env,
            cwd=kwargs.pop("cwd", REPO),
            stdout=kwargs.pop("stdout", subprocess.PIPE),
            stderr=kwargs.pop("stderr", subprocess.PIPE),
            text=True,
            start_new_session=True,
            **kwargs,
        )
        self.started.append(proc)
        return proc

    def python(self, *args: str, **kwargs) -> subprocess.Popen[str]:
        return self.start(sys.executable, *args, **kwargs)

    def kill_all(self) -> None:
        for proc in self.started:
            if proc.poll() is None:
                for pid in [*_descendants(proc.pid), proc.pid]:  # children in other groups too
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(pid, signal.SIGKILL)
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(proc.pid, signal.SIGKILL)
            with contextlib.suppress(subprocess.TimeoutExpired, ValueError):
                proc.communicate(timeout=5)


def _descendants(pid: int) -> list[int]:
    """Every process below ``pid``, deepest first (from /proc's children lists)."""
    found: list[int] = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        with contextlib.suppress(OSError):
            for child in map(int, (task / "children").read_text().split()):
                found = [*_descendants(child), child, *found]
    return found


@pytest.fixture
def procs() -> Iterator[Processes]:
    group = Processes()
    yield group
    group.kill_all()


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "allow_leftovers: the test checks cleanup itself")
    if not hasattr(config, "workerinput"):  # once, in the process that starts the workers
        compile_packages()


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Tests marked slow first (in their order): the workers end on short tests together
    instead of one waiting for the other's minute-long browser test."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


PACKAGES = ("cnc", "hal", "iocontrol", "motion", "nml", "scripts", "task", "tests")


def compile_packages() -> None:
    """Write the project's bytecode (.pyc) before the tests start machines.

    An editable install is never compiled, and where PYTHONDONTWRITEBYTECODE is set (as on
    CI's machines) no process writes it either: each of the thousands of processes the
    tests start would compile every module it imports from source again, about a third
    of its start-up. (Python reads .pyc files whatever that variable says.)"""
    import compileall

    for package in PACKAGES:
        compileall.compile_dir(REPO / package, quiet=1, workers=0)


@pytest.fixture
def collector_off() -> Iterator[None]:
    """The realtime host's setting (hal/README.md): the garbage collector does not run, so
    a reference cycle made now stays until collected; ``gc.collect()`` then counts them."""
    gc.collect()
    gc.disable()
    try:
        yield
    finally:
        gc.enable()
