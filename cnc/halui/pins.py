"""halui's HAL pins, with LinuxCNC 2.9's names, types and directions (``man 1 halui``).

Each group of pins is a declarative class (``hal.api``: attribute access reads and writes
shared memory); ``create_pins`` makes one instance per group under its prefix:
``halui``, ``halui.feed-override``, ``halui.joint.N``, ``halui.axis.L``, ``halui.spindle.N``.
Button pins (``bit in``) act on their rising edge; ``is-*`` and value pins are outputs that
mirror the controller's status.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from cnc.halui.config import HaluiConfig
from hal.api import RtComponent, pin
from hal.core import Hal

COMPONENT = "halui"


class MainPins(RtComponent):
    """``halui.*``: machine, e-stop, modes, coolant, program, tool and the selected joint/axis."""

    units_per_mm = pin("float out", "machine.units-per-mm")
    is_machine_on = pin("bit out", "machine.is-on")
    machine_on = pin("bit in", "machine.on")
    machine_off = pin("bit in", "machine.off")

    is_estop_activated = pin("bit out", "estop.is-activated")
    estop_activate = pin("bit in", "estop.activate")
    estop_reset = pin("bit in", "estop.reset")

    is_mode_manual = pin("bit out", "mode.is-manual")
    is_mode_auto = pin("bit out", "mode.is-auto")
    is_mode_mdi = pin("bit out", "mode.is-mdi")
    is_mode_teleop = pin("bit out", "mode.is-teleop")
    is_mode_joint = pin("bit out", "mode.is-joint")
    mode_manual = pin("bit in", "mode.manual")
    mode_auto = pin("bit in", "mode.auto")
    mode_mdi = pin("bit in", "mode.mdi")
    mode_teleop = pin("bit in", "mode.teleop")
    mode_joint = pin("bit in", "mode.joint")

    is_mist_on = pin("bit out", "mist.is-on")
    mist_on = pin("bit in", "mist.on")
    mist_off = pin("bit in", "mist.off")
    is_flood_on = pin("bit out", "flood.is-on")
    flood_on = pin("bit in", "flood.on")
    flood_off = pin("bit in", "flood.off")
    is_lube_on = pin("bit out", "lube.is-on")
    lube_on = pin("bit in", "lube.on")
    lube_off = pin("bit in", "lube.off")

    is_program_idle = pin("bit out", "program.is-idle")
    is_program_running = pin("bit out", "program.is-running")
    is_program_paused = pin("bit out", "program.is-paused")
    program_run = pin("bit in", "program.run")
    program_pause = pin("bit in", "program.pause")
    program_resume = pin("bit in", "program.resume")
    program_step = pin("bit in", "program.step")
    program_stop = pin("bit in", "program.stop")
    is_optional_stop_on = pin("bit out", "program.optional-stop.is-on")
    optional_stop_on = pin("bit in", "program.optional-stop.on")
    optional_stop_off = pin("bit in", "program.optional-stop.off")
    is_block_delete_on = pin("bit out", "program.block-delete.is-on")
    block_delete_on = pin("bit in", "program.block-delete.on")
    block_delete_off = pin("bit in", "program.block-delete.off")

    abort = pin("bit in")
    mdi_command = pin("bit in", "mdi-command-{:02d}", count="mdi_count")

    tool_number = pin("u32 out", "tool.number")
    tool_diameter = pin("float out", "tool.diameter")

    joint_selected = pin("u32 out", "joint.selected")
    joint_jog_speed = pin("float in", "joint.jog-speed")
    joint_jog_deadband = pin("float in", "joint.jog-deadband", default=0.2)
    axis_selected = pin("u32 out", "axis.selected")
    axis_jog_speed = pin("float in", "axis.jog-speed")
    axis_jog_deadband = pin("float in", "axis.jog-deadband", default=0.2)


class ToolOffsetPins(RtComponent):
    """``halui.tool.length_offset.L``: the tool offset in use, per axis (LinuxCNC 2.9's
    halui exports these names; its man page spells them length-offset)."""

    x = pin("float out")
    y = pin("float out")
    z = pin("float out")
    a = pin("float out")
    b = pin("float out")
    c = pin("float out")
    u = pin("float out")
    v = pin("float out")
    w = pin("float out")


class JogPins(RtComponent):
    """Jogging one joint or axis; ``halui.joint.selected.*`` and ``halui.axis.selected.*``
    are the same pins acting on the selected one."""

    plus = pin("bit in")
    minus = pin("bit in")
    increment = pin("float in")
    increment_plus = pin("bit in")
    increment_minus = pin("bit in")


class AxisPins(JogPins):
    """``halui.axis.L.*``."""

    select = pin("bit in")
    is_selected = pin("bit out")
    analog = pin("float in")
    pos_commanded = pin("float out")
    pos_feedback = pin("float out")
    pos_relative = pin("float out")


class JointStatusPins(RtComponent):
    """A joint's status: ``halui.joint.N.*`` and, for the selected joint,
    ``halui.joint.selected.*``."""

    is_homed = pin("bit out")
    on_soft_min_limit = pin("bit out")
    on_soft_max_limit = pin("bit out")
    on_hard_min_limit = pin("bit out")
    on_hard_max_limit = pin("bit out")
    override_limits = pin("bit out")
    has_fault = pin("bit out")


class SelectedJointPins(JogPins, JointStatusPins):
    """``halui.joint.selected.*``."""

    home = pin("bit in")
    unhome = pin("bit in")


class JointPins(SelectedJointPins):
    """``halui.joint.N.*``."""

    select = pin("bit in")
    is_selected = pin("bit out")
    analog = pin("float in")


class AdjustPins(RtComponent):
    """A value set by an encoder (counts x scale) or buttons: ``halui.max-velocity.*``."""

    value = pin("float out")
    counts = pin("s32 in")
    count_enable = pin("bit in", default=1)
    direct_value = pin("bit in")
    scale = pin("float in")
    increase = pin("bit in")
    decrease = pin("bit in")


class OverridePins(AdjustPins):
    """An override, with a reset to 100 %: ``halui.feed-override.*``,
    ``halui.rapid-override.*``, ``halui.spindle.N.override.*``."""

    scale = pin("float in", default=0.1)
    reset = pin("bit in")


class SpindlePins(RtComponent):
    """``halui.spindle.N.*`` (its override pins are an OverridePins)."""

    start = pin("bit in")
    stop = pin("bit in")
    forward = pin("bit in")
    reverse = pin("bit in")
    increase = pin("bit in")
    decrease = pin("bit in")
    brake_on = pin("bit in")
    brake_off = pin("bit in")
    is_on = pin("bit out")
    runs_forward = pin("bit out")
    runs_backward = pin("bit out")
    brake_is_on = pin("bit out")


class HomeAllPin(RtComponent):
    """``halui.home-all``: only when [JOINT_0]HOME_SEQUENCE is set, as in LinuxCNC."""

    home_all = pin("bit in")


@dataclass
class Pins:
    """Every pin group of one halui."""

    main: MainPins
    tool_offset: ToolOffsetPins
    max_velocity: AdjustPins
    feed_override: OverridePins
    rapid_override: OverridePins
    selected_joint: SelectedJointPins
    selected_axis: JogPins
    joints: list[JointPins]
    axes: dict[str, AxisPins]  # letter -> pins, in XYZABCUVW order
    spindles: list[SpindlePins]
    spindle_overrides: list[OverridePins]
    home_all: HomeAllPin | None


# makes one pin group: (class, prefix, options) -> its instance
GroupMaker = Callable[[type[RtComponent], str, dict[str, Any]], Any]


def create_pins(hal: Hal, config: HaluiConfig, comp: str = COMPONENT) -> Pins:
    """Make every pin of component ``comp`` (which must exist) in one HAL update."""
    with hal.edit():
        return build_pins(
            config, lambda cls, prefix, options: cls.create(hal, comp, prefix, options)
        )


def build_pins(config: HaluiConfig, make: GroupMaker) -> Pins:
    """Every pin group of a halui for ``config``; ``make`` makes each (tests make fakes)."""
    return Pins(
        main=make(MainPins, "halui", {"mdi_count": len(config.mdi_commands)}),
        tool_offset=make(ToolOffsetPins, "halui.tool.length_offset", {}),
        max_velocity=make(AdjustPins, "halui.max-velocity", {}),
        feed_override=make(OverridePins, "halui.feed-override", {}),
        rapid_override=make(OverridePins, "halui.rapid-override", {}),
        selected_joint=make(SelectedJointPins, "halui.joint.selected", {}),
        selected_axis=make(JogPins, "halui.axis.selected", {}),
        joints=[make(JointPins, f"halui.joint.{n}", {}) for n in range(config.num_joints)],
        axes={letter: make(AxisPins, f"halui.axis.{letter}", {}) for letter in config.axes},
        spindles=[make(SpindlePins, f"halui.spindle.{n}", {}) for n in range(config.num_spindles)],
        spindle_overrides=[
            make(OverridePins, f"halui.spindle.{n}.override", {})
            for n in range(config.num_spindles)
        ],
        home_all=make(HomeAllPin, "halui", {}) if config.has_home_all else None,
    )
