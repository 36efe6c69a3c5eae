"""halui's logic, one cycle at a time: HAL inputs -> commands to task, status -> HAL outputs.

``Halui.step()`` does what LinuxCNC's halui does each 20 ms: take the latest status, send a
command for every button pin that rose since the last cycle (and for every counts, jog or
analog input that changed), then copy the status to the output pins. It works on any
objects with the attributes of ``cnc.stat`` and the methods of ``cnc.command`` (plus
``lube(is_on)``), and on any pin objects with the attributes of ``cnc.halui.pins``, so the
tests drive it with fakes.

Task's rules are kept as LinuxCNC's halui keeps them: an MDI button switches task to MDI
mode if needed, sends the line and, once the last line halui sent has finished, puts task
back into the mode it was in (manual, or auto); ``program.run`` switches to auto first;
jogs are sent only with the machine on, joint jogs in joint (free) mode and axis jogs in
teleop mode. Everything else is sent as is, and task refuses what it must refuse.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from typing import Any

from cnc.api import constants as c
from cnc.api.commands import serial_difference
from cnc.api.errors import error
from cnc.halui.config import AXIS_LETTERS, HaluiConfig
from cnc.halui.pins import AdjustPins, JogPins, Pins
from nml.commands import Handlers, Refused, handler, internal_error

# The ``halui.*`` buttons that send one command each, in LinuxCNC's order
MAIN_BUTTONS = (
    "machine_on", "machine_off", "estop_activate", "estop_reset", "mode_manual", "mode_auto",
    "mode_mdi", "mode_teleop", "mode_joint", "mist_on", "mist_off", "flood_on", "flood_off",
    "lube_on", "lube_off", "program_run", "program_pause", "optional_stop_on",
    "optional_stop_off", "block_delete_on", "block_delete_off", "program_resume",
    "program_step", "program_stop", "abort",
)  # fmt: skip
_MACHINE_STATES = {"machine_on": c.STATE_ON, "machine_off": c.STATE_OFF,
                   "estop_activate": c.STATE_ESTOP, "estop_reset": c.STATE_ESTOP_RESET}  # fmt: skip
_MODES = {"mode_manual": c.MODE_MANUAL, "mode_auto": c.MODE_AUTO, "mode_mdi": c.MODE_MDI}
_PROGRAM_ACTIONS = {"program_pause": c.AUTO_PAUSE, "program_resume": c.AUTO_RESUME,
                    "program_step": c.AUTO_STEP}  # fmt: skip
JOINT_JOG, AXIS_JOG = 1, 0  # jog()'s jjogmode
SPEED_EPSILON = 1e-5  # a jog-speed change smaller than this does not restart running jogs


def warn(text: str) -> None:
    print(f"halui: {text}", file=sys.stderr, flush=True)


class Halui:
    def __init__(self, config: HaluiConfig, pins: Pins, stat: Any, command: Any) -> None:
        self.config = config
        self.pins = pins
        self.stat = stat
        self.command = command
        self._last: dict[str, Any] = {}  # every input's value at the last cycle, by pin name
        self._jog_speeds = {"joint": 0.0, "axis": 0.0}  # speeds the running jogs were sent with
        self._mdi_serial: int | None = None  # the last MDI line halui sent, until it ends
        self._mode_before_mdi = c.MODE_MANUAL
        self._has_units = False
        # at start the first joint and the first axis are selected, as in LinuxCNC
        if pins.joints:
            pins.joints[0].is_selected = True
        first_axis = config.axes[0]
        pins.axes[first_axis].is_selected = True
        pins.main.axis_selected = AXIS_LETTERS.index(first_axis)
        self.handlers = Handlers(self)  # the main buttons' (@handler below)

    def step(self) -> None:
        """One cycle; ``cnc.error`` (nothing done) while the controller is not running."""
        self.stat.poll()
        self._act()
        self._mirror()
        self._end_mdi()

    # ================================================================ edges
    def _swap(self, key: str, value: Any) -> Any:
        """Remember ``value`` as input ``key``'s; return the one of the last cycle (0 at first,
        as LinuxCNC's halui starts, so an input already high at start acts once)."""
        last = self._last.get(key, 0)
        self._last[key] = value
        return last

    def _rose_value(self, key: str, value: Any) -> bool:
        last = self._swap(key, value)
        return bool(value) and not last

    def _rose(self, pins: Any, attr: str) -> bool:
        """Whether bit pin ``attr`` of a pin group went from 0 to 1 since the last cycle."""
        return self._rose_value(f"{pins.name}.{attr}", getattr(pins, attr))

    # ================================================================ inputs -> commands
    def _act(self) -> None:
        """Every input that changed, each through ``_carry_out``: the main buttons in
        LinuxCNC's order (the order they act in when several rise in one cycle), then
        the overrides, spindles, joints, jogs and MDI buttons."""
        pins, cmd, config = self.pins, self.command, self.config
        for button in MAIN_BUTTONS:
            if self._rose(pins.main, button):
                self._carry_out(button, self.handlers[button], button)
        self._carry_out("max-velocity", self._adjust, pins.max_velocity, cmd.maxvel, 0.0,
                        config.max_velocity)  # fmt: skip
        self._carry_out("feed-override", self._adjust, pins.feed_override, cmd.feedrate, 0.0,
                        config.max_feed_override)  # fmt: skip
        self._carry_out("rapid-override", self._adjust, pins.rapid_override, cmd.rapidrate,
                        0.0, 1.0)  # fmt: skip
        for n, spindle in enumerate(pins.spindles):
            self._carry_out(
                f"spindle.{n}.override",
                self._adjust,
                pins.spindle_overrides[n],
                lambda v, n=n: cmd.spindleoverride(v, n),
                config.min_spindle_override,
                config.max_spindle_override,
            )
            self._carry_out(f"spindle.{n}", self._spindle_buttons, n, spindle)
        if pins.home_all is not None and self._rose(pins.home_all, "home_all"):
            self._carry_out("home-all", cmd.home, -1)
        self._carry_out("joint", self._joint_buttons)
        self._carry_out("jog", self._jogs)
        for n, text in enumerate(config.mdi_commands):
            if self._rose_value(f"halui.mdi-command-{n:02d}", pins.main.mdi_command[n]):
                self._carry_out(f"mdi-command-{n:02d}", self._run_mdi, n, text)

    @staticmethod
    def _carry_out(name: str, function: Callable[..., Any], *args: Any) -> None:
        """Run the handler of input ``name``. A refusal (``Refused``) is said on stderr,
        where LinuxCNC's halui says what it does not do; any other exception but the
        controller's absence (``cnc.error``, which the process loop waits out) is an
        internal error, said, and halui goes on (nml/commands.py)."""
        try:
            function(*args)
        except Refused as refusal:
            if not refusal.is_quiet:
                warn(refusal.reason)
        except error:
            raise
        except Exception as exc:
            said = internal_error("halui", f"in {name}", exc).reason  # ("halui: ...")
            print(said, file=sys.stderr, flush=True)

    # ---------------------------------------------------------------- main buttons
    @handler("machine_on", "machine_off", "estop_activate", "estop_reset")
    def _machine(self, button: str) -> None:
        self.command.state(_MACHINE_STATES[button])

    @handler("mode_manual", "mode_auto", "mode_mdi")
    def _mode(self, button: str) -> None:
        self._set_mode(_MODES[button])

    @handler("mode_teleop", "mode_joint")
    def _teleop(self, button: str) -> None:
        self._set_teleop(button == "mode_teleop")

    @handler("mist_on", "mist_off")
    def _mist(self, button: str) -> None:
        self.command.mist(c.MIST_ON if button == "mist_on" else c.MIST_OFF)

    @handler("flood_on", "flood_off")
    def _flood(self, button: str) -> None:
        self.command.flood(c.FLOOD_ON if button == "flood_on" else c.FLOOD_OFF)

    @handler("lube_on", "lube_off")
    def _lube(self, button: str) -> None:
        self.command.lube(button == "lube_on")

    @handler("program_run")
    def _run_program(self, _button: str) -> None:
        if not self.stat.file:
            return  # no program open: nothing to run
        self._set_mode(c.MODE_AUTO)
        self.command.auto(c.AUTO_RUN, 0)

    @handler("program_pause", "program_resume", "program_step")
    def _program(self, button: str) -> None:
        self.command.auto(_PROGRAM_ACTIONS[button])

    @handler("optional_stop_on", "optional_stop_off")
    def _optional_stop(self, button: str) -> None:
        self.command.set_optional_stop(int(button == "optional_stop_on"))

    @handler("block_delete_on", "block_delete_off")
    def _block_delete(self, button: str) -> None:
        self.command.set_block_delete(int(button == "block_delete_on"))

    @handler("program_stop", "abort")
    def _abort(self, _button: str) -> None:
        self.command.abort()

    # ---------------------------------------------------------------- other inputs
    def _set_mode(self, mode: int) -> None:
        if self.stat.task_mode != mode:
            self.command.mode(mode)

    def _set_teleop(self, is_teleop: bool) -> None:
        self.command.teleop_enable(int(is_teleop))
        self.command.wait_complete()

    def _adjust(
        self, pins: AdjustPins, send: Callable[[float], Any], low: float, high: float
    ) -> None:
        """An override or the max velocity: counts (relative, or counts x scale with
        direct-value), increase / decrease by scale, reset to 1.0; sent within low..high."""

        def send_within(value: float) -> None:
            if math.isfinite(value):
                send(min(max(value, low), high))

        counts = pins.counts
        last = self._swap(f"{pins.name}.counts", counts)
        if counts != last and pins.count_enable:
            if pins.direct_value:
                send_within(counts * pins.scale)
            else:
                send_within(pins.value + (counts - last) * pins.scale)
        if self._rose(pins, "increase"):
            send_within(pins.value + pins.scale)
        if self._rose(pins, "decrease"):
            send_within(pins.value - pins.scale)
        if hasattr(pins, "reset") and self._rose(pins, "reset"):  # overrides, not max-velocity
            send_within(1.0)

    def _spindle_buttons(self, n: int, pins: Any) -> None:
        cmd = self.command
        speed = abs(self.stat.settings[2]) or 1.0  # the programmed S, else 1 (LinuxCNC)
        if self._rose(pins, "start"):
            cmd.spindle(c.SPINDLE_FORWARD, speed, n)
        if self._rose(pins, "stop"):
            cmd.spindle(c.SPINDLE_OFF, n)
        if self._rose(pins, "forward"):
            cmd.spindle(c.SPINDLE_FORWARD, speed, n)
        if self._rose(pins, "reverse"):
            cmd.spindle(c.SPINDLE_REVERSE, speed, n)
        # increase / decrease act while held: constant speed again on release
        for attr, direction in (("increase", c.SPINDLE_INCREASE), ("decrease", c.SPINDLE_DECREASE)):
            value = getattr(pins, attr)
            if value != self._swap(f"{pins.name}.{attr}", value):
                cmd.spindle(direction if value else c.SPINDLE_CONSTANT, n)
        if self._rose(pins, "brake_on"):
            cmd.brake(c.BRAKE_ENGAGE, n)
        if self._rose(pins, "brake_off"):
            cmd.brake(c.BRAKE_RELEASE, n)

    def _joint_buttons(self) -> None:
        for n, joint in enumerate(self.pins.joints):
            if self._rose(joint, "home"):
                self.command.home(n)
            if self._rose(joint, "unhome"):
                self.command.unhome(n)
        selected = self.pins.main.joint_selected
        if self._rose(self.pins.selected_joint, "home"):
            self.command.home(selected)
        if self._rose(self.pins.selected_joint, "unhome"):
            self.command.unhome(selected)

    # ---------------------------------------------------------------- jogging
    def _jogs(self) -> None:
        main, pins = self.pins.main, self.pins
        self._jog_group(
            "joint",
            list(enumerate(pins.joints)),
            pins.selected_joint,
            main.joint_jog_speed,
            main.joint_jog_deadband,
            JOINT_JOG,
        )
        self._jog_group(
            "axis",
            [(AXIS_LETTERS.index(letter), axis) for letter, axis in pins.axes.items()],
            pins.selected_axis,
            main.axis_jog_speed,
            main.axis_jog_deadband,
            AXIS_JOG,
        )

    def _jog_group(
        self,
        kind: str,
        items: list[tuple[int, Any]],
        selected_pins: JogPins,
        speed: float,
        deadband: float,
        jjogmode: int,
    ) -> None:
        """The joints' or the axes' jog, select and ``selected.*`` pins. Held buttons and
        analog inputs jog at jog-speed (units/min); a speed change restarts running jogs."""
        is_speed_changed = abs(speed - self._jog_speeds[kind]) > SPEED_EPSILON
        if is_speed_changed:
            self._jog_speeds[kind] = speed
        newly_selected = None
        for index, pins in items:
            self._held_jog(pins, "minus", index, -speed, jjogmode, is_speed_changed)
            self._held_jog(pins, "plus", index, speed, jjogmode, is_speed_changed)
            analog = pins.analog
            is_active = abs(analog) > deadband
            if analog != self._swap(f"{pins.name}.analog", analog) or (
                is_active and is_speed_changed
            ):
                if is_active:
                    self._jog_continuous(index, speed * analog, jjogmode)
                else:
                    self._jog_stop(index, jjogmode)
            self._increment_jogs(pins, index, speed, jjogmode)
            if self._rose(pins, "select"):
                newly_selected = index
        selected_attr = f"{kind}_selected"
        if newly_selected is not None:
            self._select(items, selected_pins, selected_attr, newly_selected, speed, jjogmode)
        selected = getattr(self.pins.main, selected_attr)
        self._held_jog(selected_pins, "minus", selected, -speed, jjogmode, is_speed_changed)
        self._held_jog(selected_pins, "plus", selected, speed, jjogmode, is_speed_changed)
        self._increment_jogs(selected_pins, selected, speed, jjogmode)

    def _select(
        self,
        items: list[tuple[int, Any]],
        selected_pins: JogPins,
        selected_attr: str,
        chosen: int,
        speed: float,
        jjogmode: int,
    ) -> None:
        """A new joint or axis is selected: a jog held on ``selected.plus/minus`` moves to it."""
        setattr(self.pins.main, selected_attr, chosen)
        prefix = selected_pins.name
        was_jogging = self._last.get(f"{prefix}.plus") or self._last.get(f"{prefix}.minus")
        for index, pins in items:
            pins.is_selected = index == chosen
            if index == chosen:
                if selected_pins.plus:
                    self._jog_continuous(index, speed, jjogmode)
                elif selected_pins.minus:
                    self._jog_continuous(index, -speed, jjogmode)
            elif was_jogging and not (pins.plus or pins.minus or pins.analog):
                self._jog_stop(index, jjogmode)

    def _held_jog(
        self,
        pins: Any,
        attr: str,
        index: int,
        velocity: float,
        jjogmode: int,
        is_speed_changed: bool,
    ) -> None:
        value = getattr(pins, attr)
        if value != self._swap(f"{pins.name}.{attr}", value) or (value and is_speed_changed):
            if value:
                self._jog_continuous(index, velocity, jjogmode)
            else:
                self._jog_stop(index, jjogmode)

    def _increment_jogs(self, pins: JogPins, index: int, speed: float, jjogmode: int) -> None:
        if self._rose(pins, "increment_plus"):
            self._jog_increment(index, speed, pins.increment, jjogmode)
        if self._rose(pins, "increment_minus"):
            self._jog_increment(index, speed, -pins.increment, jjogmode)

    def _is_jog_mode(self, jjogmode: int) -> bool:
        """Joints jog in joint (free) mode, axes in teleop mode."""
        is_teleop = self.stat.motion_mode == c.TRAJ_MODE_TELEOP
        return is_teleop == (jjogmode == AXIS_JOG)

    def _jog_continuous(self, index: int, speed: float, jjogmode: int) -> None:
        if self.stat.task_state == c.STATE_ON and self._is_jog_mode(jjogmode):
            self.command.jog(c.JOG_CONTINUOUS, jjogmode, index, speed / 60.0)

    def _jog_increment(self, index: int, speed: float, increment: float, jjogmode: int) -> None:
        if self.stat.task_state == c.STATE_ON and self._is_jog_mode(jjogmode):
            self.command.jog(c.JOG_INCREMENT, jjogmode, index, speed / 60.0, increment)

    def _jog_stop(self, index: int, jjogmode: int) -> None:
        if self._is_jog_mode(jjogmode):
            self.command.jog(c.JOG_STOP, jjogmode, index)

    # ---------------------------------------------------------------- MDI buttons
    def _run_mdi(self, n: int, text: str) -> None:
        """halui.mdi-command-NN: switch to MDI mode if needed and send the line."""
        stat, cmd = self.stat, self.command
        if self._mdi_serial is None:  # the first of a series: the mode to come back to
            self._mode_before_mdi = stat.task_mode
        if stat.task_mode != c.MODE_MDI:
            cmd.mode(c.MODE_MDI)
            cmd.wait_complete()
            stat.poll()
            if stat.task_mode != c.MODE_MDI:
                raise Refused(f"mdi-command-{n:02d} not sent: task did not switch to MDI mode")
        cmd.mdi(text)
        self._mdi_serial = cmd.serial

    def _end_mdi(self) -> None:
        """Once the last MDI line halui sent has finished (done or failed), go back to the
        mode task was in before: manual, auto, or stay in MDI (LinuxCNC's halui)."""
        if self._mdi_serial is None:
            return
        stat = self.stat
        ahead = serial_difference(stat.echo_serial_number, self._mdi_serial)
        if ahead < 0 or (ahead == 0 and stat.state not in (c.RCS_DONE, c.RCS_ERROR)):
            return
        self._mdi_serial = None
        if self._mode_before_mdi == c.MODE_AUTO:
            self._set_mode(c.MODE_AUTO)
        elif self._mode_before_mdi != c.MODE_MDI:
            self._set_mode(c.MODE_MANUAL)

    # ================================================================ status -> outputs
    def _mirror(self) -> None:
        stat, pins, main = self.stat, self.pins, self.pins.main
        if not self._has_units and stat.linear_units:  # set once, when task has set it
            main.units_per_mm = stat.linear_units
            self._has_units = True
        main.is_machine_on = stat.task_state == c.STATE_ON
        main.is_estop_activated = stat.task_state == c.STATE_ESTOP
        mode = stat.task_mode
        main.is_mode_manual = mode == c.MODE_MANUAL
        main.is_mode_auto = mode == c.MODE_AUTO
        main.is_mode_mdi = mode == c.MODE_MDI
        main.is_mode_teleop = stat.motion_mode == c.TRAJ_MODE_TELEOP
        main.is_mode_joint = stat.motion_mode == c.TRAJ_MODE_FREE
        interp = stat.interp_state
        main.is_program_idle = interp == c.INTERP_IDLE
        main.is_program_running = interp in (c.INTERP_READING, c.INTERP_WAITING)
        main.is_program_paused = interp == c.INTERP_PAUSED
        main.is_optional_stop_on = stat.optional_stop
        main.is_block_delete_on = stat.block_delete
        main.is_mist_on = stat.mist
        main.is_flood_on = stat.flood
        main.is_lube_on = stat.lube
        pins.max_velocity.value = stat.max_velocity
        pins.feed_override.value = stat.feedrate
        pins.rapid_override.value = stat.rapidrate
        main.tool_number = stat.tool_in_spindle
        main.tool_diameter = self._tool_diameter()
        for letter, offset in zip(AXIS_LETTERS, stat.tool_offset, strict=True):
            setattr(pins.tool_offset, letter, offset)
        for n, spindle in enumerate(stat.spindle[: len(pins.spindles)]):
            spindle_pins = pins.spindles[n]
            spindle_pins.is_on = spindle["enabled"]
            spindle_pins.runs_forward = spindle["direction"] == 1
            spindle_pins.runs_backward = spindle["direction"] == -1
            spindle_pins.brake_is_on = spindle["brake"]
            pins.spindle_overrides[n].value = spindle["override"]
        joints = stat.joint
        for n, joint_pins in enumerate(pins.joints):
            _mirror_joint(joint_pins, joints[n])
        selected = main.joint_selected
        if selected < len(joints):
            _mirror_joint(pins.selected_joint, joints[selected])
        self._mirror_axes()

    def _mirror_axes(self) -> None:
        """pos-commanded and pos-feedback in machine coordinates; pos-relative is the
        feedback position in the current work offsets (G5x with its XY rotation, G92, tool)."""
        stat = self.stat
        actual = stat.actual_position
        g5x, g92, tool = stat.g5x_offset, stat.g92_offset, stat.tool_offset
        relative = [actual[i] - g5x[i] - tool[i] for i in range(len(AXIS_LETTERS))]
        angle = -math.radians(stat.rotation_xy)
        x, y = relative[0], relative[1]
        relative[0] = x * math.cos(angle) - y * math.sin(angle)
        relative[1] = y * math.cos(angle) + x * math.sin(angle)
        for letter, pins in self.pins.axes.items():
            i = AXIS_LETTERS.index(letter)
            pins.pos_commanded = stat.position[i]
            pins.pos_feedback = actual[i]
            pins.pos_relative = relative[i] - g92[i]

    def _tool_diameter(self) -> float:
        number = self.stat.tool_in_spindle
        if number <= 0:
            return 0.0
        for entry in self.stat.tool_table:
            if entry.id == number:
                return entry.diameter
        return 0.0


def _mirror_joint(pins: Any, joint: dict[str, Any]) -> None:
    pins.is_homed = joint["homed"]
    pins.on_soft_min_limit = joint["min_soft_limit"]
    pins.on_soft_max_limit = joint["max_soft_limit"]
    pins.on_hard_min_limit = joint["min_hard_limit"]
    pins.on_hard_max_limit = joint["max_hard_limit"]
    pins.override_limits = joint["override_limits"]
    pins.has_fault = joint["fault"]
