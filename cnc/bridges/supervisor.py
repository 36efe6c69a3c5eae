"""The launcher's bridges: started from the INI after task, restarted when they die.

A bridge carries no safety input or output, so it is not one of the launcher's supervised
children (no heartbeat, no E-stop when it ends): a bridge that exits is reported and
started again after ``RESTART_DELAYS_S`` (longer each time it dies soon after a start),
and the machine goes on as it was.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from cnc.bridges import BRIDGES, command_line
from cnc.inischema import MachineConfig

RESTART_DELAYS_S = (1.0, 2.0, 5.0, 10.0, 30.0, 60.0)
STABLE_S = 60.0  # a bridge that ran this long starts again from the first delay
STOP_TIMEOUT_S = 3.0


@dataclass
class Bridge:
    section: str
    proc: subprocess.Popen[bytes] | None = None
    started_at: float = 0.0
    deaths: int = 0  # in a row, each soon after its start
    restart_at: float | None = None

    @property
    def name(self) -> str:
        return BRIDGES[self.section][0]


class BridgeSupervisor:
    def __init__(
        self,
        config: MachineConfig,
        ini_path: str,
        folder: Path,
        say: Callable[[str], None],
        child_setup: Callable[[], None] | None = None,
    ) -> None:
        self.ini_path = ini_path
        self.folder = folder
        self.say = say
        self.child_setup = child_setup
        self.bridges = [Bridge(s) for s in BRIDGES if config.value(s, "ENABLE")]

    def start(self) -> None:
        for bridge in self.bridges:
            self._start(bridge)

    def _start(self, bridge: Bridge) -> None:
        self.say(f"starting the {bridge.name} bridge")
        bridge.restart_at = None
        bridge.started_at = time.monotonic()
        try:
            bridge.proc = subprocess.Popen(
                command_line(bridge.section, self.ini_path),
                cwd=self.folder,
                process_group=0,  # Ctrl-C reaches the launcher, which stops it in order
                preexec_fn=self.child_setup,
            )
        except OSError as exc:
            self.say(f"cannot start the {bridge.name} bridge: {exc}")
            self._schedule(bridge)

    def check(self) -> None:
        """Report bridges that ended; start those whose delay is over (the launcher's loop)."""
        now = time.monotonic()
        for bridge in self.bridges:
            if bridge.restart_at is not None:
                if now >= bridge.restart_at:
                    self._start(bridge)
            elif bridge.proc is not None and bridge.proc.poll() is not None:
                self.say(
                    f"the {bridge.name} bridge (pid {bridge.proc.pid}) ended with status "
                    f"{bridge.proc.returncode}; the machine goes on"
                )
                if now - bridge.started_at >= STABLE_S:
                    bridge.deaths = 0
                self._schedule(bridge)

    def _schedule(self, bridge: Bridge) -> None:
        delay = RESTART_DELAYS_S[min(bridge.deaths, len(RESTART_DELAYS_S) - 1)]
        bridge.deaths += 1
        bridge.restart_at = time.monotonic() + delay
        self.say(f"starting the {bridge.name} bridge again in {delay:g} s")

    def pids(self) -> dict[str, int]:
        """The running bridges: name -> pid."""
        return {
            b.name: b.proc.pid for b in self.bridges if b.proc is not None and b.proc.poll() is None
        }

    def stop(self) -> None:
        """SIGTERM to every bridge at once; any still running after STOP_TIMEOUT_S is killed
        (a bridge holds nothing the machine needs: its shut-down never waits long)."""
        running = [b.proc for b in self.bridges if b.proc is not None and b.proc.poll() is None]
        for bridge in self.bridges:
            bridge.restart_at = None
        for proc in running:
            proc.terminate()
        deadline = time.monotonic() + STOP_TIMEOUT_S
        for proc in running:
            try:
                proc.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
