"""halui's pins in a real HAL: exactly LinuxCNC 2.9's names, with its types and directions."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from cnc.halui.config import HaluiConfig
from cnc.halui.pins import COMPONENT, create_pins
from hal.core import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_OUT, HAL_S32, HAL_U32, Hal

# The names LinuxCNC 2.9's halui exports (from its binary, which differs from its man page
# for tool.length_offset), for 2 joints, axes X and Z, 1 spindle, home-all, 1 MDI command.
LINUXCNC_NAMES = """
abort home-all mdi-command-00
machine.units-per-mm machine.is-on machine.on machine.off
estop.is-activated estop.activate estop.reset
mode.is-manual mode.is-auto mode.is-mdi mode.is-teleop mode.is-joint
mode.manual mode.auto mode.mdi mode.teleop mode.joint
mist.is-on mist.on mist.off flood.is-on flood.on flood.off lube.is-on lube.on lube.off
program.is-idle program.is-running program.is-paused program.run program.pause
program.resume program.step program.stop program.optional-stop.is-on
program.optional-stop.on program.optional-stop.off program.block-delete.is-on
program.block-delete.on program.block-delete.off
tool.number tool.diameter tool.length_offset.x tool.length_offset.y tool.length_offset.z
tool.length_offset.a tool.length_offset.b tool.length_offset.c tool.length_offset.u
tool.length_offset.v tool.length_offset.w
max-velocity.value max-velocity.counts max-velocity.count-enable max-velocity.direct-value
max-velocity.scale max-velocity.increase max-velocity.decrease
feed-override.value feed-override.counts feed-override.count-enable
feed-override.direct-value feed-override.scale feed-override.increase
feed-override.decrease feed-override.reset
rapid-override.value rapid-override.counts rapid-override.count-enable
rapid-override.direct-value rapid-override.scale rapid-override.increase
rapid-override.decrease rapid-override.reset
spindle.0.is-on spindle.0.runs-forward spindle.0.runs-backward spindle.0.brake-is-on
spindle.0.start spindle.0.stop spindle.0.forward spindle.0.reverse spindle.0.increase
spindle.0.decrease spindle.0.brake-on spindle.0.brake-off spindle.0.override.value
spindle.0.override.counts spindle.0.override.count-enable spindle.0.override.direct-value
spindle.0.override.scale spindle.0.override.increase spindle.0.override.decrease
spindle.0.override.reset
joint.selected joint.jog-speed joint.jog-deadband
joint.selected.is-homed joint.selected.on-soft-min-limit joint.selected.on-soft-max-limit
joint.selected.on-hard-min-limit joint.selected.on-hard-max-limit
joint.selected.override-limits joint.selected.has-fault joint.selected.home
joint.selected.unhome joint.selected.plus joint.selected.minus joint.selected.increment
joint.selected.increment-plus joint.selected.increment-minus
axis.selected axis.jog-speed axis.jog-deadband axis.selected.plus axis.selected.minus
axis.selected.increment axis.selected.increment-plus axis.selected.increment-minus
"""
JOINT_NAMES = """is-homed is-selected on-soft-min-limit on-soft-max-limit on-hard-min-limit
on-hard-max-limit override-limits has-fault home unhome select plus minus analog increment
increment-plus increment-minus"""
AXIS_NAMES = """select is-selected pos-commanded pos-feedback pos-relative plus minus analog
increment increment-plus increment-minus"""


@pytest.fixture
def hal() -> Iterator[Hal]:
    h = Hal()
    h.new_component(COMPONENT)
    yield h
    h.destroy()
    h.close()


def make_pins(hal: Hal) -> dict[str, dict]:
    config = HaluiConfig(
        ini_path="t.ini", num_joints=2, axes="xz", has_home_all=True, mdi_commands=("G0 X0",)
    )
    create_pins(hal, config)
    return {name: pin for name, pin in hal.meta["pins"].items() if pin["owner"] == COMPONENT}


def test_the_pin_names_are_linuxcncs(hal: Hal) -> None:
    expected = {f"halui.{name}" for name in LINUXCNC_NAMES.split()}
    for joint in (0, 1):
        expected |= {f"halui.joint.{joint}.{name}" for name in JOINT_NAMES.split()}
    for letter in "xz":
        expected |= {f"halui.axis.{letter}.{name}" for name in AXIS_NAMES.split()}
    assert set(make_pins(hal)) == expected


@pytest.mark.parametrize(
    ("name", "hal_type", "direction", "value"),
    [
        ("halui.machine.on", HAL_BIT, HAL_IN, 0),
        ("halui.machine.is-on", HAL_BIT, HAL_OUT, 0),
        ("halui.tool.number", HAL_U32, HAL_OUT, 0),
        ("halui.joint.selected", HAL_U32, HAL_OUT, 0),
        ("halui.feed-override.counts", HAL_S32, HAL_IN, 0),
        ("halui.feed-override.count-enable", HAL_BIT, HAL_IN, 1),
        ("halui.feed-override.scale", HAL_FLOAT, HAL_IN, 0.1),
        ("halui.spindle.0.override.scale", HAL_FLOAT, HAL_IN, 0.1),
        ("halui.max-velocity.scale", HAL_FLOAT, HAL_IN, 0.0),
        ("halui.max-velocity.count-enable", HAL_BIT, HAL_IN, 1),
        ("halui.joint.jog-deadband", HAL_FLOAT, HAL_IN, 0.2),
        ("halui.axis.jog-speed", HAL_FLOAT, HAL_IN, 0.0),
        ("halui.axis.z.pos-relative", HAL_FLOAT, HAL_OUT, 0.0),
        ("halui.joint.1.analog", HAL_FLOAT, HAL_IN, 0.0),
    ],
)
def test_types_directions_and_start_values(
    hal: Hal, name: str, hal_type: int, direction: int, value: float
) -> None:
    pin = make_pins(hal)[name]
    assert (pin["type"], pin["dir"]) == (hal_type, direction)
    assert hal.pin_value(pin) == pytest.approx(value)
