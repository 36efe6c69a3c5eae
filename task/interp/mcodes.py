"""M codes: I/O, M61, spindle, coolant, overrides, M100+ and the M70..M73 modal state."""

from __future__ import annotations

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from . import statetag
from .block import (
    G_7,
    G_8,
    G_17,
    G_17_1,
    G_18,
    G_18_1,
    G_19,
    G_19_1,
    G_20,
    G_21,
    G_40,
    G_41,
    G_42,
    G_43,
    G_49,
    G_61,
    G_61_1,
    G_64,
    G_90,
    G_90_1,
    G_91,
    G_91_1,
    G_92_2,
    G_92_3,
    G_93,
    G_94,
    G_95,
    G_96,
    G_97,
    G_98,
    G_99,
    Block,
)
from .common import (
    CONSTANT_RPM,
    INVERSE_TIME,
    LEFT,
    MODE_ABSOLUTE,
    OLD_Z,
    RIGHT,
    UNITS_PER_MINUTE,
    round_to_int,
)
from .errors import INTERP_OK, InterpError

CONTEXT_VALID, CONTEXT_RESTORE_ON_RETURN = 1, 2


class MCodesMixin:
    """M-code conversions; mixed into the Interpreter."""

    # ============================================================== M codes
    def convert_m(self, block: Block) -> None:
        """The M codes of a block, group by group (stops, group 4, come last: convert_stop)."""
        m_modes = block.m_modes
        if m_modes[5] != -1:
            self.convert_m_group5(block, m_modes[5])
        if m_modes[6] != -1:
            self.convert_m_group6(block, m_modes[6])
        if m_modes[7] != -1:
            self.convert_m_group7(block, m_modes[7])
        if m_modes[8] != -1:
            self.convert_m_group8(block, m_modes[8])
        if m_modes[9] != -1:
            self.convert_m_group9(block, m_modes[9])
        if m_modes[10] != -1:
            self.convert_m_group10(block, m_modes[10])

    def convert_m_group5(self, block: Block, m5: int) -> None:
        """M62..M68: digital and analog I/O."""
        canon = self.canon
        if m5 in (62, 63, 64, 65):
            if self.cutter_comp_side:
                what = {62: "motion output", 63: "motion digital output"}.get(
                    m5, "auxiliary digital output"
                )
                raise InterpError(f"Cannot set {what} with cutter radius compensation on")
            if not block.p_flag:
                raise InterpError(f"No valid P word with M{m5}")
            index = round_to_int(block.p_number)
            {
                62: canon.SET_MOTION_OUTPUT_BIT,
                63: canon.CLEAR_MOTION_OUTPUT_BIT,
                64: canon.SET_AUX_OUTPUT_BIT,
                65: canon.CLEAR_AUX_OUTPUT_BIT,
            }[m5](index)
        elif m5 == 66:
            self.convert_m66(block)
        elif m5 in (67, 68):
            if self.cutter_comp_side:
                raise InterpError(
                    "Cannot set motion analog output with cutter radius compensation on"
                    if m5 == 67
                    else "Cannot set auxiliary analog output with cutter radius compensation on"
                )
            if not block.e_flag or round_to_int(block.e_number) < 0:
                raise InterpError(f"Invalid analog index with M{m5}")
            func = canon.SET_MOTION_OUTPUT_VALUE if m5 == 67 else canon.SET_AUX_OUTPUT_VALUE
            func(round_to_int(block.e_number), block.q_number)

    def convert_m_group6(self, block: Block, m6: int) -> None:
        """M6 and M61 (inside a remap of them, the built-in: noted for its epilog)."""
        canon = self.canon
        if self.remap_level and m6 in (6, 61):
            self.remap_blocks[self.remap_level].builtin_used = True
        if m6 == 6:
            self.convert_tool_change()
        elif m6 == 61:
            toolno = round_to_int(block.q_number)
            if toolno < 0:
                raise InterpError("Need non-negative Q-word to specify tool number with M61")
            idx = self.find_tool_index(toolno)
            self.current_pocket = idx
            self.toolchange_flag = True
            canon.CHANGE_TOOL_NUMBER(self.current_pocket)
            self.set_tool_parameters()

    def convert_m_group7(self, block: Block, m7: int) -> None:
        """M3, M4, M5, M19 and M70..M73."""
        if m7 in (3, 4, 5):
            if block.dollar_flag:
                if block.dollar_number >= self.num_spindles or block.dollar_number < -1:
                    raise InterpError(
                        f"Spindle ($) number out of range in M{m7} Command\nnum_spindles "
                        f"={self.num_spindles}. $={int(block.dollar_number)}\n"
                    )
                spindles = (
                    range(self.num_spindles)
                    if block.dollar_number == -1
                    else [int(block.dollar_number)]
                )
            else:
                spindles = [0]
            for s in spindles:
                if m7 == 3:
                    self._enq("START_SPINDLE_CLOCKWISE", s)
                    self.spindle_turning[s] = C.CLOCKWISE
                elif m7 == 4:
                    self._enq("START_SPINDLE_COUNTERCLOCKWISE", s)
                    self.spindle_turning[s] = C.COUNTERCLOCKWISE
                else:
                    self.spindle_turning[s] = C.STOPPED
                    self._enq("STOP_SPINDLE_TURNING", s)
        elif m7 == 19:
            for s in range(self.num_spindles):
                self.spindle_turning[s] = C.STOPPED
            if block.dollar_flag and (
                block.dollar_number >= self.num_spindles or block.dollar_number < 0
            ):
                raise InterpError("Spindle ($) number out of range in M19 Command")
            spindle = int(block.dollar_number) if block.dollar_flag else 0
            if block.r_flag or block.p_flag:
                self._enq(
                    "ORIENT_SPINDLE",
                    spindle,
                    (block.r_number + self.orient_offset) if block.r_flag else self.orient_offset,
                    int(block.p_number) if block.p_flag else 0,
                )
            if block.q_flag:
                if block.q_number <= 0.0:
                    raise InterpError("Q word with M19 requires a value > 0")
                self._enq("WAIT_SPINDLE_ORIENT_COMPLETE", spindle, block.q_number)
        elif m7 in (70, 71, 72, 73):
            self.convert_context(m7)

    def convert_m_group8(self, block: Block, m8: int) -> None:
        """M7, M8, M9: coolant."""
        if m8 == 7:
            self._enq("MIST_ON")
            self.mist = True
        elif m8 == 8:
            self._enq("FLOOD_ON")
            self.flood = True
        elif m8 == 9:
            self._enq("MIST_OFF")
            self.mist = False
            self._enq("FLOOD_OFF")
            self.flood = False

    def convert_m_group9(self, block: Block, m9: int) -> None:
        """M48..M53: overrides."""
        canon = self.canon
        if m9 in (48, 49):
            if self.cutter_comp_side:
                raise InterpError(
                    f"Cannot {'enable' if m9 == 48 else 'disable'} overrides with cutter "
                    "radius compensation on"
                )
            if m9 == 48:
                canon.ENABLE_FEED_OVERRIDE()
                self.feed_override = True
                for s in range(self.num_spindles):
                    self.speed_override[s] = True
                    canon.ENABLE_SPEED_OVERRIDE(s)
            else:
                canon.DISABLE_FEED_OVERRIDE()
                self.feed_override = False
                for s in range(self.num_spindles):
                    self.speed_override[s] = False
                    canon.DISABLE_SPEED_OVERRIDE(s)
        elif m9 in (50, 51, 52, 53):
            on = block.p_number != 0
            if m9 == 51:
                e = -1
                if block.dollar_flag:
                    if block.dollar_number <= 0 or block.dollar_number >= self.num_spindles:
                        raise InterpError("Invalid spindle ($) number in M51 command")
                    e = int(block.dollar_number)
            if self.cutter_comp_side:
                raise InterpError(
                    f"Cannot {'enable' if on else 'disable'} overrides with cutter radius "
                    "compensation on"
                )
            if m9 == 50:
                (canon.ENABLE_FEED_OVERRIDE if on else canon.DISABLE_FEED_OVERRIDE)()
                self.feed_override = on
            elif m9 == 51:
                for s in range(self.num_spindles):
                    if e == -1 or s == e:
                        (canon.ENABLE_SPEED_OVERRIDE if on else canon.DISABLE_SPEED_OVERRIDE)(s)
                        self.speed_override[s] = on
            elif m9 == 52:
                (canon.ENABLE_ADAPTIVE_FEED if on else canon.DISABLE_ADAPTIVE_FEED)()
                self.adaptive_feed = on
            else:
                (canon.ENABLE_FEED_HOLD if on else canon.DISABLE_FEED_HOLD)()
                self.feed_hold = on

    def convert_m_group10(self, block: Block, m10: int) -> None:
        """M100..M199: user-defined M codes (external programs)."""
        if not self.canon.USER_DEFINED_FUNCTION(m10, block.p_number, block.q_number):
            raise InterpError(f"Unknown m code used: M{m10}")

    def convert_m66(self, block: Block) -> None:
        if block.p_flag and block.e_flag:
            raise InterpError("Invalid to select both a digital and an analog input with M66")
        if block.q_number <= 0 and block.l_flag and round_to_int(block.l_number) > 0:
            raise InterpError("Zero timeout with wait type != immediate return")
        if block.e_flag and block.l_flag and round_to_int(block.l_number) != 0:
            raise InterpError("Can't select analog input with wait type != immediate return")
        if (
            (block.p_flag and round_to_int(block.p_number) < 0)
            or (block.e_flag and round_to_int(block.e_number) < 0)
            or (not block.p_flag and not block.e_flag)
        ):
            raise InterpError("Need to have either a valid P or a valid E word with M66")
        self.write_canon_state_tag(block)
        if block.p_flag:
            wait_type = round_to_int(block.l_number) if block.l_flag else 0
            timeout = block.q_number if block.q_number > 0 else 0.0
            if self.cutter_comp_side:
                raise InterpError(
                    "Cannot wait for digital input with cutter radius compensation on"
                )
            ret = self.canon.WAIT(round_to_int(block.p_number), C.DIGITAL_INPUT, wait_type, timeout)
            if ret == -1:
                raise InterpError("Digital input selected out of bounds")
            if ret == 0:
                self.input_flag = True
                self.input_index = round_to_int(block.p_number)
                self.input_digital = True
        elif round_to_int(block.e_number) >= 0:
            if self.cutter_comp_side:
                raise InterpError("Cannot wait for analog input with cutter radius compensation on")
            ret = self.canon.WAIT(round_to_int(block.e_number), C.ANALOG_INPUT, 0, 0)
            if ret == -1:
                raise InterpError("Analog input selected out of bounds")
            if ret == 0:
                self.input_flag = True
                self.input_index = round_to_int(block.e_number)
                self.input_digital = False

    # ======================================================== M70..M73
    def convert_context(self, m7: int) -> None:
        frame = self.sub_context[self.call_level]
        if m7 in (70, 73):
            self.save_settings()
            frame.context_status |= CONTEXT_VALID
            if m7 == 73 and self.call_level > 0:
                frame.context_status |= CONTEXT_RESTORE_ON_RETURN
        elif m7 == 71:
            frame.context_status &= ~CONTEXT_VALID
        else:
            if not frame.context_status & CONTEXT_VALID:
                raise InterpError(
                    "Cannot restore context from invalid stack frame - missing M70/M73?"
                )
            self.restore_settings(self.call_level)

    def active_g_codes(self) -> list[int]:
        plane = {
            C.PLANE_XY: G_17,
            C.PLANE_XZ: G_18,
            C.PLANE_YZ: G_19,
            C.PLANE_UV: G_17_1,
            C.PLANE_UW: G_18_1,
            C.PLANE_VW: G_19_1,
        }.get(self.plane, 0)
        o = self.origin_index
        return [
            self.sequence_number,
            self.motion_mode,
            -1,
            plane,
            G_42
            if self.cutter_comp_side == RIGHT
            else G_41
            if self.cutter_comp_side == LEFT
            else G_40,
            G_20 if self.length_units == C.UNITS_INCHES else G_21,
            G_90 if self.distance_mode == MODE_ABSOLUTE else G_91,
            G_93
            if self.feed_mode == INVERSE_TIME
            else G_94
            if self.feed_mode == UNITS_PER_MINUTE
            else G_95,
            530 + 10 * o if o < 7 else 584 + o,
            G_43 if any(self.tool_offset) else G_49,
            G_98 if self.retract_mode == OLD_Z else G_99,
            G_64
            if self.control_mode == C.CONTINUOUS
            else G_61
            if self.control_mode == C.EXACT_PATH
            else G_61_1,
            -1,
            G_97 if self.spindle_mode[0] == CONSTANT_RPM else G_96,
            G_90_1 if self.ijk_distance_mode == MODE_ABSOLUTE else G_91_1,
            G_7 if self.lathe_diameter_mode else G_8,
            G_92_3 if self.parameters[5210] else G_92_2,
        ]

    def active_m_codes(self) -> list[int]:
        turning = self.spindle_turning[0]
        return [
            self.sequence_number,
            -1,
            5 if turning == C.STOPPED else 3 if turning == C.CLOCKWISE else 4,
            -1,
            7 if self.mist else -1 if self.flood else 9,
            8 if self.flood else -1,
            48 if self.feed_override else 51,  # LinuxCNC tests the array, always true
            52 if self.adaptive_feed else -1,
            53 if self.feed_hold else -1,
            0,
        ]

    def active_settings(self) -> list[float]:
        return [
            float(self.sequence_number),
            self.feed_rate,
            self.speed[0],
            self.tolerance,
            self.naivecam_tolerance,
        ]

    def save_settings(self) -> None:
        frame = self.sub_context[self.call_level]
        frame.saved_g_codes = self.active_g_codes()
        frame.saved_m_codes = self.active_m_codes()
        frame.saved_settings = self.active_settings()

    def restore_settings(self, from_level: int) -> None:
        frame = self.sub_context[from_level]
        current_g = self.active_g_codes()
        if current_g[5] != frame.saved_g_codes[5]:
            self._execute_restore(
                f"G{frame.saved_g_codes[5] // 10}", "M7x: restore_settings G20/G21 failed: ''"
            )
            current_g = self.active_g_codes()
        cmd = _gen_settings(current_g, frame.saved_g_codes, frame.saved_settings)
        cmd += _gen_m_codes(self.active_m_codes(), frame.saved_m_codes)
        for part in cmd.split("\n"):
            if part:
                self._execute_restore(part, None)

    def restore_from_tag(self, tag: tuple) -> bool:
        """After a program's abort: bring the modes back to those of the move motion was
        carrying out (its state tag, statetag.py), which the interpreter, reading ahead,
        had left behind, as LinuxCNC's restore_from_tag: G20/G21 first, then the other
        modal groups that differ (cutter compensation always off, never the motion mode),
        feed, speed and G64's tolerances, executed as G-code so the canon hears of them;
        M codes stay. False (nothing done) for a tag that is not restorable: invalid, or
        taken inside a subroutine or a remap."""
        if not statetag.is_restorable(tag):
            return False
        self.input_flag = self.toolchange_flag = self.probe_flag = False
        saved_g, _saved_m, saved_settings = statetag.active_modes(tag)
        saved_g[4] = G_40
        current_g = self.active_g_codes()
        lines = []
        if current_g[5] != saved_g[5]:
            lines.append(f"G{saved_g[5] // 10}")
        lines += _gen_settings(current_g, saved_g, saved_settings).split("\n")
        for line in lines:
            if not line:
                continue
            try:
                self.execute(line)
            except InterpError as error:
                raise InterpError(
                    f"Failed to restore interp state on abort '{line}': {error.message}"
                ) from None
        return True

    def _execute_restore(self, command: str, message: str | None) -> None:
        try:
            status = self.execute(command)
        except InterpError as error:
            if message is not None:
                raise InterpError(message) from None
            raise InterpError(
                f"M7x: restore_settings failed executing: '{command}': {error.message}"
            ) from None
        if status != INTERP_OK and message is not None:
            raise InterpError(message)


