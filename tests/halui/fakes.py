"""Stand-ins for halui's pins, ``cnc.stat`` and ``cnc.command``, to drive ``Halui`` cycle by
cycle without a controller or a HAL."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from cnc.api import constants as c
from cnc.halui.config import HaluiConfig
from cnc.halui.core import Halui
from cnc.halui.pins import Pins, build_pins
from hal.api import RtComponent

NUM_JOINT_SLOTS = 16  # EMC_STAT has every joint and spindle slot, used or not
NUM_SPINDLE_SLOTS = 8


def fake_group(cls: type[RtComponent], prefix: str, options: dict[str, Any]) -> SimpleNamespace:
    """A pin group as plain attributes with the declared defaults; ``name`` is its prefix."""
    group = SimpleNamespace(name=prefix)
    for decl in cls.declarations():
        count = options[decl.count] if isinstance(decl.count, str) else decl.count
        value = decl.default if count is None else [decl.default] * count
        setattr(group, decl.attr, value)
    return group


def joint_status(**changes: Any) -> dict[str, Any]:
    status = {
        "homed": 0,
        "min_soft_limit": 0,
        "max_soft_limit": 0,
        "min_hard_limit": 0,
        "max_hard_limit": 0,
        "override_limits": 0,
        "fault": 0,
    }
    status.update(changes)
    return status


class FakeStat:
    """The ``cnc.stat`` attributes halui reads, as after start-up: e-stop, manual mode."""

    def __init__(self) -> None:
        self.polls = 0
        self.task_state = c.STATE_ESTOP
        self.task_mode = c.MODE_MANUAL
        self.motion_mode = c.TRAJ_MODE_FREE
        self.interp_state = c.INTERP_IDLE
        self.state = c.RCS_DONE
        self.echo_serial_number = 0
        self.file = ""
        self.optional_stop = False
        self.block_delete = False
        self.mist = self.flood = self.lube = False
        self.max_velocity = 50.0
        self.feedrate = 1.0
        self.rapidrate = 1.0
        self.linear_units = 1.0
        self.settings = (0.0, 0.0, 0.0)
        self.tool_in_spindle = 0
        self.tool_table: tuple[Any, ...] = ()
        self.tool_offset = (0.0,) * 9
        self.position = self.actual_position = (0.0,) * 9
        self.g5x_offset = self.g92_offset = (0.0,) * 9
        self.rotation_xy = 0.0
        self.spindle = [
            {"enabled": 0, "direction": 0, "brake": 1, "override": 1.0}
            for _ in range(NUM_SPINDLE_SLOTS)
        ]
        self.joint = [joint_status() for _ in range(NUM_JOINT_SLOTS)]

    def poll(self) -> None:
        self.polls += 1


class FakeCommand:
    """Records every command as ``(method, *args)``; plays task for ``mode`` (the mode
    changes unless ``is_mode_refused``) and for ``mdi`` (the line is taken and runs)."""

    def __init__(self, stat: FakeStat) -> None:
        self.stat = stat
        self.calls: list[tuple[Any, ...]] = []
        self.serial = 0
        self.is_mode_refused = False

    def wait_complete(self, timeout: float = 5.0) -> int:
        return c.RCS_DONE

    def __getattr__(self, name: str) -> Any:
        def send(*args: Any) -> None:
            self.serial += 1
            self.calls.append((name, *args))
            if name == "mode" and not self.is_mode_refused:
                self.stat.task_mode = args[0]
            if name == "mdi":
                self.stat.echo_serial_number = self.serial
                self.stat.state = c.RCS_EXEC

        return send

    def take(self) -> list[tuple[Any, ...]]:
        """The commands sent since the last take."""
        calls, self.calls = self.calls, []
        return calls


class Rig:
    """A Halui on fakes: set pins, ``cycle()``, look at the commands and output pins."""

    def __init__(self, config: HaluiConfig | None = None) -> None:
        self.config = config or HaluiConfig(ini_path="test.ini", axes="xyz", has_home_all=True)
        self.pins: Pins = build_pins(self.config, fake_group)
        self.stat = FakeStat()
        self.command = FakeCommand(self.stat)
        self.halui = Halui(self.config, self.pins, self.stat, self.command)

    def cycle(self) -> list[tuple[Any, ...]]:
        """One halui cycle; the commands it sent."""
        self.halui.step()
        return self.command.take()

    def press(self, group: Any, attr: str) -> list[tuple[Any, ...]]:
        """Raise a button for one cycle, then release it for one; the commands sent."""
        setattr(group, attr, True)
        sent = self.cycle()
        setattr(group, attr, False)
        return sent + self.cycle()
