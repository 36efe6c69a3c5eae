"""The halui process: the HAL component ``halui``, attached to the controller as a UI.

Start-up as LinuxCNC's halui: read the INI file, make every pin, tell HAL it is ready
(``loadusr -W`` returns), then attach to the NML buffers. The controller may not run yet
(the launcher starts halui before the HAL files and task): until task publishes its status
halui only waits. Every cycle ([HALUI]CYCLE_TIME, 20 ms) ``Halui.step()`` runs; SIGTERM
(``unloadusr``) or SIGINT ends the loop and removes the component.
"""

from __future__ import annotations

import contextlib
import os
import signal
import time
from typing import Any

from cnc.api.commands import command
from cnc.api.errors import error
from cnc.api.safety import use_heartbeat
from cnc.api.status import stat
from cnc.halui.config import HaluiConfig
from cnc.halui.core import Halui, warn
from cnc.halui.pins import COMPONENT, create_pins
from hal.core import Hal, HalError
from nml import emc
from nml.safety import SafetyLink


class HaluiCommand(command):
    """``cnc.command`` with lube on/off, which halui sends but LinuxCNC's Python API lacks."""

    __slots__ = ()

    def lube(self, is_on: bool) -> None:
        self._send(emc.EMC_LUBE_ON() if is_on else emc.EMC_LUBE_OFF())


class _Stopper:
    """SIGTERM / SIGINT handler: the main loop ends at its next cycle."""

    def __init__(self) -> None:
        self.is_stopping = False
        for sig in (signal.SIGTERM, signal.SIGINT):
            signal.signal(sig, self.stop)

    def stop(self, *_: Any) -> None:
        self.is_stopping = True


def run(config: HaluiConfig) -> int:
    """Serve until SIGTERM / SIGINT; the exit status (1 if halui cannot start)."""
    try:
        hal = Hal(is_creating=False)  # the HAL of the machine: never one of our own
    except HalError as exc:
        warn(f"{exc}: start the machine (or halrun) first")
        return 1
    stopper = _Stopper()
    try:
        hal.new_component(COMPONENT, "user", os.getpid())
    except HalError as exc:
        warn(str(exc))
        hal.close()
        return 1
    status = command_channel = safety = None
    try:
        pins = create_pins(hal, config)
        status = stat(config.ini_path)
        command_channel = HaluiCommand(config.ini_path)
        halui = Halui(config, pins, status, command_channel)
        # halui's pins carry E-stop and jogs: supervised; its jogs are leased to its loop
        safety = SafetyLink.open("halui", config.heartbeat_timeout, is_reporter=False)
        use_heartbeat(safety.heartbeat if safety is not None else None)
        hal.ready(COMPONENT)
        _serve(halui, config.cycle_time, stopper, safety)
    except (HalError, error) as exc:
        warn(str(exc))
        return 1
    finally:
        if safety is not None:
            safety.close()
        for channel in (status, command_channel):
            if channel is not None:
                channel.close()
        with contextlib.suppress(HalError):
            hal.remove_component(COMPONENT)
        hal.close()
    return 0


def _serve(halui: Halui, cycle_time: float, stopper: _Stopper, safety: SafetyLink | None) -> None:
    is_up = False  # whether the last cycle reached the controller (a loss is told once)
    while not stopper.is_stopping:
        if safety is not None:  # heartbeat; lost processes get their E-stop from here too
            safety.tick()
        try:
            halui.step()
            is_up = True
        except error as exc:
            if is_up:
                warn(f"lost the controller ({exc}); waiting for it")
            is_up = False
        time.sleep(cycle_time)