def _gen_settings(current_g, saved_g, saved_f) -> str:
    """The G-code text that brings the modal state back to a saved one (M72, M73).

    Feed, speed and the G64 tolerances are restored whether or not they changed, as
    LinuxCNC 2.9.10 does (its fix of issue 1987; the 2.9.0 pre-release compared them with
    the current values and so lost a feed or speed the canon layer had not applied yet).
    """
    cmd = [f" F{saved_f[1]:.1f}", f" S{saved_f[2]:.0f}"]
    g64_changed = True
    for i in range(17):
        val = saved_g[i]
        if val == current_g[i]:
            continue
        if i in (3, 4, 6, 7, 8, 9, 10, 13, 14, 15, 16):
            if val != -1:
                cmd.append(f" G{val // 10}.{val % 10}" if val % 10 else f" G{val // 10}")
        elif i == 11:
            if val == G_64:
                g64_changed = True
            elif val == G_61:
                cmd.append(" G61")
            elif val == G_61_1:
                cmd.append(" G61.1")
    if saved_g[11] == G_64 and g64_changed:
        if saved_f[3] < 0:
            cmd.append(" G64")
        elif saved_f[4] < 0:
            cmd.append(f" G64 P{saved_f[3]:f}")
        else:
            cmd.append(f" G64 P{saved_f[3]:f} Q{saved_f[4]:f}")
    return "".join(cmd)


def _gen_m_codes(current, saved) -> str:
    cmd = []
    for i in range(10):
        val = saved[i]
        if val != current[i] and i in (2, 4, 5, 6, 7, 8) and val != -1:
            cmd.append(f"M{val}\n")
    return "".join(cmd)
