"""The RS274NGC interpreter: state, the read/execute cycle and LinuxCNC's order of execution.

The public face is LinuxCNC's ``Interp``: ``init()``, ``open(file)``, ``read([line])``,
``execute()``, ``synch()``, ``close()``, ``exit()``; each returns one of the codes in
``errors`` or raises ``InterpError``. The interpreter only talks to the world through a canon
(``canon.Canon``), so it knows nothing about processes (INTERP-022).

Units: internally positions are in program units (G20/G21); the canon's ``length units`` are
the machine's, and the parameter file and tool table are in those ("user") units.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
from collections.abc import Callable

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from . import ldmath
from .block import (
    CT_NGC_M98_SUB,
    CT_NONE,
    G_0,
    G_1,
    G_2,
    G_3,
    G_4,
    G_5,
    G_5_1,
    G_5_2,
    G_5_3,
    G_7,
    G_8,
    G_10,
    G_17,
    G_17_1,
    G_18,
    G_18_1,
    G_19,
    G_19_1,
    G_20,
    G_21,
    G_28,
    G_28_1,
    G_30,
    G_30_1,
    G_33,
    G_33_1,
    G_38_2,
    G_38_3,
    G_38_4,
    G_38_5,
    G_40,
    G_41,
    G_41_1,
    G_42,
    G_42_1,
    G_43,
    G_43_1,
    G_43_2,
    G_49,
    G_52,
    G_53,
    G_54,
    G_61,
    G_61_1,
    G_64,
    G_70,
    G_71,
    G_71_1,
    G_71_2,
    G_72,
    G_72_1,
    G_72_2,
    G_73,
    G_74,
    G_76,
    G_80,
    G_81,
    G_82,
    G_83,
    G_84,
    G_86,
    G_87,
    G_88,
    G_89,
    G_90,
    G_90_1,
    G_91,
    G_91_1,
    G_92,
    G_92_1,
    G_92_2,
    G_92_3,
    G_93,
    G_94,
    G_95,
    G_96,
    G_97,
    G_98,
    G_99,
    GM_CONTROL_MODE,
    GM_COORD_SYSTEM,
    GM_CUTTER_COMP,
    GM_DISTANCE_MODE,
    GM_FEED_MODE,
    GM_G92_IS_APPLIED,
    GM_IJK_DISTANCE_MODE,
    GM_LATHE_DIAMETER_MODE,
    GM_LENGTH_UNITS,
    GM_MODAL_0,
    GM_MOTION,
    GM_RETRACT_MODE,
    GM_SET_PLANE,
    GM_SPINDLE_MODE,
    GM_TOOL_LENGTH_OFFSET,
    M_98,
    Block,
    O_none,
    is_a_cycle,
)
from .comp import QOTHER, CompMixin
from .compiled import Compiler
from .cycles import CyclesMixin
from .errors import (
    INTERP_ENDFILE,
    INTERP_EXECUTE_FINISH,
    INTERP_EXIT,
    INTERP_FILE_NOT_OPEN,
    INTERP_OK,
    InterpError,
)
from .owords import Context, OWordMixin
from .params import ParamsMixin
from .reader import _DOWNCASE, LINELEN, ReaderMixin, close_and_downcase

MM_PER_INCH = 25.4
INCH_PER_MM = 1.0 / 25.4
CENTER_ARC_RADIUS_TOLERANCE_INCH = 2 * 0.001 * math.sqrt(2)
CENTER_ARC_RADIUS_TOLERANCE_MM = 2 * 0.01 * math.sqrt(2)
RADIUS_TOLERANCE_INCH = 0.00005
RADIUS_TOLERANCE_MM = RADIUS_TOLERANCE_INCH * MM_PER_INCH
SPIRAL_RELATIVE_TOLERANCE = 0.001
TINY = 1e-12
MAX_EMS = 4

UNITS_PER_MINUTE, INVERSE_TIME, UNITS_PER_REVOLUTION = 0, 1, 2
MODE_ABSOLUTE, MODE_INCREMENTAL = 0, 1
R_PLANE, OLD_Z = 0, 1
RIGHT, LEFT = 1, 2
CONSTANT_RPM, CONSTANT_SURFACE = 0, 1
NUM_SPINDLES_MAX = 8


def rotate(x: float, y: float, theta: float) -> tuple[float, float]:
    t = theta * (math.pi / 180.0)
    c, s = math.cos(t), math.sin(t)
    return x * c - y * s, x * s + y * c


def _round_to_int(x: float) -> int:
    return round(x)  # nearbyint: ties to even, like Python's round


def _is_near_int(value: float) -> tuple[bool, int]:
    result = int(value + 0.5)
    return abs(result - value) < 0.0001, result


class Interpreter(ParamsMixin, ReaderMixin, OWordMixin, CyclesMixin, CompMixin):
    """LinuxCNC's RS274NGC interpreter, talking to a canon."""

    def __init__(self, canon, *, ini=None, parameter_file: str = "", task: int = 0) -> None:
        self.canon = canon
        canon.linetext = self._get_linetext
        self.ini = ini
        self.parameter_file = parameter_file
        self.task = task
        # where rs274's stray diagnostics go (a standalone run passes stderr)
        self.report: Callable[[str], object] = lambda text: None
        self.parameters = [0.0] * 5602
        self.parameter_assignments: list[tuple[int, float]] = []
        self.named_parameter_assignments: list[tuple[str, float]] = []
        self.sub_context = [Context() for _ in range(11)]
        self.init_named_parameters()
        self.file_lines: list[str] | None = None
        self.file_pos = 0
        self.filename = ""
        self.linetext = ""
        self.blocktext = ""
        self.line_length = 0
        self.sequence_number = 0
        self.percent_flag = False
        self.block = Block()
        self.use_lazy_close = False
        self.lazy_closing = False
        self.qc: list = []  # cutter compensation: moves (and calls) held back
        self._qc_stale_front = None
        self.nurbs_points: list[tuple[float, float, float]] = []
        self.nurbs_order = 3
        self.endpoint = [0.0, 0.0]
        self.endpoint_valid = False
        self._fast = None  # a line taken by the fast path: (motion, ends)
        self._no_fast = False
        self._file_cache: dict[str, list[str]] = {}
        self._compiled: dict = {}  # (line, position) -> compiled value (see compiled.py)
        self._compiler = Compiler(self)

    def _get_linetext(self) -> str:
        return self.linetext

    # ================================================================== init
    def init(self) -> int:
        self.tool_change_at_g30 = 0
        self.tool_change_quill_up = 0
        self.tool_change_with_spindle_on = 0
        self.a_axis_wrapped = self.b_axis_wrapped = self.c_axis_wrapped = 0
        self.random_toolchanger = 0
        self.a_indexer_jnum = self.b_indexer_jnum = self.c_indexer_jnum = -1
        self.return_value = 0.0
        self.value_returned = 0
        self.remap_level = 0
        self.num_spindles = 1
        self.active_spindle = 0
        self.center_arc_radius_tolerance_inch = CENTER_ARC_RADIUS_TOLERANCE_INCH
        self.center_arc_radius_tolerance_mm = CENTER_ARC_RADIUS_TOLERANCE_MM
        self.feature_ini_vars = True
        self.feature_hal_pin_vars = True
        self.feature_retain_g43 = False
        self.feature_oword_n_args = False
        self.feature_no_downcase_oword = False
        self.feature_oword_warnonly = False
        self.orient_offset = 0.0
        self.program_prefix = ""
        self.subroutines: list[str] = []
        self.disable_g92_persistence = 0
        self.disable_fanuc_style_sub = 0
        self.loop_on_main_m99 = False
        self.use_lazy_close = False
        self.on_abort_command = None
        if self.ini is not None:
            self._read_ini(self.ini)
        canon = self.canon
        self.length_units = canon.GET_EXTERNAL_LENGTH_UNIT_TYPE()
        canon.USE_LENGTH_UNITS(self.length_units)
        self.restore_parameters(self.parameter_file or "rs274ngc.var")
        pars = self.parameters
        self.origin_index = int(pars[5220] + 0.0001)
        if self.origin_index < 1 or self.origin_index > 9:
            self.origin_index = 1
            pars[5220] = 1.0
        k = 5200 + self.origin_index * 20
        self.origin_offset = [self.u2p_len(pars[k + 1]), self.u2p_len(pars[k + 2]),
                              self.u2p_len(pars[k + 3]), pars[k + 4], pars[k + 5], pars[k + 6],
                              self.u2p_len(pars[k + 7]), self.u2p_len(pars[k + 8]),
                              self.u2p_len(pars[k + 9])]
        canon.SET_G5X_OFFSET(self.origin_index, *self.origin_offset)
        if self.disable_g92_persistence:
            for i in range(5210, 5220):
                pars[i] = 0.0
        if pars[5210]:
            self.axis_offset = [self.u2p_len(pars[5211]), self.u2p_len(pars[5212]),
                                self.u2p_len(pars[5213]), pars[5214], pars[5215], pars[5216],
                                self.u2p_len(pars[5217]), self.u2p_len(pars[5218]),
                                self.u2p_len(pars[5219])]
        else:
            self.axis_offset = [0.0] * 9
        canon.SET_G92_OFFSET(*self.axis_offset)
        self.rotation_xy = pars[k + 10]
        canon.SET_XY_ROTATION(pars[k + 10])
        canon.SET_FEED_REFERENCE(C.CANON_XYZ)
        self.cutter_comp_side = 0
        self.cutter_comp_radius = 0.0
        self.cutter_comp_orientation = 0
        self.arc_not_allowed = False
        self.cycle_il_flag = False
        self.cycle_il = 0.0
        self.cycle_cc = self.cycle_i = self.cycle_j = self.cycle_k = 0.0
        self.cycle_p = self.cycle_q = self.cycle_r = 0.0
        self.cycle_l = 0
        self.distance_mode = MODE_ABSOLUTE
        self.ijk_distance_mode = MODE_INCREMENTAL
        self.feed_mode = UNITS_PER_MINUTE
        self.filename = ""
        self.file_lines = None
        self.line_length = 0
        self.linetext = ""
        self.motion_mode = G_80
        self.probe_flag = False
        self.toolchange_flag = False
        self.input_flag = False
        self.input_index = -1
        self.input_digital = False
        self.program_x = self.program_y = self.program_z = 0.0
        self.cutter_comp_firstmove = True
        self.retract_mode = R_PLANE
        self.sequence_number = 0
        self.speed_feed_mode = 0
        self.tool_offset = [0.0] * 9
        self.call_level = 0
        self.defining_sub = 0
        self.skipping_o = None
        self.skipping_to_sub = None
        self.skipping_start = 0
        self.sub_name = None
        self.doing_continue = 0
        self.doing_break = 0
        self.executed_if = 0
        self.test_value = 0.0
        self.offset_map: dict = {}
        self.lathe_diameter_mode = False
        self.mdi_interrupt = False
        self.selected_tool = 0
        self.selected_pocket = 0
        self.parameters[5599] = 1.0
        self._readers = self._make_readers(canon.GET_EXTERNAL_AXIS_MASK())
        self.synch()
        self.init_tool_parameters()
        return INTERP_OK

    def _read_ini(self, ini) -> None:
        def get_int(section: str, key: str, default: int) -> int:
            value = ini.find(section, key)
            if value is None:
                return default
            try:
                return int(float(value.split()[0]))
            except (ValueError, IndexError):
                return default

        def get_bool(section: str, key: str, default: bool) -> bool:
            value = ini.find(section, key)
            if value is None:
                return default
            word = value.strip().lower()
            if word in ("1", "true", "yes", "on"):
                return True
            if word in ("0", "false", "no", "off"):
                return False
            return default

        self.tool_change_at_g30 = get_int("EMCIO", "TOOL_CHANGE_AT_G30", 0)
        self.tool_change_quill_up = get_int("EMCIO", "TOOL_CHANGE_QUILL_UP", 0)
        self.tool_change_with_spindle_on = get_int("EMCIO", "TOOL_CHANGE_WITH_SPINDLE_ON", 0)
        self.a_axis_wrapped = get_int("AXIS_A", "WRAPPED_ROTARY", 0)
        self.b_axis_wrapped = get_int("AXIS_B", "WRAPPED_ROTARY", 0)
        self.c_axis_wrapped = get_int("AXIS_C", "WRAPPED_ROTARY", 0)
        self.random_toolchanger = get_int("EMCIO", "RANDOM_TOOLCHANGER", 0)
        self.num_spindles = get_int("TRAJ", "SPINDLES", 1)
        self.feature_ini_vars = get_bool("RS274NGC", "INI_VARS", True)
        self.feature_hal_pin_vars = get_bool("RS274NGC", "HAL_PIN_VARS", True)
        self.feature_retain_g43 = get_bool("RS274NGC", "RETAIN_G43", False)
        self.feature_oword_n_args = get_bool("RS274NGC", "OWORD_NARGS", False)
        self.feature_no_downcase_oword = get_bool("RS274NGC", "NO_DOWNCASE_OWORD", False)
        self.feature_oword_warnonly = get_bool("RS274NGC", "OWORD_WARNONLY", False)
        for axis, attr in (("AXIS_A", "a_indexer_jnum"), ("AXIS_B", "b_indexer_jnum"),
                           ("AXIS_C", "c_indexer_jnum")):
            value = ini.find(axis, "LOCKING_INDEXER_JOINT")
            if value is not None:
                try:
                    setattr(self, attr, int(value.split()[0]))
                except (ValueError, IndexError):
                    setattr(self, attr, 0)
        value = ini.find("RS274NGC", "ORIENT_OFFSET")
        if value is not None:
            with contextlib.suppress(ValueError):
                self.orient_offset = float(value)
        self.use_lazy_close = True
        base = os.path.dirname(os.path.abspath(getattr(ini, "path", "."))) or "."
        prefix = ini.find("DISPLAY", "PROGRAM_PREFIX")
        if prefix is not None:
            self.program_prefix = _realpath(prefix, base)
        path = ini.find("RS274NGC", "SUBROUTINE_PATH")
        if path is not None:
            dirs = []
            for item in path.split(":"):
                if not item:
                    continue
                found = _realpath(item, base)
                if found:
                    dirs.append(found)
                if len(dirs) >= 10:
                    break
            self.subroutines = dirs
        for key, attr, default in (
            ("CENTER_ARC_RADIUS_TOLERANCE_INCH", "center_arc_radius_tolerance_inch",
             CENTER_ARC_RADIUS_TOLERANCE_INCH),
            ("CENTER_ARC_RADIUS_TOLERANCE_MM", "center_arc_radius_tolerance_mm",
             CENTER_ARC_RADIUS_TOLERANCE_MM),
        ):
            value = ini.find("RS274NGC", key)
            if value is not None:
                try:
                    number = float(value)
                    minimum = 0.00004 if key.endswith("INCH") else 0.001
                    if minimum <= number <= default:
                        setattr(self, attr, number)
                except ValueError:
                    pass
        self.disable_g92_persistence = get_int("RS274NGC", "DISABLE_G92_PERSISTENCE", 0)
        self.disable_fanuc_style_sub = get_int("RS274NGC", "DISABLE_FANUC_STYLE_SUB", 0)
        self.on_abort_command = ini.find("RS274NGC", "ON_ABORT_COMMAND")

    # ================================================================= units
    def u2p_len(self, u: float) -> float:
        """USER_TO_PROGRAM_LEN"""
        value = u / self.canon.GET_EXTERNAL_LENGTH_UNITS()
        if self.length_units == C.UNITS_INCHES:
            return value / 25.4
        if self.length_units == C.UNITS_CM:
            return value / 10.0
        return value

    def p2u_len(self, p: float) -> float:
        """PROGRAM_TO_USER_LEN"""
        if self.length_units == C.UNITS_INCHES:
            p = p * 25.4
        elif self.length_units == C.UNITS_CM:
            p = p * 10.0
        return p * self.canon.GET_EXTERNAL_LENGTH_UNITS()

    def _u2p_pose(self, values) -> list[float]:
        u = self.u2p_len
        return [u(values[0]), u(values[1]), u(values[2]), values[3], values[4], values[5],
                u(values[6]), u(values[7]), u(values[8])]

    # ================================================================= synch
    def synch(self) -> int:
        canon = self.canon
        pos = canon.GET_EXTERNAL_POSITION()
        self.current = list(pos)
        self.control_mode = canon.GET_EXTERNAL_MOTION_CONTROL_MODE()
        self.tolerance = canon.GET_EXTERNAL_MOTION_CONTROL_TOLERANCE()
        self.naivecam_tolerance = canon.GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE()
        self.current_pocket = canon.GET_EXTERNAL_TOOL_SLOT()
        self.selected_pocket = canon.GET_EXTERNAL_SELECTED_TOOL_SLOT()
        self.feed_rate = canon.GET_EXTERNAL_FEED_RATE()
        self.flood = canon.GET_EXTERNAL_FLOOD()
        self.length_units = canon.GET_EXTERNAL_LENGTH_UNIT_TYPE()
        self.mist = canon.GET_EXTERNAL_MIST()
        self.plane = canon.GET_EXTERNAL_PLANE()
        self.traverse_rate = canon.GET_EXTERNAL_TRAVERSE_RATE()
        self.feed_override = canon.GET_EXTERNAL_FEED_OVERRIDE_ENABLE()
        self.adaptive_feed = canon.GET_EXTERNAL_ADAPTIVE_FEED_ENABLE()
        self.feed_hold = canon.GET_EXTERNAL_FEED_HOLD_ENABLE()
        self.speed = [canon.GET_EXTERNAL_SPEED(s) for s in range(NUM_SPINDLES_MAX)]
        self.spindle_turning = [canon.GET_EXTERNAL_SPINDLE(s) for s in range(NUM_SPINDLES_MAX)]
        self.speed_override = [canon.GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE(s)
                               for s in range(NUM_SPINDLES_MAX)]
        self.spindle_mode = [CONSTANT_RPM] * NUM_SPINDLES_MAX
        self.save_parameters(self.parameter_file or "rs274ngc.var")
        self.load_tool_table()
        return INTERP_OK

    def refresh_actual_position(self) -> None:
        self.current = list(self.canon.GET_EXTERNAL_POSITION())

    def read_inputs(self) -> None:
        canon = self.canon
        pars = self.parameters
        pars[5600] = canon.GET_EXTERNAL_TC_FAULT()
        pars[5601] = canon.GET_EXTERNAL_TC_REASON()
        if not (self.probe_flag or self.toolchange_flag or self.input_flag):
            return
        if self.probe_flag:
            self.set_probe_data()
            self.probe_flag = False
        if self.toolchange_flag:
            self.refresh_actual_position()
            self.load_tool_table()
            self.toolchange_flag = False
        if self.input_flag:
            if self.input_digital:
                self.parameters[5399] = canon.GET_EXTERNAL_DIGITAL_INPUT(
                    self.input_index, int(self.parameters[5399] != 0.0))
            else:
                self.parameters[5399] = canon.GET_EXTERNAL_ANALOG_INPUT(
                    self.input_index, self.parameters[5399])
            self.input_flag = False

    def set_probe_data(self) -> None:
        self.refresh_actual_position()
        probe = self.canon.GET_EXTERNAL_PROBE_POSITION()
        pars = self.parameters
        for k in range(9):
            value = probe[k]
            if 3 <= k <= 5 and (self.a_axis_wrapped, self.b_axis_wrapped,
                                self.c_axis_wrapped)[k - 3]:
                value = math.fmod(value, 360.0)
                if value < 0:
                    value += 360.0
            pars[5061 + k] = value
        pars[5070] = float(self.canon.GET_EXTERNAL_PROBE_TRIPPED_VALUE())

    # ============================================================ open/close
    def _load_file(self, filename: str) -> list[str] | None:
        try:
            with open(filename, "rb") as handle:
                data = handle.read()
        except OSError:
            return None
        text = data.decode("latin-1")
        lines = [line + "\n" for line in text.split("\n")]
        if lines[-1] == "\n":
            lines.pop()  # the text ended with a newline (or was empty)
        else:
            lines[-1] = lines[-1][:-1]
        return lines

    def open(self, filename: str) -> int:
        if self.use_lazy_close and self.lazy_closing:
            self.use_lazy_close = False
            self.close()
            self.use_lazy_close = True
            self.lazy_closing = False
        if self.file_lines is not None:
            raise InterpError("A file is already open")
        if len(filename) > LINELEN - 1:
            raise InterpError("File name too long")
        lines = self._load_file(filename)
        if lines is None:
            raise InterpError(f"Unable to open file <{filename}>")
        index = 0
        while True:
            if index >= len(lines):
                self.file_lines = lines
                self.file_pos = index
                raise InterpError("File ended with no percent sign")
            line = lines[index]
            if len(line) >= LINELEN - 1:
                self.file_lines = lines
                self.file_pos = index + 1
                raise InterpError("Command too long")
            stripped = line.rstrip()
            index += 1
            if stripped:
                break
        self.file_lines = lines
        if stripped.endswith("%") and not stripped[:-1].strip():
            self.percent_flag = True
            self.sequence_number = 1
            self.file_pos = index
            self.linetext = line.rstrip("\r\n") if len(line) < LINELEN else line
        else:
            self.percent_flag = False
            self.sequence_number = 0
            self.file_pos = 0
        self.filename = filename
        self._file_cache[filename] = lines
        self.reset()
        return INTERP_OK

    def close(self) -> int:
        if self.use_lazy_close:
            self.lazy_closing = True
            return INTERP_OK
        if self.file_lines is not None:
            self.file_lines = None
            self.percent_flag = False
        self.reset()
        return INTERP_OK

    def reset(self) -> int:
        self.call_state = 0
        self.linetext = ""
        self.blocktext = ""
        self.line_length = 0
        self.canon.ON_RESET()
        self.unwind_call()
        return INTERP_OK

    def exit(self) -> int:
        self.save_parameters(self.parameter_file or "rs274ngc.var")
        self.reset()
        return INTERP_OK

    # ================================================================= read
    def read(self, command: str | None = None) -> int:
        try:
            return self._read(command)
        except InterpError:
            self.unwind_call()
            raise

    def _read(self, command: str | None) -> int:
        lines = self.file_lines
        if command is None and lines is not None and self.file_pos < len(lines) and not (
                self.probe_flag or self.toolchange_flag or self.input_flag):
            # the common case first: a plain motion line from the file (see _fast_read)
            raw = lines[self.file_pos]
            if raw[:1] in _FAST_FIRST and len(raw) < LINELEN - 1 and "(" not in raw \
                    and ";" not in raw and "\x00" not in raw:
                text = raw.rstrip(" \t\n\r\f\v")
                line = text.translate(_DOWNCASE)
                match = _FAST_LINE.match(line)
                if match is not None and not self._no_fast and self._fast_read(match):
                    canon = self.canon
                    pars = self.parameters
                    pars[5600] = canon.GET_EXTERNAL_TC_FAULT()
                    pars[5601] = canon.GET_EXTERNAL_TC_REASON()
                    pars[5420:5429] = self.current
                    self.file_pos += 1
                    self.sequence_number += 1
                    self.linetext = text
                    self.blocktext = line
                    self.line_length = len(line)
                    self.parameter_assignments = []
                    return INTERP_OK
        self.read_inputs()
        if command is None and self.file_lines is None:
            return INTERP_FILE_NOT_OPEN
        self.parameters[5420:5429] = self.current
        offset = self.file_pos
        try:
            status = self.read_text(command)
        except InterpError:
            self.block = _EMPTY_BLOCK
            if self.skipping_to_sub:
                self.skipping_to_sub = None
            raise
        if status == INTERP_OK:
            if self.line_length != 0:
                match = _FAST_LINE.match(self.blocktext)
                if match is not None and not self._no_fast and self._fast_read(match):
                    return INTERP_OK
                block = Block()
                block.offset = offset
                self.block = block
                self.parse_line(self.blocktext, block)
            else:
                self.block = _EMPTY_BLOCK
        elif status == INTERP_ENDFILE and self.skipping_o:
            raise InterpError(f"Failed to find sub 'O{self.skipping_o}' before EOF")
        return status

    def read_text(self, command: str | None) -> int:
        if command is None:
            lines = self.file_lines
            pos = self.file_pos
            if pos >= len(lines):
                if self.skipping_to_sub:
                    raise InterpError(
                        f"EOF in file:{self.filename} seeking o-word: o<{self.skipping_to_sub}>"
                        f" from line: {self.skipping_start}"
                    )
                if self.percent_flag:
                    raise InterpError("File ended with no percent sign")
                raise InterpError("File ended with no percent sign or program end")
            raw = lines[pos]
            if "\x00" in raw:
                raw = raw[:raw.index("\x00")]  # C strings end at NUL
            self.file_pos = pos + 1
            self.sequence_number += 1
            if len(raw) >= LINELEN - 1:
                self.linetext = raw[:LINELEN - 1]
                raise InterpError("Command too long")
            raw = raw.rstrip(" \t\n\r\f\v")
            self.linetext = raw
            if "(" in raw or ";" in raw or "\n" in raw:
                line = close_and_downcase(raw)
            else:
                line = raw.translate(_DOWNCASE)
            if line == "%" and self.percent_flag:
                self.canon.FINISH()
                return INTERP_ENDFILE
        else:
            if len(command) >= LINELEN:
                raise InterpError("Command too long")
            self.linetext = command
            line = close_and_downcase(command)
        self.blocktext = line
        self.parameter_assignments = []
        if not line or (line[0] == "/" and self.canon.GET_BLOCK_DELETE()):
            self.line_length = 0
        else:
            self.line_length = len(line)
        return INTERP_OK

    # --------------------------------------------------------------- fast path
    def _fast_read(self, match) -> bool:
        """Take a plain ``[Nn] [G0|G1] X.. Y.. Z..`` line without building a Block.

        Only lines whose outcome is certain go this way (no error possible, no special
        state); everything else takes the general path, so the result is the same.
        """
        if self.skipping_o or self.cutter_comp_side or self.lathe_diameter_mode:
            return False
        g = match.group(2)
        if g is None:
            move = self.motion_mode
            if move != G_0 and move != G_1:
                return False
        else:
            move = G_1 if g == "1" else G_0
        if move == G_1 and (self.feed_mode != UNITS_PER_MINUTE or self.feed_rate == 0.0):
            return False
        words = match.groups()[2:]
        if (words[3] is not None or words[4] is not None or words[5] is not None) and (
                self.a_axis_wrapped or self.b_axis_wrapped or self.c_axis_wrapped
                or self.a_indexer_jnum != -1 or self.b_indexer_jnum != -1
                or self.c_indexer_jnum != -1):
            return False
        ends = list(self.current)
        x, y, z = words[0], words[1], words[2]
        if self.distance_mode == MODE_ABSOLUTE:
            if x is not None:
                ends[0] = float(x)
            if y is not None:
                ends[1] = float(y)
            if z is not None:
                ends[2] = float(z)
            for k in (3, 4, 5):
                if words[k] is not None:
                    ends[k] = float(words[k])
        else:
            for k, word in enumerate(words):
                if word is not None:
                    ends[k] += float(word)
        self._fast = (move, ends)
        return True

    def _fast_execute(self) -> int:
        move, ends = self._fast
        self._fast = None
        self.cycle_il_flag = False
        self.arc_not_allowed = False
        self.motion_mode = move
        if move == G_0:
            self.canon.STRAIGHT_TRAVERSE(self.sequence_number, *ends)
        else:
            self.canon.STRAIGHT_FEED(self.sequence_number, *ends)
        self.current = ends
        return INTERP_OK

    def parse_line(self, line: str, block: Block) -> None:
        self.read_items(block, line)
        if not self.skipping_o:
            self.enhance_block(block)
            self.check_items(block)

    # ================================================================ execute
    def execute(self, command: str | None = None) -> int:
        try:
            return self._execute(command)
        except InterpError:
            self.unwind_call()
            raise

    def _execute(self, command: str | None) -> int:
        mdi_mode = False
        if command is not None:
            mdi_mode = True
            status = self.read(command)
            if status != INTERP_OK:
                return status
        if self._fast is not None:
            return self._fast_execute()
        block = self.block
        if block.o_name is not None or self.mdi_interrupt:
            status = self.convert_control_functions(block)
            if status != INTERP_OK:
                return status
            if self.mdi_interrupt:
                self.mdi_interrupt = False
                mdi_mode = True
            while mdi_mode and self.call_level:
                status = self.read()
                status = self.execute()
                if status != INTERP_OK:
                    if status == INTERP_EXECUTE_FINISH:
                        self.mdi_interrupt = True
                    return status
            self.mdi_interrupt = False
            if mdi_mode:
                self.canon.FINISH()
                self.offset_map.clear()
            return INTERP_OK
        if self.skipping_o:
            return INTERP_OK
        pars = self.parameters
        for index, value in self.parameter_assignments:
            pars[index] = value
        if self.named_parameter_assignments:
            for name, value in self.named_parameter_assignments:
                self.store_named_param(name, value)
            self.named_parameter_assignments = []
        if self.line_length != 0:
            return self.execute_block(block)
        return INTERP_OK

    # ======================================================= block checking
    def enhance_block(self, block: Block) -> None:
        if block.radius_flag or block.theta_flag:
            if "x" not in self._readers or "y" not in self._readers:
                raise InterpError("Cannot use polar coordinate on a machine lacking X or Y axes")
            if self.plane != C.PLANE_XY:
                raise InterpError("Cannot use polar coordinate except in G17 plane")
            if block.x_flag:
                raise InterpError("Cannot specify both polar coordinate and X word")
            if block.y_flag:
                raise InterpError("Cannot specify both polar coordinate and Y word")
        axis_flag = (block.x_flag or block.y_flag or block.z_flag or block.a_flag
                     or block.b_flag or block.c_flag or block.u_flag or block.v_flag
                     or block.w_flag)
        polar_flag = block.radius_flag or block.theta_flag
        ijk_flag = block.i_flag or block.j_flag or block.k_flag
        mode0 = block.g_modes[GM_MODAL_0]
        mode1 = block.g_modes[GM_MOTION]
        covets = mode0 in (G_10, G_28, G_30, G_52, G_92)
        if mode1 != -1:
            if mode1 == G_80:
                if (polar_flag or axis_flag) and not covets:
                    raise InterpError("Cannot use axis values with g80")
                if polar_flag and mode0 == G_92:
                    raise InterpError("Polar coordinates can only be used for motion")
                if not axis_flag and mode0 in (G_52, G_92):
                    raise InterpError("All axes missing with g52 or g92")
            else:
                if covets:
                    raise InterpError("Cannot use two g codes that both use axis values")
                if (not axis_flag and not polar_flag and mode1 not in (
                        G_0, G_1, G_2, G_3, G_5_2, G_70, G_71, G_71_1, G_71_2, G_72,
                        G_72_1, G_72_2)):
                    raise InterpError("All axes missing with motion code")
            block.motion_to_be = mode1
        elif covets:
            if polar_flag and mode0 == G_92:
                raise InterpError("Polar coordinates can only be used for motion")
            if not axis_flag and mode0 in (G_52, G_92):
                raise InterpError("All axes missing with g52 or g92")
        elif axis_flag or polar_flag:
            tlo = block.g_modes[GM_TOOL_LENGTH_OFFSET]
            if self.motion_mode in (-1, G_80) and tlo != G_43_1 and tlo != G_43_2:
                raise InterpError("Cannot use axis values without a g code that uses them")
            if tlo != G_43_1:
                block.motion_to_be = self.motion_mode
        elif ijk_flag and self.motion_mode in (G_2, G_3):
            block.motion_to_be = self.motion_mode
        if polar_flag and block.motion_to_be == -1:
            raise InterpError("Polar coordinates can only be used for motion")

    def check_items(self, block: Block) -> None:
        self.check_g_codes(block)
        if block.m_count > MAX_EMS:
            raise InterpError("Too many m codes on line")
        self.check_other_codes(block)

    def check_g_codes(self, block: Block) -> None:
        mode0 = block.g_modes[GM_MODAL_0]
        mode1 = block.g_modes[GM_MOTION]
        if mode0 == -1:
            return
        if mode0 == G_4:
            if block.p_number == -1.0:
                raise InterpError("Dwell time missing with g4")
            if mode1 in (G_2, G_3):
                raise InterpError("G4 not allowed with G2 or G3 because they both use P")
        elif mode0 == G_10:
            p = block.p_number
            p_int = int(p + 0.5) if p >= 0 else int(p - 0.5)
            lnum = block.l_number
            if lnum not in (0, 1, 2, 10, 11, 20):
                raise InterpError("Line with G10 does not have L0, L1, L10, L11, L2, or L20")
            if (p + 0.0001) - p_int > 0.0002:
                raise InterpError("P value not an integer with G10")
            if lnum in (2, 20) and (p_int < 0 or p_int > 9):
                raise InterpError(f"P value out of range (0-9) with G10 L{lnum}")
            if lnum in (1, 10, 11) and p_int < 1:
                raise InterpError(f"P value out of range with G10 L{lnum}")
        elif mode0 == G_5_3:
            if mode1 != G_5_2 and mode1 != -1:
                raise InterpError(
                    "Between G5.2 and G5.3 codes, only additional G5.2 codes are allowed.")
        elif mode0 == G_53:
            if block.motion_to_be not in (G_0, G_1):
                raise InterpError("Must use g0 or g1 with g53")
            dm = block.g_modes[GM_DISTANCE_MODE]
            if dm == G_91 or (dm != G_90 and self.distance_mode == MODE_INCREMENTAL):
                raise InterpError("Cannot use g53 incremental")

    def check_other_codes(self, block: Block) -> None:
        motion = block.motion_to_be
        g_modes = block.g_modes
        m_modes = block.m_modes
        cycle = is_a_cycle(motion)
        if block.a_flag and cycle:
            raise InterpError("Cannot put an a in canned cycle")
        if block.b_flag and cycle:
            raise InterpError("Cannot put a b in canned cycle")
        if block.c_flag and cycle:
            raise InterpError("Cannot put a c in canned cycle")
        g7x = motion in (G_70, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2)
        if block.d_flag and not (
                g_modes[7] in (G_41, G_42, G_41_1, G_42_1) or g7x or g_modes[14] == G_96):
            raise InterpError(
                "D word with no G41, G41.1, G42, G42.1, G71, G71.1, G71.2 or G96 to use it")
        if block.dollar_flag and not (
                motion in (G_76, G_33, G_33_1, G_95, G_96, G_97) or m_modes[7] in (3, 4, 5, 19)
                or m_modes[9] == 51 or block.s_flag):
            raise InterpError(
                "$ (spindle selection) word with no M3, M4, M5, M19, M51, G33, G33.1, G76, G95,"
                " G96 or G97 to use it")
        if block.e_flag and not (motion in (G_76, G_33, G_33_1, G_70)
                                 or m_modes[5] in (66, 67, 68)):
            raise InterpError("E word with no G70, G76, M66, M67 or M68 to use it")
        if block.h_flag and not (g_modes[GM_TOOL_LENGTH_OFFSET] in (G_43, G_43_2)
                                 or motion == G_76):
            raise InterpError("H word with no G43 or G76 to use it")
        if block.i_flag and not (
                motion in (G_2, G_3, 50, 51, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2, G_76,
                           G_87, G_33_1) or g_modes[GM_MODAL_0] == G_10):
            raise InterpError("I word with no G2, G3, G5, G5.1, G10, G33.1, G76, or G87 to use it")
        if block.j_flag and not (motion in (G_2, G_3, 50, 51, G_76, G_87)
                                 or g_modes[GM_MODAL_0] == G_10):
            raise InterpError("J word with no G2, G3, G5, G5.1, G10, G76 or G87 to use it")
        if block.k_flag and motion not in (G_2, G_3, G_33, G_33_1, G_76, G_87):
            raise InterpError("K word with no G2, G3, G33, G33.1, G76, or G87 to use it")
        if block.l_number != -1 and not (
                G_81 <= motion <= G_89 or motion in (G_76, G_5_2, G_73)
                or g_modes[GM_MODAL_0] == G_10
                or g_modes[GM_CUTTER_COMP] in (G_41, G_41_1, G_42, G_42_1)
                or m_modes[5] == 66 or block.o_type == M_98):
            raise InterpError("L word with no G10, cutter compensation, canned cycle, "
                              "digital/analog input, M98 or NURBS code")
        if block.p_flag:
            if not (g_modes[GM_MODAL_0] in (G_10, G_4) or g_modes[GM_CONTROL_MODE] == G_64
                    or motion in (G_76, G_82, G_86, G_88, G_89, 50, G_5_2, G_70, G_2, G_3,
                                  G_74, G_84)
                    or m_modes[9] in (50, 51, 52, 53) or m_modes[5] in (62, 63, 64, 65, 66)
                    or m_modes[7] == 19 or block.user_m == 1 or block.o_type == M_98):
                raise InterpError(
                    "P word with no G2 G3 G4 G10 G64 G5 G5.2 G76 G82 G86 G88 G89"
                    " or M50 M51 M52 M53 M62 M63 M64 M65 M66 M98 or user M code to use it")
            p_value = _round_to_int(block.p_number)
            if (motion in (G_2, G_3) or m_modes[7] == 19) and abs(p_value - block.p_number) > 0.001:
                raise InterpError("P value not an integer with M19 G2 or G3")
            if m_modes[7] == 19 and (p_value > 2 or p_value < 0):
                raise InterpError("P value must be 0,1,or 2 with M19")
            if motion in (G_2, G_3) and p_value < 1:
                raise InterpError("P value should be 1 or greater with G2 or G3")
        if block.q_number != -1.0 and not (
                motion in (G_83, G_73, 50, G_76, G_70, G_71, G_71_1, G_71_2, G_72, G_72_1,
                           G_72_2)
                or block.user_m == 1 or m_modes[5] in (66, 67, 68)
                or g_modes[GM_MODAL_0] == G_10 or m_modes[6] == 61
                or g_modes[GM_CONTROL_MODE] == G_64 or m_modes[7] == 19):
            raise InterpError("Q word with no G5, G10, G64, G73, G76, G83, M19, M66, M67, M68 "
                              "or user M code that uses it")
        if block.r_flag:
            if not (motion in (G_2, G_3, G_76, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2,
                               G_73, G_74) or G_81 <= motion <= G_89
                    or g_modes[GM_CUTTER_COMP] in (G_41_1, G_42_1)
                    or g_modes[GM_MODAL_0] == G_10 or m_modes[7] == 19):
                raise InterpError("R word with no g code that uses it")
            if m_modes[7] == 19 and (block.r_number > 360.0 or block.r_number < 0.0):
                raise InterpError("R value must be within 0..360 with M19")
        if not block.s_flag and g_modes[GM_SPINDLE_MODE] == G_96:
            raise InterpError("S word missing with G96")
        if motion in (G_33, G_33_1):
            if not block.k_flag:
                raise InterpError("K word missing with g33/g33.1")
            if block.f_flag:
                raise InterpError("F word used with a g33/g33.1")
        if motion == G_76:
            if block.p_number == -1:
                raise InterpError("P word missing with G76")
            if not block.i_flag or not block.j_flag or not block.k_flag:
                raise InterpError("I J or K words missing with G76")

    # ====================================================== order of execution
    def _enq(self, name: str, *args) -> None:
        """enqueue_*: immediate unless cutter compensation holds moves back."""
        if not self.qc:
            getattr(self.canon, name)(*args)
        else:
            self.qc.append([QOTHER, name, args])

    def execute_block(self, block: Block) -> int:
        block.line_number = self.sequence_number
        if block.comment:
            self.convert_comment(block.comment)
        if block.g_modes[GM_SPINDLE_MODE] != -1:
            self.active_spindle = 0
            if block.dollar_flag:
                if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                    raise InterpError("Invalid spindle ($) number in Spindle Mode command")
                self.active_spindle = int(block.dollar_number)
            self.convert_spindle_mode(self.active_spindle, block)
        if block.g_modes[GM_FEED_MODE] != -1:
            self.active_spindle = 0
            if block.dollar_flag:
                if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                    raise InterpError("Invalid spindle ($) number in Spindle Feed command")
                self.active_spindle = int(block.dollar_number)
            self.convert_feed_mode(block.g_modes[GM_FEED_MODE])
        if block.f_flag and self.feed_mode != INVERSE_TIME:
            self.feed_rate = block.f_number
            self._enq("SET_FEED_RATE", block.f_number)
        if block.s_flag:
            if block.dollar_flag:
                if block.dollar_number < -1 or block.dollar_number >= self.num_spindles:
                    raise InterpError("Invalid spindle ($) number in Spindle speed command")
                if block.dollar_number == -1:
                    for i in range(self.num_spindles):
                        self.convert_speed(i, block)
                else:
                    self.convert_speed(int(block.dollar_number), block)
            else:
                self.convert_speed(0, block)
        if block.t_flag:
            self.convert_tool_select(block)
        self.convert_m(block)
        self.convert_g(block)
        if block.m_modes[4] != -1:
            status = self.convert_stop(block)
            if status == INTERP_EXIT:
                return INTERP_EXIT
            if status != INTERP_OK:
                return status
        if self.probe_flag or self.input_flag or self.toolchange_flag:
            return INTERP_EXECUTE_FINISH
        return INTERP_OK

    # ============================================================ comments
    def convert_comment(self, comment: str) -> int:
        m = 0
        while m < len(comment) and comment[m] in " \t\n\r\f\v":
            m += 1
        start = m
        body = comment[start:]
        lc = body[:256].lower()
        canon = self.canon
        if lc.startswith("msg,"):
            canon.MESSAGE(body[4:])
        elif lc.startswith("debug,"):
            expanded = self.convert_param_comment(body[6:])
            if self.parameters[5599] > 0.0:
                canon.MESSAGE(expanded)
        elif lc.startswith("print,"):
            canon.PRINT_LINE(self.convert_param_comment(body[6:]))
        elif lc.startswith("log,"):
            canon.LOG(self.convert_param_comment(body[4:]))
        elif lc.startswith("logopen,"):
            canon.LOGOPEN(body[8:])
        elif lc.startswith("logappend,"):
            canon.LOGAPPEND(body[10:])
        elif lc.startswith("py,") or lc.startswith("pyrun,") or lc.startswith("pyreload"):
            raise InterpError("Python plugin not available")
        elif lc.startswith("abort,"):
            raise InterpError(self.convert_param_comment(body[6:]))
        elif lc == "logclose":
            canon.LOGCLOSE()
        else:
            self._enq("COMMENT", body)
        return INTERP_OK

    def convert_param_comment(self, comment: str) -> str:
        """Expand #n, #<name> and %d/%f/%.Nf in (DEBUG,) (PRINT,) (LOG,) (ABORT,) text.

        LinuxCNC ignores an expansion error and uses its buffer as it stands: the text
        expanded so far followed by the rest of the previous expansion; so do we.
        """
        out: list[str] = []
        try:
            self._expand_param_comment(comment, out)
        except InterpError:
            done = "".join(out)
            self._last_expansion = done + self._last_expansion[len(done):]
            return self._last_expansion
        self._last_expansion = "".join(out)
        return self._last_expansion

    _last_expansion = ""

    def _expand_param_comment(self, comment: str, out: list[str]) -> None:
        fmt = "%lf"
        i = 0
        n = len(comment)
        while i < n:
            ch = comment[i]
            if ch == "%":
                i += 1
                nxt = comment[i] if i < n else ""
                if nxt == "d":
                    i += 1
                    fmt = "%.0f"
                elif nxt == "f":
                    i += 1
                    fmt = "%.4f"
                elif nxt == ".":
                    i += 1
                    if i < n and comment[i].isdigit():
                        if i + 1 < n and comment[i + 1] == "f":
                            fmt = "%." + comment[i] + "f"
                            i += 2
                        else:
                            out.append(".")
                    else:
                        out.append(".")
                else:
                    out.append("%")
            elif ch == "#":
                i += 1
                if i >= n:
                    raise InterpError("Named parameter not terminated")
                found = False
                value = 0.0
                if comment[i].isdigit():
                    j = i
                    while j < n and comment[j].isdigit():
                        j += 1
                    number = int(comment[i:j])
                    i = j
                    if 0 <= number < 5602:
                        value = self.parameters[number]
                        found = True
                elif comment[i] == "<":
                    i += 1
                    if i >= n:
                        raise InterpError("Named parameter not terminated")
                    name = []
                    while i < n and comment[i] != ")" and comment[i] != ">":
                        if comment[i].isspace():
                            i += 1
                            continue
                        c = comment[i]
                        name.append(c if self.feature_no_downcase_oword else c.lower())
                        i += 1
                    if i >= n or comment[i] != ">":
                        raise InterpError("Named parameter not terminated")
                    i += 1
                    exists, value = self.find_named_param("".join(name))
                    found = bool(exists)
                else:
                    out.append("#")
                    continue
                if found:
                    pvalue = 0.0 if abs(value) < 0.0001 else value
                    text = _c_format(fmt, pvalue)
                    if len(text) >= 30:
                        text = "######"
                else:
                    text = "######"
                out.append(text)
            else:
                out.append(ch)
                i += 1

    # ========================================================= mode changes
    def convert_spindle_mode(self, dollar: int, block: Block) -> None:
        for s in range(self.num_spindles):
            if dollar == -1 or s == dollar:
                if block.g_modes[14] == G_97:
                    self.spindle_mode[s] = CONSTANT_RPM
                    self._enq("SET_SPINDLE_MODE", s, 0.0)
                else:
                    self.spindle_mode[s] = CONSTANT_SURFACE
                    self._enq("SET_SPINDLE_MODE", s,
                              abs(block.d_number_float) if block.d_flag else 1e30)

    def convert_feed_mode(self, g_code: int) -> None:
        if g_code == G_93:
            self._enq("COMMENT", "interpreter: feed mode set to inverse time")
            self.feed_mode = INVERSE_TIME
            self._enq("SET_FEED_MODE", 0, 0)
        elif g_code == G_94:
            self._enq("COMMENT", "interpreter: feed mode set to units per minute")
            self.feed_mode = UNITS_PER_MINUTE
            self._enq("SET_FEED_MODE", 0, 0)
            self.feed_rate = 0.0
            self._enq("SET_FEED_RATE", 0.0)
        elif g_code == G_95:
            self._enq("COMMENT", "interpreter: feed mode set to units per revolution")
            self.feed_mode = UNITS_PER_REVOLUTION
            self._enq("SET_FEED_MODE", self.active_spindle, 1)
            self.feed_rate = 0.0
            self._enq("SET_FEED_RATE", 0.0)

    def convert_speed(self, spindle: int, block: Block) -> None:
        if 0 <= spindle < self.num_spindles:
            self._enq("SET_SPINDLE_SPEED", spindle, block.s_number)
            self.speed[spindle] = block.s_number

    # ============================================================== M codes
    def convert_m(self, block: Block) -> None:
        canon = self.canon
        m5 = block.m_modes[5]
        if m5 != -1:
            if m5 in (62, 63, 64, 65):
                if self.cutter_comp_side:
                    raise InterpError({
                        62: "Cannot set motion output with cutter radius compensation on",
                        63: "Cannot set motion digital output with cutter radius compensation on",
                        64: "Cannot set auxiliary digital output with cutter radius compensation"
                            " on",
                        65: "Cannot set auxiliary digital output with cutter radius compensation"
                            " on"}[m5])
                if not block.p_flag:
                    raise InterpError(f"No valid P word with M{m5}")
                index = _round_to_int(block.p_number)
                {62: canon.SET_MOTION_OUTPUT_BIT, 63: canon.CLEAR_MOTION_OUTPUT_BIT,
                 64: canon.SET_AUX_OUTPUT_BIT, 65: canon.CLEAR_AUX_OUTPUT_BIT}[m5](index)
            elif m5 == 66:
                self.convert_m66(block)
            elif m5 in (67, 68):
                if self.cutter_comp_side:
                    raise InterpError(
                        "Cannot set motion analog output with cutter radius compensation on"
                        if m5 == 67 else
                        "Cannot set auxiliary analog output with cutter radius compensation on")
                if not block.e_flag or _round_to_int(block.e_number) < 0:
                    raise InterpError(f"Invalid analog index with M{m5}")
                func = canon.SET_MOTION_OUTPUT_VALUE if m5 == 67 else canon.SET_AUX_OUTPUT_VALUE
                func(_round_to_int(block.e_number), block.q_number)
        m6 = block.m_modes[6]
        if m6 == 6:
            self.convert_tool_change()
        elif m6 == 61:
            toolno = _round_to_int(block.q_number)
            if toolno < 0:
                raise InterpError("Need non-negative Q-word to specify tool number with M61")
            idx = self.find_tool_index(toolno)
            self.current_pocket = idx
            self.toolchange_flag = True
            canon.CHANGE_TOOL_NUMBER(self.current_pocket)
            self.set_tool_parameters()
        m7 = block.m_modes[7]
        if m7 in (3, 4, 5):
            if block.dollar_flag:
                if block.dollar_number >= self.num_spindles or block.dollar_number < -1:
                    raise InterpError(
                        f"Spindle ($) number out of range in M{m7} Command\nnum_spindles "
                        f"={self.num_spindles}. $={int(block.dollar_number)}\n")
                spindles = (range(self.num_spindles) if block.dollar_number == -1
                            else [int(block.dollar_number)])
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
            if block.dollar_flag and (block.dollar_number >= self.num_spindles
                                      or block.dollar_number < 0):
                raise InterpError("Spindle ($) number out of range in M19 Command")
            spindle = int(block.dollar_number) if block.dollar_flag else 0
            if block.r_flag or block.p_flag:
                self._enq("ORIENT_SPINDLE", spindle,
                          (block.r_number + self.orient_offset) if block.r_flag
                          else self.orient_offset,
                          int(block.p_number) if block.p_flag else 0)
            if block.q_flag:
                if block.q_number <= 0.0:
                    raise InterpError("Q word with M19 requires a value > 0")
                self._enq("WAIT_SPINDLE_ORIENT_COMPLETE", spindle, block.q_number)
        elif m7 in (70, 71, 72, 73):
            self.convert_context(m7)
        m8 = block.m_modes[8]
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
        m9 = block.m_modes[9]
        if m9 in (48, 49):
            if self.cutter_comp_side:
                raise InterpError(
                    f"Cannot {'enable' if m9 == 48 else 'disable'} overrides with cutter "
                    "radius compensation on")
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
                    "compensation on")
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
        m10 = block.m_modes[10]
        if m10 != -1 and not canon.USER_DEFINED_FUNCTION(m10, block.p_number,
                                                         block.q_number):
            raise InterpError(f"Unknown m code used: M{m10}")

    def convert_m66(self, block: Block) -> None:
        if block.p_flag and block.e_flag:
            raise InterpError("Invalid to select both a digital and an analog input with M66")
        if block.q_number <= 0 and block.l_flag and _round_to_int(block.l_number) > 0:
            raise InterpError("Zero timeout with wait type != immediate return")
        if block.e_flag and block.l_flag and _round_to_int(block.l_number) != 0:
            raise InterpError("Can't select analog input with wait type != immediate return")
        if ((block.p_flag and _round_to_int(block.p_number) < 0)
                or (block.e_flag and _round_to_int(block.e_number) < 0)
                or (not block.p_flag and not block.e_flag)):
            raise InterpError("Need to have either a valid P or a valid E word with M66")
        if block.p_flag:
            wait_type = _round_to_int(block.l_number) if block.l_flag else 0
            timeout = block.q_number if block.q_number > 0 else 0.0
            if self.cutter_comp_side:
                raise InterpError(
                    "Cannot wait for digital input with cutter radius compensation on")
            ret = self.canon.WAIT(_round_to_int(block.p_number), C.DIGITAL_INPUT, wait_type,
                                  timeout)
            if ret == -1:
                raise InterpError("Digital input selected out of bounds")
            if ret == 0:
                self.input_flag = True
                self.input_index = _round_to_int(block.p_number)
                self.input_digital = True
        elif _round_to_int(block.e_number) >= 0:
            if self.cutter_comp_side:
                raise InterpError(
                    "Cannot wait for analog input with cutter radius compensation on")
            ret = self.canon.WAIT(_round_to_int(block.e_number), C.ANALOG_INPUT, 0, 0)
            if ret == -1:
                raise InterpError("Analog input selected out of bounds")
            if ret == 0:
                self.input_flag = True
                self.input_index = _round_to_int(block.e_number)
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
                    "Cannot restore context from invalid stack frame - missing M70/M73?")
            self.restore_settings(self.call_level)

    def active_g_codes(self) -> list[int]:
        plane = {C.PLANE_XY: G_17, C.PLANE_XZ: G_18, C.PLANE_YZ: G_19, C.PLANE_UV: G_17_1,
                 C.PLANE_UW: G_18_1, C.PLANE_VW: G_19_1}.get(self.plane, 0)
        o = self.origin_index
        return [
            self.sequence_number, self.motion_mode, -1, plane,
            G_42 if self.cutter_comp_side == RIGHT else G_41 if self.cutter_comp_side == LEFT
            else G_40,
            G_20 if self.length_units == C.UNITS_INCHES else G_21,
            G_90 if self.distance_mode == MODE_ABSOLUTE else G_91,
            G_93 if self.feed_mode == INVERSE_TIME else G_94
            if self.feed_mode == UNITS_PER_MINUTE else G_95,
            530 + 10 * o if o < 7 else 584 + o,
            G_43 if any(self.tool_offset) else G_49,
            G_98 if self.retract_mode == OLD_Z else G_99,
            G_64 if self.control_mode == C.CONTINUOUS else G_61
            if self.control_mode == C.EXACT_PATH else G_61_1,
            -1,
            G_97 if self.spindle_mode[0] == CONSTANT_RPM else G_96,
            G_90_1 if self.ijk_distance_mode == MODE_ABSOLUTE else G_91_1,
            G_7 if self.lathe_diameter_mode else G_8,
            G_92_3 if self.parameters[5210] else G_92_2,
        ]

    def active_m_codes(self) -> list[int]:
        turning = self.spindle_turning[0]
        return [
            self.sequence_number, -1,
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
        return [float(self.sequence_number), self.feed_rate, self.speed[0], self.tolerance,
                self.naivecam_tolerance]

    def save_settings(self) -> None:
        frame = self.sub_context[self.call_level]
        frame.saved_g_codes = self.active_g_codes()
        frame.saved_m_codes = self.active_m_codes()
        frame.saved_settings = self.active_settings()

    def restore_settings(self, from_level: int) -> None:
        frame = self.sub_context[from_level]
        current_g = self.active_g_codes()
        if current_g[5] != frame.saved_g_codes[5]:
            self._execute_restore(f"G{frame.saved_g_codes[5] // 10}",
                                  "M7x: restore_settings G20/G21 failed: ''")
            current_g = self.active_g_codes()
        cmd = _gen_settings(current_g, frame.saved_g_codes, self.active_settings(),
                            frame.saved_settings)
        cmd += _gen_m_codes(self.active_m_codes(), frame.saved_m_codes)
        for part in cmd.split("\n"):
            if part:
                self._execute_restore(part, None)

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

    # ============================================================== G codes
    def convert_g(self, block: Block) -> None:
        g = block.g_modes
        if g[GM_MODAL_0] == G_4:
            self._enq("DWELL", block.p_number)
        if g[GM_SET_PLANE] != -1:
            self.convert_set_plane(g[GM_SET_PLANE])
        if g[GM_LENGTH_UNITS] != -1:
            self.convert_length_units(g[GM_LENGTH_UNITS])
        if g[GM_LATHE_DIAMETER_MODE] != -1:
            self.convert_lathe_diameter_mode(g[GM_LATHE_DIAMETER_MODE], block)
        if g[GM_CUTTER_COMP] != -1:
            self.convert_cutter_compensation(g[GM_CUTTER_COMP], block)
        if g[GM_TOOL_LENGTH_OFFSET] != -1:
            self.convert_tool_length_offset(g[GM_TOOL_LENGTH_OFFSET], block)
        if g[GM_COORD_SYSTEM] != -1:
            self.convert_coordinate_system(g[GM_COORD_SYSTEM])
        if g[GM_CONTROL_MODE] != -1:
            self.convert_control_mode(g[GM_CONTROL_MODE], block.p_number, block.q_number)
        if g[GM_DISTANCE_MODE] != -1:
            mode = MODE_ABSOLUTE if g[GM_DISTANCE_MODE] == G_90 else MODE_INCREMENTAL
            if mode != self.distance_mode:
                self._enq("COMMENT", "interpreter: distance mode changed to "
                          + ("absolute" if mode == MODE_ABSOLUTE else "incremental"))
                self.distance_mode = mode
        if g[GM_IJK_DISTANCE_MODE] != -1:
            mode = MODE_ABSOLUTE if g[GM_IJK_DISTANCE_MODE] == G_90_1 else MODE_INCREMENTAL
            if mode != self.ijk_distance_mode:
                self._enq("COMMENT", "interpreter: IJK distance mode changed to "
                          + ("absolute" if mode == MODE_ABSOLUTE else "incremental"))
                self.ijk_distance_mode = mode
        if g[GM_RETRACT_MODE] != -1:
            if self.cutter_comp_side:
                raise InterpError("Cannot change retract mode with cutter radius compensation on")
            if g[GM_RETRACT_MODE] == G_98:
                self._enq("COMMENT", "interpreter: retract mode set to old_z")
                self.retract_mode = OLD_Z
            else:
                self._enq("COMMENT", "interpreter: retract mode set to r_plane")
                self.retract_mode = R_PLANE
        if g[GM_MODAL_0] != -1:
            self.convert_modal_0(g[GM_MODAL_0], block)
        if g[GM_G92_IS_APPLIED] != -1:
            with contextlib.suppress(InterpError):  # LinuxCNC ignores this status
                self.convert_axis_offsets(g[GM_G92_IS_APPLIED], block)
        if block.motion_to_be != -1:
            self.convert_motion(block.motion_to_be, block)

    def convert_set_plane(self, g_code: int) -> None:
        side = self.cutter_comp_side
        if side:
            if ((g_code == G_17 and self.plane != C.PLANE_XY)
                    or (g_code == G_18 and self.plane != C.PLANE_XZ)
                    or (g_code == G_19 and self.plane != C.PLANE_YZ)):
                raise InterpError("Cannot change planes with cutter radius compensation on")
            if g_code == G_19:
                raise InterpError("Cutter radius compensation allowed only in XY, XZ planes")
        plane = {G_17: C.PLANE_XY, G_18: C.PLANE_XZ, G_19: C.PLANE_YZ, G_17_1: C.PLANE_UV,
                 G_18_1: C.PLANE_UW, G_19_1: C.PLANE_VW}[g_code]
        self.canon.SELECT_PLANE(plane)
        self.plane = plane

    def convert_length_units(self, g_code: int) -> None:
        canon = self.canon
        if g_code == G_20:
            canon.USE_LENGTH_UNITS(C.UNITS_INCHES)
            if self.length_units == C.UNITS_INCHES:
                return
            self.length_units = C.UNITS_INCHES
            factor = INCH_PER_MM
        else:
            canon.USE_LENGTH_UNITS(C.UNITS_MM)
            if self.length_units == C.UNITS_MM:
                return
            self.length_units = C.UNITS_MM
            factor = MM_PER_INCH
        cur = self.current
        for k in (0, 1, 2, 6, 7, 8):
            cur[k] = cur[k] * factor
            self.axis_offset[k] = self.axis_offset[k] * factor
            self.origin_offset[k] = self.origin_offset[k] * factor
        self.program_x *= factor
        self.program_y *= factor
        self.program_z *= factor
        self.qc_scale(factor)
        self.cutter_comp_radius *= factor
        self.tool_offset = list(canon.GET_EXTERNAL_TOOL_LENGTH_OFFSET())
        self.feed_rate = canon.GET_EXTERNAL_FEED_RATE()
        self.tolerance = canon.GET_EXTERNAL_MOTION_CONTROL_TOLERANCE()
        self.naivecam_tolerance = canon.GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE()

    def convert_lathe_diameter_mode(self, g_code: int, block: Block) -> None:
        if g_code == G_7:
            if not self.lathe_diameter_mode:
                if block.x_flag:
                    block.x_number /= 2
                if block.motion_to_be == G_76:
                    block.i_number /= 2
                    block.j_number /= 2
                    block.k_number /= 2
                self.canon.COMMENT("interpreter: Lathe diameter mode changed to diameter")
                self.lathe_diameter_mode = True
        elif g_code == G_8 and self.lathe_diameter_mode:
            if block.x_flag:
                block.x_number *= 2
            if block.motion_to_be == G_76:
                block.i_number *= 2
                block.j_number *= 2
                block.k_number *= 2
            self.canon.COMMENT("interpreter: Lathe diameter mode changed to radius")
            self.lathe_diameter_mode = False

    def convert_cutter_compensation(self, g_code: int, block: Block) -> None:
        if g_code == G_40:
            self.convert_cutter_compensation_off()
        elif g_code in (G_41, G_41_1):
            self.convert_cutter_compensation_on(LEFT, block)
        else:
            self.convert_cutter_compensation_on(RIGHT, block)

    def convert_cutter_compensation_off(self) -> None:
        self._enq("COMMENT", "interpreter: cutter radius compensation off")
        if self.cutter_comp_side and self.cutter_comp_radius > 0.0 and \
                not self.cutter_comp_firstmove:
            cx, cy, _ = self.comp_get_current()
            self.move_endpoint_and_flush(cx, cy)
            self.dequeue_canons()
            self.current[0] = self.program_x
            self.current[1] = self.program_y
            self.current[2] = self.program_z
            self.arc_not_allowed = True
        self.cutter_comp_side = 0
        self.cutter_comp_firstmove = True

    def convert_cutter_compensation_on(self, side: int, block: Block) -> None:
        if self.plane not in (C.PLANE_XY, C.PLANE_XZ):
            raise InterpError("Cutter radius compensation allowed only in XY, XZ planes")
        if self.cutter_comp_side:
            raise InterpError("Cannot turn cutter radius comp on when on")
        gcode = block.g_modes[GM_CUTTER_COMP]
        if gcode in (G_41_1, G_42_1):
            if not block.d_flag:
                raise InterpError(f"G{gcode // 10}.1 with no D word")
            radius = block.d_number_float / 2
            if block.l_number != -1:
                if self.plane != C.PLANE_XZ:
                    raise InterpError(f"G{gcode // 10}.1 with L word, but plane is not G18")
                orientation = block.l_number
            else:
                orientation = 0
        else:
            if not block.d_flag:
                idx = 0
            else:
                ok, tool = _is_near_int(block.d_number_float)
                if not ok:
                    raise InterpError(f"G{gcode // 10} requires D word to be a whole number")
                if tool < 0:
                    raise InterpError("Negative d word tool radius index used")
                idx = self.find_tool_index(tool)
            entry = self.tool_table[idx]
            radius = self.u2p_len(entry.diameter) / 2.0
            orientation = entry.orientation
            if self.plane != C.PLANE_XZ and orientation not in (0, 9):
                raise InterpError(f"G{gcode // 10} with lathe tool, but plane is not G18")
        if radius < 0.0:
            radius = -radius
            side = LEFT if side == RIGHT else RIGHT
        self._enq("COMMENT", "interpreter: cutter radius compensation on "
                  + ("right" if side == RIGHT else "left"))
        self.cutter_comp_radius = radius
        self.cutter_comp_orientation = orientation
        self.cutter_comp_side = side

    def convert_control_mode(self, g_code: int, tolerance_in: float, naive_in: float) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot change control mode with cutter radius compensation on")
        canon = self.canon
        if g_code == G_61:
            canon.SET_MOTION_CONTROL_MODE(C.EXACT_PATH, 0)
            self.control_mode = C.EXACT_PATH
        elif g_code == G_61_1:
            canon.SET_MOTION_CONTROL_MODE(C.EXACT_STOP, 0)
            self.control_mode = C.EXACT_STOP
        else:
            tolerance = tolerance_in if tolerance_in >= 0 else 0.0
            self.control_mode = C.CONTINUOUS
            self.tolerance = tolerance
            canon.SET_MOTION_CONTROL_MODE(C.CONTINUOUS, tolerance)
            if naive_in >= 0:
                naive = naive_in
            elif tolerance_in >= 0:
                naive = tolerance_in
            else:
                naive = 0.0
            self.naivecam_tolerance = naive
            canon.SET_NAIVECAM_TOLERANCE(naive)

    def convert_coordinate_system(self, g_code: int) -> None:
        if self.cutter_comp_side:
            raise InterpError(
                "Cannot change coordinate systems with cutter radius compensation on")
        origin = {540: 1, 550: 2, 560: 3, 570: 4, 580: 5, 590: 6, 591: 7, 592: 8, 593: 9}[g_code]
        if origin == self.origin_index:
            self._enq("COMMENT", "interpreter: continuing to use same coordinate system")
            return
        self.current = self.find_current_in_system(origin)
        self.origin_index = origin
        pars = self.parameters
        pars[5220] = float(origin)
        base = 5200 + origin * 20
        self.origin_offset = self._u2p_pose(pars[base + 1:base + 10])
        self.rotation_xy = pars[base + 10]
        self.canon.SET_G5X_OFFSET(origin, *self.origin_offset)
        self.canon.SET_G92_OFFSET(*self.axis_offset)
        self.canon.SET_XY_ROTATION(self.rotation_xy)

    # =============================================================== modal 0
    def convert_modal_0(self, code: int, block: Block) -> None:
        if code == G_10:
            lnum = block.l_number
            if lnum in (1, 10, 11):
                self.convert_setup_tool(block)
            elif lnum == 0:
                tno = self.tool_table[0].toolno
                if tno > 0:
                    raise InterpError(f"G10 L0 not allowed with loaded tool <{tno}>\n")
                self.toolchange_flag = True
                self.canon.RELOAD_TOOLDATA()
            else:
                self.convert_setup(block)
        elif code in (G_28, G_30):
            self.convert_home(code, block)
        elif code in (G_28_1, G_30_1):
            self.convert_savehome(code)
        elif code in (G_52, G_92):
            self.convert_axis_offsets(code, block)
        elif code == G_5_3:
            self.convert_nurbs(code, block)

    def convert_axis_offsets(self, g_code: int, block: Block) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot change axis offsets with cutter radius comp")
        for letter, wrapped in (("a", self.a_axis_wrapped), ("b", self.b_axis_wrapped),
                                ("c", self.c_axis_wrapped)):
            value = getattr(block, letter + "_number")
            if getattr(block, letter + "_flag") and wrapped and (value <= -360.0
                                                                  or value >= 360.0):
                raise InterpError(_wrapped_msg(value, letter.upper()))
        pars = self.parameters
        cur = self.current
        off = self.axis_offset
        if g_code in (G_52, G_92):
            pars[5210] = 1.0
            words = _axis_words(block)
            for k, value in enumerate(words):
                if value is None:
                    continue
                if g_code == G_52:
                    cur[k] += off[k] - value
                    off[k] = value
                else:
                    off[k] = cur[k] + off[k] - value
                    cur[k] = value
            self.canon.SET_G92_OFFSET(*off)
            for k in range(9):
                pars[5211 + k] = self.p2u_len(off[k]) if k in (0, 1, 2, 6, 7, 8) else off[k]
        elif g_code in (G_92_1, G_92_2):
            pars[5210] = 0.0
            for k in range(9):
                cur[k] = cur[k] + off[k]
            self.canon.SET_G92_OFFSET(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            self.axis_offset = [0.0] * 9
            if g_code == G_92_1:
                for k in range(9):
                    pars[5211 + k] = 0.0
        elif g_code == G_92_3:
            pars[5210] = 1.0
            new = self._u2p_pose(pars[5211:5220])
            for k in range(9):
                cur[k] = cur[k] + off[k] - new[k]
            self.axis_offset = new
            self.canon.SET_G92_OFFSET(*new)

    def convert_savehome(self, code: int) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot set reference point with cutter compensation in effect")
        cur, off, org, tlo = self.current, self.axis_offset, self.origin_offset, self.tool_offset
        x, y = rotate(cur[0] + off[0], cur[1] + off[1], self.rotation_xy)
        values = [self.p2u_len(x + tlo[0] + org[0]), self.p2u_len(y + tlo[1] + org[1]),
                  self.p2u_len(cur[2] + tlo[2] + org[2] + off[2])]
        for k in (3, 4, 5):
            values.append(cur[k] + tlo[k] + org[k] + off[k])
        for k in (6, 7, 8):
            values.append(self.p2u_len(cur[k] + tlo[k] + org[k] + off[k]))
        for k, wrapped in ((3, self.a_axis_wrapped), (4, self.b_axis_wrapped),
                           (5, self.c_axis_wrapped)):
            if wrapped:
                values[k] = math.fmod(values[k], 360.0)
                if values[k] < 0:
                    values[k] += 360.0
        base = 5161 if code == G_28_1 else 5181
        self.parameters[base:base + 9] = values

    def convert_home(self, move: int, block: Block) -> None:
        ends = self.find_ends(block)
        if self.cutter_comp_side:
            raise InterpError("Cannot use g28 or g30 with cutter radius comp")
        self._index_rotaries(ends, block.line_number)
        self.canon.STRAIGHT_TRAVERSE(block.line_number, *ends)
        self.current = list(ends)
        base = 5161 if move == G_28 else 5181
        home = self.find_relative(self._u2p_pose(self.parameters[base:base + 9]))
        words = _axis_words(block)
        if all(w is None for w in words):
            ends = home
        else:
            ends = [home[k] if words[k] is not None else ends[k] for k in range(9)]
        self._index_rotaries(ends, block.line_number)
        self.canon.STRAIGHT_TRAVERSE(block.line_number, *ends)
        self.current = list(ends)

    def _index_rotaries(self, ends: list[float], line: int) -> None:
        for k, jnum in ((3, self.a_indexer_jnum), (4, self.b_indexer_jnum),
                        (5, self.c_indexer_jnum)):
            if ends[k] != self.current[k] and jnum != -1:
                self.issue_straight_index(k, jnum, ends[k], line)

    def issue_straight_index(self, axis: int, jnum: int, target: float, line: int) -> None:
        canon = self.canon
        save_mode = canon.GET_EXTERNAL_MOTION_CONTROL_MODE()
        save_tol = canon.GET_EXTERNAL_MOTION_CONTROL_TOLERANCE()
        save_cam = canon.GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE()
        if save_mode != C.EXACT_PATH:
            canon.SET_MOTION_CONTROL_MODE(C.EXACT_PATH, 0)
        target_pose = list(self.current)
        target_pose[axis] = target
        canon.STRAIGHT_TRAVERSE(line, *target_pose)
        if save_mode != C.EXACT_PATH:
            canon.SET_MOTION_CONTROL_MODE(save_mode, save_tol)
            canon.SET_NAIVECAM_TOLERANCE(save_cam)
        self.current[axis] = target

    def convert_setup(self, block: Block) -> None:
        """G10 L2 / L20: set a coordinate system's origin."""
        if block.i_flag or block.j_flag:
            raise InterpError("I J words not allowed with G10 L2")
        pars = self.parameters
        p_int = int(block.p_number + 0.0001)
        if p_int == 0:
            p_int = self.origin_index
        l20 = block.l_number == 20
        for letter, wrapped in (("a", self.a_axis_wrapped), ("b", self.b_axis_wrapped),
                                ("c", self.c_axis_wrapped)):
            value = getattr(block, letter + "_number")
            if l20 and getattr(block, letter + "_flag") and wrapped and (
                    value <= -360.0 or value >= 360.0):
                raise InterpError(_wrapped_msg(value, letter.upper()))
        if self.cutter_comp_side and p_int == self.origin_index:
            raise InterpError(
                "Cannot change the active coordinate system with cutter radius compensation on")
        cs = self.find_current_in_system(p_int)
        base = 5200 + p_int * 20
        if block.r_flag:
            if l20:
                raise InterpError("R not allowed in G10 L20")
            r = block.r_number
            pars[base + 10] = r
        else:
            r = pars[base + 10]
        if l20:
            oldx, oldy = rotate(cs[0], cs[1], r)
            x = block.x_number if block.x_flag else cs[0]
            y = block.y_number if block.y_flag else cs[1]
            x, y = rotate(x, y, r)
            x = oldx + self.u2p_len(pars[base + 1]) - x
            y = oldy + self.u2p_len(pars[base + 2]) - y
            pars[base + 1] = self.p2u_len(x)
            pars[base + 2] = self.p2u_len(y)
            if p_int == self.origin_index:
                self.current[0], self.current[1] = rotate(self.current[0], self.current[1],
                                                          self.rotation_xy)
                self.rotation_xy = 0.0
        else:
            if block.x_flag:
                x = block.x_number
                pars[base + 1] = self.p2u_len(x)
            else:
                x = self.u2p_len(pars[base + 1])
            if block.y_flag:
                y = block.y_number
                pars[base + 2] = self.p2u_len(y)
            else:
                y = self.u2p_len(pars[base + 2])
        values = [x, y]
        for k, letter in ((2, "z"), (3, "a"), (4, "b"), (5, "c"), (6, "u"), (7, "v"), (8, "w")):
            linear = k not in (3, 4, 5)
            if getattr(block, letter + "_flag"):
                v = getattr(block, letter + "_number")
                if l20:
                    stored = self.u2p_len(pars[base + 1 + k]) if linear else pars[base + 1 + k]
                    v = cs[k] + stored - v
                pars[base + 1 + k] = self.p2u_len(v) if linear else v
            else:
                v = self.u2p_len(pars[base + 1 + k]) if linear else pars[base + 1 + k]
            values.append(v)
        if p_int == self.origin_index:
            cur = self.current
            cur[0], cur[1] = rotate(cur[0], cur[1], self.rotation_xy)
            for k in range(9):
                cur[k] += self.origin_offset[k]
            self.origin_offset = list(values)
            for k in range(9):
                cur[k] -= values[k]
            self.canon.SET_G5X_OFFSET(p_int, *values)
            cur[0], cur[1] = rotate(cur[0], cur[1], -r)
            self.rotation_xy = r
            self.canon.SET_XY_ROTATION(self.rotation_xy)
        else:
            self._enq("COMMENT", "interpreter: setting coordinate system origin")

    # ================================================================ motion
    def convert_motion(self, motion: int, block: Block) -> None:
        ai = block.a_flag and self.a_indexer_jnum != -1
        bi = block.b_flag and self.b_indexer_jnum != -1
        ci = block.c_flag and self.c_indexer_jnum != -1
        if motion != G_0:
            for flag, letter in ((ai, "A"), (bi, "B"), (ci, "C")):
                if flag:
                    raise InterpError(f"Indexing axis {letter} can only be moved with G0")
        xyz = (block.x_flag or block.y_flag or block.z_flag or block.u_flag or block.v_flag
               or block.w_flag)
        if ai and (xyz or block.b_flag or block.c_flag):
            raise InterpError("Indexing axis A can only be moved alone")
        if bi and (xyz or block.a_flag or block.c_flag):
            raise InterpError("Indexing axis B can only be moved alone")
        if ci and (xyz or block.a_flag or block.b_flag):
            raise InterpError("Indexing axis C can only be moved alone")
        if not is_a_cycle(motion):
            self.cycle_il_flag = False
        if ai or bi or ci:
            axis, jnum = ((3, self.a_indexer_jnum) if ai else (4, self.b_indexer_jnum) if bi
                          else (5, self.c_indexer_jnum))
            ends = self.find_ends(block)
            self.issue_straight_index(axis, jnum, ends[axis], block.line_number)
        elif motion in (G_0, G_1, G_33, G_33_1, G_76):
            self.convert_straight(motion, block)
        elif motion in (G_2, G_3):
            self.convert_arc(motion, block)
        elif motion in (G_38_2, G_38_3, G_38_4, G_38_5):
            self.convert_probe(block, motion)
        elif motion == G_80:
            self._enq("COMMENT", "interpreter: motion mode set to none")
            self.motion_mode = G_80
        elif is_a_cycle(motion):
            self.convert_cycle(motion, block)
        elif motion in (G_70, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2):
            self.convert_g7x(block)
        elif motion in (G_5, G_5_1):
            self.convert_spline(motion, block)
        elif motion == G_5_2:
            self.convert_nurbs(motion, block)
        else:
            raise InterpError(f"G{motion / 10:g} is not supported by this interpreter")

    def convert_straight(self, move: int, block: Block) -> None:
        self.arc_not_allowed = False
        if move == G_1:
            if self.feed_mode == UNITS_PER_MINUTE:
                if self.feed_rate == 0.0:
                    raise InterpError("Cannot do g1 with zero feed rate")
            elif self.feed_mode == UNITS_PER_REVOLUTION:
                if self.feed_rate == 0.0:
                    raise InterpError("Cannot do g1 with zero feed rate")
                if self.speed[self.active_spindle] == 0.0:
                    raise InterpError("Cannot feed with zero spindle speed in feed per rev mode")
            elif not block.f_flag:
                raise InterpError("F word missing with inverse time g1 move")
        self.motion_mode = move
        ends = self.find_ends(block)
        if move == G_1 and self.feed_mode == INVERSE_TIME:
            self.inverse_time_rate_straight(ends, block)
        if self.cutter_comp_side and self.cutter_comp_radius > 0.0:
            if block.g_modes[GM_MODAL_0] == G_53:
                raise InterpError("Cannot use g53 with cutter radius comp")
            if self.plane not in (C.PLANE_XY, C.PLANE_XZ):
                raise InterpError("BUG: Invalid plane for cutter compensation")
            if self.cutter_comp_firstmove:
                self.convert_straight_comp1(move, block, ends)
            else:
                self.convert_straight_comp2(move, block, ends)
            return
        canon = self.canon
        if move == G_0:
            canon.STRAIGHT_TRAVERSE(block.line_number, *ends)
        elif move == G_1:
            canon.STRAIGHT_FEED(block.line_number, *ends)
        elif move in (G_33, G_33_1):
            if block.dollar_flag:
                if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                    raise InterpError(
                        f"Invalid spindle ($) number in {'G33' if move == G_33 else 'G33.1'}"
                        " move")
                self.active_spindle = int(block.dollar_number)
            if self.spindle_turning[self.active_spindle] not in (C.CLOCKWISE,
                                                                 C.COUNTERCLOCKWISE):
                raise InterpError(
                    "Spindle not turning in G33" if move == G_33
                    else "Spindle not turning in G33.1")
            canon.START_SPEED_FEED_SYNCH(self.active_spindle, block.k_number, False)
            if move == G_33:
                canon.STRAIGHT_FEED(block.line_number, *ends)
            else:
                scale = 1.0
                if block.i_flag:
                    scale = max(block.i_number, 1.0)
                canon.RIGID_TAP(block.line_number, ends[0], ends[1], ends[2], scale)
            canon.STOP_SPEED_FEED_SYNCH()
            if move == G_33_1:
                for k in (3, 4, 5, 6, 7, 8):
                    self.current[k] = ends[k]
                return
        else:  # G76
            if block.dollar_flag:
                if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                    raise InterpError("Invalid D-number in G76 cycle")
                self.active_spindle = int(block.dollar_number)
            if self.spindle_turning[self.active_spindle] not in (C.CLOCKWISE,
                                                                 C.COUNTERCLOCKWISE):
                raise InterpError(
                    f"Chosen spindle ({self.active_spindle}) not turning in G76")
            if ends[3:9] != self.current[3:9]:
                raise InterpError("Cannot move rotary axes with G76")
            self.convert_threading_cycle(block, ends)
            return
        self.current = list(ends)

    # ============================================================= threading
    def convert_threading_cycle(self, block: Block, ends: list[float]) -> None:
        """G76: passes of decreasing depth, then spring passes (LinuxCNC's algorithm)."""
        if self.cutter_comp_side:
            raise InterpError("Cannot use G76 threading cycle with cutter radius compensation on")
        if block.i_number == 0:
            raise InterpError("In G76, I must not be 0")
        if block.j_number <= 0:
            raise InterpError("In G76, J must be greater than 0")
        if block.k_number <= block.j_number:
            raise InterpError("In G76, K must be greater than J")
        start_x, start_y, start_z = self.current[0], self.current[1], self.current[2]
        i_number, j_number, k_number = block.i_number, block.j_number, block.k_number
        if self.lathe_diameter_mode:
            i_number /= 2
            j_number /= 2
            k_number /= 2
        boring = i_number > 0.0
        safe_x = start_x
        full_dia_depth = abs(i_number)
        start_depth = abs(i_number) + abs(j_number)
        cut_increment = abs(j_number)
        full_threadheight = abs(k_number)
        end_depth = abs(k_number) + abs(i_number)
        pitch = block.p_number
        compound = block.q_number
        if compound == -1:
            compound = 0.0
        compound = ldmath.degrees_to_radians(compound)
        end_x, end_y, end_z = ends[0], ends[1], ends[2]
        if end_z > start_z:
            compound = -compound
        spring_cuts = block.h_number if block.h_flag else 0
        degression = block.r_number
        if degression < 1.0 or not block.r_flag:
            degression = 1.0
        taper_dist = block.e_number if block.e_flag else 0.0
        if taper_dist < 0.0:
            taper_dist = 0.0
        taper_pitch = (pitch * ldmath.hypot(taper_dist, full_threadheight) / taper_dist
                       if taper_dist > 0.0 else pitch)
        if end_z > start_z:
            taper_dist = -taper_dist
        taper_flags = max(block.l_number, 0)
        entry_taper = taper_flags & 1
        exit_taper = taper_flags & 2
        target_z = end_z + abs(k_number) * math.tan(compound)
        passes = 1
        depth = start_depth
        zoff = (depth - full_dia_depth) * math.tan(compound)
        args = (block, boring, safe_x, end_depth, start_y, start_z, taper_dist, entry_taper,
                exit_taper, taper_pitch, pitch, full_threadheight, target_z)
        while depth < end_depth:
            self._threading_pass(depth, zoff, *args)
            passes += 1
            depth = full_dia_depth + cut_increment * math.pow(passes, 1.0 / degression)
            zoff = (depth - full_dia_depth) * math.tan(compound)
        depth = end_depth
        zoff = (depth - full_dia_depth) * math.tan(compound)
        for _ in range(spring_cuts + 1):
            self._threading_pass(depth, zoff, *args)
        cur = self.current
        self.canon.STRAIGHT_TRAVERSE(block.line_number, end_x, end_y, end_z, *cur[3:9])
        cur[0], cur[1], cur[2] = end_x, end_y, end_z

    def _threading_pass(self, depth, zoff, block, boring, safe_x, end_depth, start_y, start_z,
                        taper_dist, entry_taper, exit_taper, taper_pitch, pitch,
                        full_threadheight, target_z) -> None:
        canon = self.canon
        line = block.line_number
        rest = self.current[3:9]
        spindle = self.active_spindle

        def x_at(d: float) -> float:
            return safe_x + d if boring else safe_x - d

        canon.STRAIGHT_TRAVERSE(line, x_at(depth - end_depth), start_y, start_z - zoff, *rest)
        if taper_dist and entry_taper:
            canon.DISABLE_FEED_OVERRIDE()
            canon.START_SPEED_FEED_SYNCH(spindle, taper_pitch, False)
            canon.STRAIGHT_FEED(line, x_at(depth - full_threadheight), start_y, start_z - zoff,
                                *rest)
            canon.STRAIGHT_FEED(line, x_at(depth), start_y, start_z - zoff - taper_dist, *rest)
            canon.START_SPEED_FEED_SYNCH(spindle, pitch, False)
        else:
            canon.STRAIGHT_TRAVERSE(line, x_at(depth), start_y, start_z - zoff, *rest)
            canon.DISABLE_FEED_OVERRIDE()
            canon.START_SPEED_FEED_SYNCH(spindle, pitch, False)
        if taper_dist and exit_taper:
            canon.STRAIGHT_FEED(line, x_at(depth), start_y, target_z - zoff + taper_dist, *rest)
            canon.START_SPEED_FEED_SYNCH(spindle, taper_pitch, False)
            canon.STRAIGHT_FEED(line, x_at(depth - full_threadheight), start_y, target_z - zoff,
                                *rest)
        else:
            canon.STRAIGHT_FEED(line, x_at(depth), start_y, target_z - zoff, *rest)
        canon.STOP_SPEED_FEED_SYNCH()
        canon.STRAIGHT_TRAVERSE(line, x_at(depth - end_depth), start_y, target_z - zoff, *rest)
        canon.ENABLE_FEED_OVERRIDE()

    # ========================================================== lathe cycles
    def convert_g7x(self, block: Block) -> None:
        """G70/G71/G72: read the profile from sub O<Q>, then cut it (see g7x.py)."""
        if not block.q_flag:
            raise InterpError("G7x.x  requires a Q word")
        cycle = block.g_modes[GM_MOTION]
        subcycle = cycle % 10
        cycle //= 10
        if self.cutter_comp_side and cycle != 70:
            raise InterpError(
                f"G{cycle}.{subcycle} cannot be used with cutter compensation enabled")
        if self.plane != C.PLANE_XZ:
            raise InterpError(f"G{cycle}.{subcycle} can only be used in XZ plane (G18)")
        saved_distance, saved_ijk = self.distance_mode, self.ijk_distance_mode
        self.distance_mode = self.ijk_distance_mode = MODE_ABSOLUTE
        saved_readers = {k: self._readers.get(k) for k in "acuw"}
        full = self._make_readers(0x1FF)
        for k in "acuw":
            self._readers[k] = full[k]
        self._no_fast = True
        try:
            self._convert_g7x(block, cycle, subcycle, saved_distance, saved_ijk)
        finally:
            self._no_fast = False
            self.distance_mode, self.ijk_distance_mode = saved_distance, saved_ijk
            for k, reader in saved_readers.items():
                if reader is None:
                    self._readers.pop(k, None)
                else:
                    self._readers[k] = reader

    def _convert_g7x(self, block, cycle, subcycle, distance_mode, ijk_mode) -> None:
        from .g7x import Chamfer, Fillet, G7xError, G7xPath, Round, Straight, raise_g7x

        incremental = distance_mode == MODE_INCREMENTAL
        x, z = self.current[0], self.current[2]
        if incremental:
            x += block.x_number if block.x_flag else 0.0
            z += block.z_number if block.z_flag else 0.0
        else:
            x = block.x_number if block.x_flag else x
            z = block.z_number if block.z_flag else z
        words = {k: (getattr(block, k + "_flag"), getattr(block, k + "_number"))
                 for k in ("e", "i", "r", "u", "w")}
        words["d"] = (block.d_flag, block.d_number_float)
        words["p"] = (block.p_flag, block.p_number)
        self.convert_straight(G_0, block)
        path = G7xPath(lambda text: self.canon.PRINT_LINE(text.rstrip("\n")))
        start = complex(z, x)
        exit_level = self.call_level
        self.read(f"O{block.q_number:f} CALL")
        while True:
            blk = self.block
            if blk.o_name is not None:
                self.convert_control_functions(blk)
            if self.call_level == exit_level:
                break
            for index, value in self.parameter_assignments:
                self.parameters[index] = value
            for name, value in self.named_parameter_assignments:
                self.store_named_param(name, value)
            self.named_parameter_assignments = []
            end = 0j if incremental else start
            center = 0j
            if blk.u_flag:
                if incremental:
                    raise InterpError("G7x error: Cannot use U in incremental mode (G91)")
                if blk.x_flag:
                    raise InterpError("G7x error: Cannot use U and X in the same block")
                u = blk.u_number / 2 if self.lathe_diameter_mode else blk.u_number
                end = complex(end.real, end.imag + u)
            elif blk.x_flag:
                end = complex(end.real, blk.x_number)
            if blk.w_flag:
                if incremental:
                    raise InterpError("G7x error: Cannot use W in incremental mode (G91)")
                if blk.z_flag:
                    raise InterpError("G7x error: Cannot use W and Z in the same block")
                end = complex(end.real + blk.w_number, end.imag)
            elif blk.z_flag:
                end = complex(blk.z_number, end.imag)
            if blk.i_flag:
                center = complex(center.real, blk.i_number)
            if blk.k_flag:
                center = complex(blk.k_number, center.imag)
            if incremental:
                end += start
            if blk.g_modes[GM_MOTION] != -1:
                self.motion_mode = blk.g_modes[GM_MOTION]
            if start != end:
                mode = self.motion_mode
                if mode in (G_0, G_1):
                    path.segments.append(Straight(start, end))
                elif mode in (G_2, G_3):
                    if blk.r_flag:
                        if blk.i_flag or blk.k_flag:
                            raise InterpError("G7X error: both R and I or K flag used for arc")
                        r = blk.r_number
                        center = complex((start + end).real / 2.0, (start + end).imag / 2.0)
                        chord = _norm_c(end - start)
                        root = math.sqrt((r * r - chord / 4) / chord)
                        d = complex(0.0 * root, root) * (end - start)
                        center = center + d if mode == G_3 else center - d
                    else:
                        if not blk.i_flag and not blk.k_flag:
                            raise InterpError(
                                "G7X error: either I or K must be present for arc")
                        if ijk_mode == MODE_INCREMENTAL:
                            center += start
                    path.segments.append(Round(int(mode == G_3), start, center, end))
                if mode in (G_0, G_1, G_2, G_3):
                    if blk.a_flag and blk.c_flag:
                        raise InterpError("G7X error: Both A and C parameters on a corner")
                    if blk.a_flag:
                        path.segments.append(Fillet(blk.a_number, end))
                    if blk.c_flag:
                        path.segments.append(Chamfer(blk.c_number, end))
                self.current[0], self.current[2] = end.imag, end.real
                start = end
            self.read()
        if len(path.segments) <= 1:
            return
        d = words["d"][1] if words["d"][0] else 0.0
        e = words["e"][1] if words["e"][0] else 0.0
        i = words["i"][1] if words["i"][0] else 1.0
        p = words["p"][1] if words["p"][0] else 1.0
        r = words["r"][1] if words["r"][0] else 0.5
        u = words["u"][1] if words["u"][0] else 0.0
        w = words["w"][1] if words["w"][0] else 0.0
        if i <= 0:
            raise InterpError("G7X error: I must be greater than zero.")
        motion = _G7xMachine(self, self.block)
        try:
            if cycle == 70:
                path.do_g70(motion, x, z, d, e, p)
            elif cycle == 71:
                path.do_g71(motion, subcycle, x, z, u, w, d, i, r)
            else:
                path.do_g72(motion, subcycle, x, z, u, w, d, i, r)
        except G7xError as error:
            raise_g7x(error)

    # =============================================================== splines
    def convert_spline(self, mode: int, block: Block) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot convert spline with cutter radius compensation")
        if self.feed_mode == UNITS_PER_MINUTE:
            if self.feed_rate == 0.0:
                raise InterpError("Cannot make arc with zero feed rate")
        elif self.feed_mode == INVERSE_TIME and not block.f_flag:
            raise InterpError("F word missing with inverse time arc move")
        if self.plane != C.PLANE_XY:
            raise InterpError("Splines must be in the XY plane")
        if block.z_flag or block.a_flag or block.b_flag or block.c_flag:
            raise InterpError("Splines may not have motion in Z, A, B, or C")
        cur = self.current
        if mode == G_5_1:
            if not block.i_flag or not block.j_flag:
                raise InterpError("Must specify both I and J with G5.1")
            x1, y1 = cur[0] + block.i_number, cur[1] + block.j_number
            ends = self.find_ends(block)
            points = [(cur[0], cur[1], 1.0), (x1, y1, 1.0), (ends[0], ends[1], 1.0)]
            self.canon.NURBS_FEED(block.line_number, points, 3)
        else:
            if not block.i_flag or not block.j_flag:
                if block.i_flag or block.j_flag:
                    raise InterpError("Must specify both I and J, or neither")
                x1, y1 = cur[0] + self.cycle_i, cur[1] + self.cycle_j
            else:
                x1, y1 = cur[0] + block.i_number, cur[1] + block.j_number
            ends = self.find_ends(block)
            if not block.p_flag or not block.q_flag:
                raise InterpError("Must specify both P and Q with G5")
            x2, y2 = ends[0] + block.p_number, ends[1] + block.q_number
            points = [(cur[0], cur[1], 1.0), (x1, y1, 1.0), (x2, y2, 1.0),
                      (ends[0], ends[1], 1.0)]
            self.canon.NURBS_FEED(block.line_number, points, 4)
            self.cycle_i = -block.p_number
            self.cycle_j = -block.q_number
        self.nurbs_points = []
        cur[0], cur[1] = ends[0], ends[1]

    def convert_nurbs(self, mode: int, block: Block) -> None:
        points = self.nurbs_points
        if mode == G_5_2:
            if block.x_flag != block.y_flag:
                raise InterpError("You must specify both X and Y coordinates for Control Points")
            if not block.x_flag and block.p_number > 0 and points:
                raise InterpError("Can specify P without X and Y only for the first control point")
            if block.p_number <= 0 and points:
                raise InterpError("Must specify positive weight P for every Control Point")
            if self.feed_mode == UNITS_PER_MINUTE and self.feed_rate == 0.0:
                raise InterpError("Cannot make a NURBS with 0 feedrate")
            if self.motion_mode != mode:
                points.clear()
            if not points:
                weight = block.p_number if (not block.x_flag and block.p_number > 0) else 1.0
                self.nurbs_order = 3
                points.append((self.current[0], self.current[1], weight))
            if block.l_number != -1 and block.l_number > 3:
                self.nurbs_order = block.l_number
            if block.x_flag and block.y_flag:
                ends = self.find_ends(block)
                points.append((ends[0], ends[1], block.p_number))
            self.motion_mode = mode
        else:
            if self.motion_mode != G_5_2:
                raise InterpError("Cannot use G5.3 without G5.2 first")
            if len(points) < self.nurbs_order:
                raise InterpError("You must specify a number of control points at least equal "
                                  f"to the order L = {self.nurbs_order}")
            self.current[0], self.current[1] = points[-1][0], points[-1][1]
            self.canon.NURBS_FEED(block.line_number, list(points), self.nurbs_order)
            points.clear()
            self.motion_mode = -1

    def inverse_time_rate_straight(self, ends: list[float], block: Block) -> None:
        cur = list(self.current)
        if self.cutter_comp_side and self.cutter_comp_radius > 0.0 and \
                not self.cutter_comp_firstmove:
            cur[0], cur[1], cur[2] = self.program_x, self.program_y, self.program_z
        length = _straight_length(ends, cur)
        rate = max(0.1, length * block.f_number)
        self._enq("SET_FEED_RATE", rate)
        self.feed_rate = rate

    def convert_probe(self, block: Block, g_code: int) -> None:
        probe_type = g_code - G_38_2
        if self.cutter_comp_side:
            raise InterpError("Cannot probe with cutter radius comp on")
        if self.feed_rate == 0.0:
            raise InterpError("Cannot probe with zero feed rate")
        if self.feed_mode == UNITS_PER_REVOLUTION:
            raise InterpError("Cannot probe with feed per rev mode")
        ends = self.find_ends(block)
        if not (probe_type & 1) and ends == self.current:
            raise InterpError("Start point too close to probe point")
        canon = self.canon
        canon.TURN_PROBE_ON()
        canon.STRAIGHT_PROBE(block.line_number, *ends, probe_type)
        canon.TURN_PROBE_OFF()
        self.motion_mode = g_code
        self.probe_flag = True

    # =================================================================== arcs
    def convert_arc(self, move: int, block: Block) -> None:
        if self.arc_not_allowed:
            raise InterpError("The move just after exiting cutter compensation mode must be "
                              "straight, not an arc")
        ijk_flag = block.i_flag or block.j_flag or block.k_flag
        plane = self.plane
        if plane in (C.PLANE_UV, C.PLANE_VW, C.PLANE_UW):
            raise InterpError("Cannot do an arc in planes G17.1, G18.1, or G19.1")
        if not block.r_flag and not ijk_flag:
            raise InterpError("R i j k words all missing for arc")
        if block.r_flag and ijk_flag:
            raise InterpError("Mixed radius ijk format for arc")
        if self.feed_mode == UNITS_PER_MINUTE:
            if self.feed_rate == 0.0:
                raise InterpError("Cannot make arc with zero feed rate")
        elif self.feed_mode == UNITS_PER_REVOLUTION:
            if self.feed_rate == 0.0:
                raise InterpError("Cannot make arc with zero feed rate")
            if self.speed[self.active_spindle] == 0.0:
                raise InterpError("Cannot feed with zero spindle speed in feed per rev mode")
        elif not block.f_flag:
            raise InterpError("F word missing with inverse time arc move")
        absolute = self.ijk_distance_mode == MODE_ABSOLUTE
        if ijk_flag:
            if plane == C.PLANE_XY:
                if block.k_flag:
                    raise InterpError("K word given for arc in xy plane")
                first, second = "i", "j"
            elif plane == C.PLANE_YZ:
                if block.i_flag:
                    raise InterpError("I word given for arc in yz plane")
                first, second = "j", "k"
            else:
                if block.j_flag:
                    raise InterpError("J word given for arc in xz plane")
                first, second = "i", "k"
            if not getattr(block, first + "_flag"):
                if absolute:
                    raise InterpError(f"{first.upper()} word missing in absolute center arc")
                setattr(block, first + "_number", 0.0)
            elif not getattr(block, second + "_flag"):
                if absolute:
                    raise InterpError(f"{second.upper()} word missing in absolute center arc")
                setattr(block, second + "_number", 0.0)
        else:
            if plane == C.PLANE_XY:
                if not (block.x_flag or block.y_flag or block.radius_flag or block.theta_flag):
                    raise InterpError("X and y words missing for arc in xy plane")
            elif plane == C.PLANE_YZ:
                if not (block.y_flag or block.z_flag):
                    raise InterpError("Y and z words missing for arc in yz plane")
            elif not (block.x_flag or block.z_flag):
                raise InterpError("X and z words missing for arc in xz plane")
        ends = self.find_ends(block)
        self.motion_mode = move
        if plane == C.PLANE_XY:
            axes = (0, 1, 2)
            offsets = (block.i_number, block.j_number)
        elif plane == C.PLANE_XZ:
            axes = (2, 0, 1)
            offsets = (block.k_number, block.i_number)
        else:
            axes = (1, 2, 0)
            offsets = (block.j_number, block.k_number)
        if self.cutter_comp_side and self.cutter_comp_radius != 0.0 and plane != C.PLANE_YZ:
            if self.cutter_comp_firstmove:
                self.convert_arc_comp1(move, block, ends, offsets)
            else:
                self.convert_arc_comp2(move, block, ends, offsets)
            return
        self.convert_arc2(move, block, axes, ends, offsets)

    def convert_arc2(self, move: int, block: Block, axes, ends, offsets) -> None:
        a1, a2, a3 = axes
        cur = self.current
        current1, current2, current3 = cur[a1], cur[a2], cur[a3]
        end1, end2, end3 = ends[a1], ends[a2], ends[a3]
        inch = self.length_units == C.UNITS_INCHES
        spiral_abs = (self.center_arc_radius_tolerance_inch if inch
                      else self.center_arc_radius_tolerance_mm)
        radius_tol = RADIUS_TOLERANCE_INCH if inch else RADIUS_TOLERANCE_MM
        p_number = _round_to_int(block.p_number) if block.p_flag else 1
        if block.r_flag:
            center1, center2, turn = self.arc_data_r(move, current1, current2, end1, end2,
                                                     block.r_number, p_number, radius_tol)
        else:
            center1, center2, turn = self.arc_data_ijk(
                move, current1, current2, end1, end2,
                self.ijk_distance_mode == MODE_ABSOLUTE, offsets[0], offsets[1], p_number,
                radius_tol, spiral_abs, SPIRAL_RELATIVE_TOLERANCE)
        if self.feed_mode == INVERSE_TIME:
            length = _arc_length(current1, current2, current3, center1, center2, turn, end1,
                                 end2, end3)
            rate = max(0.1, length * block.f_number)
            self._enq("SET_FEED_RATE", rate)
            self.feed_rate = rate
        self.canon.ARC_FEED(block.line_number, end1, end2, center1, center2, turn, end3,
                            ends[3], ends[4], ends[5], ends[6], ends[7], ends[8])
        self.current = list(ends)

    def _arc_axis_names(self) -> tuple[str, str]:
        return {C.PLANE_XY: ("X", "Y"), C.PLANE_XZ: ("Z", "X"), C.PLANE_YZ: ("Y", "Z")}.get(
            self.plane, ("!", "!"))

    def arc_data_ijk(self, move, cx, cy, ex, ey, absolute, i, j, p_number, radius_tol,
                     spiral_abs, spiral_rel, comp_side=0, tool_radius=0.0):
        a, b = self._arc_axis_names()
        if absolute:
            center_x, center_y = i, j
        else:
            center_x, center_y = cx + i, cy + j
        radius = ldmath.hypot(center_x - cx, center_y - cy)
        radius2 = ldmath.hypot(center_x - ex, center_y - ey)
        if radius < radius_tol or radius2 < radius_tol:
            raise InterpError(
                f"Zero-radius arc: start=({a}{cx:.4f},{b}{cy:.4f}) center=({a}{center_x:.4f},"
                f"{b}{center_y:.4f}) end=({a}{ex:.4f},{b}{ey:.4f}) r1={radius:.4f} "
                f"r2={radius2:.4f}")
        abs_err = abs(radius - radius2)
        rel_err = abs_err / max(radius, radius2)
        if abs_err > spiral_abs * 100.0 or (rel_err > spiral_rel and abs_err > spiral_abs):
            raise InterpError(
                f"Radius to end of arc differs from radius to start: "
                f"start=({a}{cx:.4f},{b}{cy:.4f}) center=({a}{center_x:.4f},{b}{center_y:.4f}) "
                f"end=({a}{ex:.4f},{b}{ey:.4f}) r1={radius:.4f} r2={radius2:.4f} "
                f"abs_err={_c_format('%.4g', abs_err)} rel_err={rel_err * 100:.4f}%")
        if comp_side and radius <= tool_radius and (
                (comp_side == LEFT and move == G_3) or (comp_side == RIGHT and move == G_2)):
            raise InterpError("Tool radius not less than arc radius with comp")
        turn = -p_number if move == G_2 else p_number
        return center_x, center_y, turn

    def arc_data_r(self, move, cx, cy, ex, ey, radius, p_number, tolerance):
        if ex == cx and ey == cy:
            raise InterpError("Current point same as end point of arc")
        abs_radius = abs(radius)
        mid_x = (ex + cx) / 2.0
        mid_y = (ey + cy) / 2.0
        half_length = ldmath.hypot(mid_x - ex, mid_y - ey)
        if half_length - abs_radius > tolerance:
            raise InterpError("Arc radius too small to reach end point")
        if half_length / abs_radius > 1 - TINY:
            half_length = abs_radius
        if (move == G_2 and radius > 0) or (move == G_3 and radius < 0):
            theta = ldmath.minus_pi_2(math.atan2(ey - cy, ex - cx))
        else:
            theta = ldmath.plus_pi_2(math.atan2(ey - cy, ex - cx))
        turn2 = math.asin(half_length / abs_radius)
        offset = abs_radius * math.cos(turn2)
        center_x = mid_x + offset * math.cos(theta)
        center_y = mid_y + offset * math.sin(theta)
        turn = -p_number if move == G_2 else p_number
        return center_x, center_y, turn

    # ================================================================= ends
    def find_ends(self, block: Block) -> list[float]:
        cur = self.current
        if block.g_modes[GM_MODAL_0] == G_53:
            if block.radius_flag or block.theta_flag:
                raise InterpError("Cannot use polar coordinates with G53")
            off, org, tlo = self.axis_offset, self.origin_offset, self.tool_offset
            cx, cy = rotate(cur[0] + off[0], cur[1] + off[1], self.rotation_xy)
            px = block.x_number - org[0] - tlo[0] if block.x_flag else cx
            py = block.y_number - org[1] - tlo[1] if block.y_flag else cy
            px, py = rotate(px, py, -self.rotation_xy)
            px -= off[0]
            py -= off[1]
            pz = block.z_number - org[2] - off[2] - tlo[2] if block.z_flag else cur[2]
            result = [px, py, pz]
            for k, letter, wrapped in ((3, "a", self.a_axis_wrapped),
                                       (4, "b", self.b_axis_wrapped),
                                       (5, "c", self.c_axis_wrapped)):
                if getattr(block, letter + "_flag"):
                    value = getattr(block, letter + "_number")
                    if wrapped:
                        result.append(self.unwrap_rotary(
                            value, value - org[k] - off[k] - tlo[k], cur[k], letter.upper()))
                    else:
                        result.append(value - org[k] - off[k])
                else:
                    result.append(cur[k])
            for k, letter in ((6, "u"), (7, "v"), (8, "w")):
                if getattr(block, letter + "_flag"):
                    result.append(getattr(block, letter + "_number") - org[k] - off[k] - tlo[k])
                else:
                    result.append(cur[k])
            return result
        comp = self.cutter_comp_side
        middle = not self.cutter_comp_firstmove
        cm = comp and middle
        plane = self.plane
        if self.distance_mode == MODE_ABSOLUTE:
            px = block.x_number if block.x_flag else (self.program_x if cm else cur[0])
            py = block.y_number if block.y_flag else (
                self.program_y if cm and plane == C.PLANE_XY else cur[1])
            if block.radius_flag or block.theta_flag:
                if block.x_flag or block.y_flag:
                    raise InterpError("Cannot specify X or Y words with polar coordinate")
                if block.radius_flag and block.theta_flag:
                    t = block.theta * (math.pi / 180.0)
                    px, py = block.radius * math.cos(t), block.radius * math.sin(t)
                elif block.radius_flag:
                    if py == 0 and px == 0:
                        raise InterpError("Must specify angle in polar coordinate if at the origin")
                    t = math.atan2(py, px)
                    px, py = block.radius * math.cos(t), block.radius * math.sin(t)
                else:
                    radius = ldmath.hypot(py, px)
                    t = block.theta * (math.pi / 180.0)
                    px, py = radius * math.cos(t), radius * math.sin(t)
            pz = block.z_number if block.z_flag else (
                self.program_z if cm and plane == C.PLANE_XZ else cur[2])
            result = [px, py, pz]
            for k, letter, wrapped in ((3, "a", self.a_axis_wrapped),
                                       (4, "b", self.b_axis_wrapped),
                                       (5, "c", self.c_axis_wrapped)):
                if getattr(block, letter + "_flag"):
                    value = getattr(block, letter + "_number")
                    if wrapped:
                        result.append(self.unwrap_rotary(value, value, cur[k], letter.upper()))
                    else:
                        result.append(value)
                else:
                    result.append(cur[k])
            result.append(block.u_number if block.u_flag else cur[6])
            result.append(block.v_number if block.v_flag else cur[7])
            result.append(block.w_number if block.w_flag else cur[8])
            return result
        px = self.program_x if cm else cur[0]
        if block.x_flag:
            px += block.x_number
        py = self.program_y if cm and plane == C.PLANE_XY else cur[1]
        if block.y_flag:
            py += block.y_number
        if block.radius_flag:
            if block.x_flag or block.y_flag:
                raise InterpError("Cannot specify X or Y words with polar coordinate")
            if py == 0 and px == 0:
                raise InterpError(
                    "Incremental motion with polar coordinates is indeterminate when at the "
                    "origin")
            t = math.atan2(py, px)
            radius = ldmath.hypot(py, px) + block.radius
            px, py = radius * math.cos(t), radius * math.sin(t)
        if block.theta_flag:
            if block.x_flag or block.y_flag:
                raise InterpError("Cannot specify X or Y words with polar coordinate")
            if py == 0 and px == 0:
                raise InterpError(
                    "G91 motion with polar coordinates is indeterminate when at the origin")
            t = math.atan2(py, px) + block.theta * (math.pi / 180.0)
            radius = ldmath.hypot(py, px)
            px, py = radius * math.cos(t), radius * math.sin(t)
        pz = self.program_z if cm and plane == C.PLANE_XZ else cur[2]
        if block.z_flag:
            pz += block.z_number
        return [px, py, pz,
                cur[3] + block.a_number if block.a_flag else cur[3],
                cur[4] + block.b_number if block.b_flag else cur[4],
                cur[5] + block.c_number if block.c_flag else cur[5],
                cur[6] + block.u_number if block.u_flag else cur[6],
                cur[7] + block.v_number if block.v_flag else cur[7],
                cur[8] + block.w_number if block.w_flag else cur[8]]

    def unwrap_rotary(self, sign_of: float, commanded: float, current: float,
                      axis: str) -> float:
        if sign_of <= -360.0 or sign_of >= 360.0:
            raise InterpError(_wrapped_msg(sign_of, axis))
        neg = math.copysign(1.0, sign_of) < 0.0
        d = math.floor(current / 360.0)
        result = abs(commanded) + d * 360.0
        if not neg and result < current:
            result += 360.0
        if neg and result > current:
            result -= 360.0
        return result

    def find_relative(self, absolute: list[float]) -> list[float]:
        org, tlo, off = self.origin_offset, self.tool_offset, self.axis_offset
        x = absolute[0] - org[0] - tlo[0]
        y = absolute[1] - org[1] - tlo[1]
        x, y = rotate(x, y, -self.rotation_xy)
        result = [x - off[0], y - off[1], absolute[2] - org[2] - off[2] - tlo[2]]
        for k, wrapped, letter in ((3, self.a_axis_wrapped, "A"), (4, self.b_axis_wrapped, "B"),
                                   (5, self.c_axis_wrapped, "C")):
            if wrapped:
                result.append(self.unwrap_rotary(absolute[k],
                                                 absolute[k] - org[k] - off[k] - tlo[k],
                                                 self.current[k], letter))
            else:
                result.append(absolute[k] - org[k] - off[k])
        for k in (6, 7, 8):
            result.append(absolute[k] - org[k] - off[k] - tlo[k])
        return result

    def find_current_in_system(self, system: int, with_tlo: bool = False) -> list[float]:
        p = self.parameters
        cur = self.current
        off, org, tlo = self.axis_offset, self.origin_offset, self.tool_offset
        v = [cur[k] + off[k] for k in range(9)]
        v[0], v[1] = rotate(v[0], v[1], self.rotation_xy)
        for k in range(9):
            v[k] += org[k]
        if with_tlo:
            for k in range(9):
                v[k] += tlo[k]
        base = 5200 + system * 20
        stored = self._u2p_pose(p[base + 1:base + 10])
        for k in range(9):
            v[k] -= stored[k]
        v[0], v[1] = rotate(v[0], v[1], -p[base + 10])
        if p[5210]:
            g92 = self._u2p_pose(p[5211:5220])
            for k in range(9):
                v[k] -= g92[k]
        return v

    # ================================================================= stop
    def convert_stop(self, block: Block) -> int:
        canon = self.canon
        cx, cy, _ = self.comp_get_current() if self.plane in (C.PLANE_XY, C.PLANE_XZ) else \
            (0.0, 0.0, 0.0)
        self.move_endpoint_and_flush(cx, cy)
        self.dequeue_canons()
        m4 = block.m_modes[4]
        if m4 == 99 and self.call_level > 0:
            raise InterpError("Bug:  Reached convert_stop() from M99 as subprogram return")
        if m4 == 0:
            canon.PROGRAM_STOP()
        elif m4 == 60:
            canon.PALLET_SHUTTLE()
            canon.PROGRAM_STOP()
        elif m4 == 1:
            canon.OPTIONAL_PROGRAM_STOP()
        elif m4 == 99 and self.loop_on_main_m99:
            self.file_pos = 0
            self.sequence_number = 0
            canon.FINISH()
            return INTERP_EXECUTE_FINISH
        elif m4 in (2, 30, 99):
            cur = self.current
            cur[0], cur[1] = rotate(cur[0], cur[1], self.rotation_xy)
            for k in range(9):
                cur[k] += self.origin_offset[k]
            self.origin_index = 1
            pars = self.parameters
            pars[5220] = 1.0
            self.origin_offset = self._u2p_pose(pars[5221:5230])
            self.rotation_xy = pars[5230]
            for k in range(9):
                cur[k] -= self.origin_offset[k]
            cur[0], cur[1] = rotate(cur[0], cur[1], -self.rotation_xy)
            canon.SET_G5X_OFFSET(self.origin_index, *self.origin_offset)
            canon.SET_XY_ROTATION(self.rotation_xy)
            if self.plane != C.PLANE_XY:
                canon.SELECT_PLANE(C.PLANE_XY)
                self.plane = C.PLANE_XY
            self.distance_mode = MODE_ABSOLUTE
            self.feed_mode = UNITS_PER_MINUTE
            canon.SET_FEED_MODE(0, 0)
            self.feed_rate = block.f_number
            canon.SET_FEED_RATE(0)
            if not self.feed_override:
                canon.ENABLE_FEED_OVERRIDE()
                self.feed_override = True
            self.cutter_comp_side = 0
            self.cutter_comp_firstmove = True
            for s in range(self.num_spindles):
                canon.STOP_SPINDLE_TURNING(s)
                self.spindle_turning[s] = C.STOPPED
                self.speed_override[s] = True
                canon.SET_SPINDLE_MODE(s, 0)
            self.motion_mode = G_1
            if self.mist:
                canon.MIST_OFF()
                self.mist = False
            if self.flood:
                canon.FLOOD_OFF()
                self.flood = False
            if self.disable_g92_persistence:
                for i in range(5210, 5220):
                    pars[i] = 0.0
            if m4 == 30:
                canon.PALLET_SHUTTLE()
            canon.PROGRAM_END()
            if self.percent_flag and self.file_lines is not None:
                lines = self.file_lines
                while True:
                    if self.file_pos >= len(lines):
                        self._enq("COMMENT", "interpreter: percent sign missing from end of file")
                        break
                    line = lines[self.file_pos]
                    self.file_pos += 1
                    if len(line) >= LINELEN - 1:
                        continue
                    self.linetext = line
                    stripped = line.rstrip()
                    if stripped.endswith("%") and not stripped[:-1].strip():
                        break
            self.unwind_call()
            return INTERP_EXIT
        return INTERP_OK

    # ============================================================== unwinding
    def unwind_call(self) -> None:
        while self.call_level > 0:
            sub = self.sub_context[self.call_level - 1]
            self.sub_context[self.call_level].named_params.clear()
            sub.subName = None
            if sub.call_type != CT_NGC_M98_SUB:
                self.parameters[1:31] = sub.saved_params
            if self.file_lines is not None and sub.filename:
                if self.filename != sub.filename:
                    lines = self._open_cached(sub.filename)
                    self.file_lines = lines if lines is not None else []
                    self.filename = sub.filename
                self.file_pos = sub.position
                self.sequence_number = sub.sequence_number
            elif self.file_lines is not None:
                self.sequence_number = sub.sequence_number
            self.call_level -= 1
        self.sub_name = None
        self.remap_level = 0
        self.defining_sub = 0
        self.skipping_o = None
        self.skipping_to_sub = None
        self.offset_map.clear()
        self.mdi_interrupt = False
        self.qc_reset()

    def _open_cached(self, filename: str) -> list[str] | None:
        lines = self._file_cache.get(filename)
        if lines is None:
            lines = self._load_file(filename)
            if lines is not None:
                self._file_cache[filename] = lines
        return lines

    # ================================================================== tools
    def load_tool_table(self) -> None:
        canon = self.canon
        self.tool_table = _ToolTableView(canon)
        self.set_tool_parameters()

    def find_tool_index(self, toolno: int) -> int:
        idx = self.canon.find_tool_index(toolno)
        if idx == -1:
            raise InterpError(f"Requested tool {toolno} not found in the tool table")
        return idx

    def convert_tool_select(self, block: Block) -> None:
        idx = self.find_tool_index(block.t_number)
        self.canon.SELECT_TOOL(block.t_number)
        self.selected_pocket = idx
        self.selected_tool = block.t_number

    def convert_tool_change(self) -> None:
        if self.selected_pocket < 0:
            raise InterpError("Need tool prepared -Txx- for toolchange")
        if self.cutter_comp_side:
            raise InterpError("Cannot change tools with cutter radius compensation on")
        canon = self.canon
        canon.START_CHANGE()
        if not self.tool_change_with_spindle_on:
            for s in range(self.num_spindles):
                canon.STOP_SPINDLE_TURNING(s)
                self.spindle_turning[s] = C.STOPPED
        if self.tool_change_quill_up:
            up_z = self.find_relative([0.0] * 9)[2]
            canon.COMMENT("AXIS,hide")
            pose = list(self.current)
            pose[2] = up_z
            canon.STRAIGHT_TRAVERSE(-1, *pose)
            canon.COMMENT("AXIS,show")
            self.current[2] = up_z
        if self.tool_change_at_g30:
            ends = self.find_relative(self._u2p_pose(self.parameters[5181:5190]))
            canon.COMMENT("AXIS,hide")
            self._index_rotaries(ends, -1)
            canon.STRAIGHT_TRAVERSE(-1, *ends)
            canon.COMMENT("AXIS,show")
            self.current = list(ends)
        canon.CHANGE_TOOL(self.selected_pocket)
        self.current_pocket = self.selected_pocket
        self.toolchange_flag = True
        self.set_tool_parameters()

    def convert_tool_length_offset(self, g_code: int, block: Block) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot change tool offset with cutter radius compensation on")
        if g_code == G_49:
            offset = [0.0] * 9
        elif g_code == G_43:
            if block.h_flag:
                idx = self.find_tool_index(block.h_number)
                if idx == 0 and self.random_toolchanger:
                    idx = self.current_pocket
            elif self.toolchange_flag:
                idx = self.current_pocket
            else:
                idx = 0
            offset = self._u2p_pose(self.tool_table[idx].offset)
        elif g_code == G_43_1:
            offset = list(self.tool_offset)
            for k, value in enumerate(_axis_words(block)):
                if value is not None:
                    offset[k] = value
        else:
            has_axes = any(w is not None for w in _axis_words(block))
            if block.h_flag and has_axes:
                raise InterpError("G43.2: Can not have both H and axis words")
            if not block.h_flag and not has_axes:
                raise InterpError("G43.2: No axes specified and H word missing")
            idx = self.find_tool_index(block.h_number)
            offset = list(self.tool_offset)
            if block.h_flag:
                add = self._u2p_pose(self.tool_table[idx].offset)
            else:
                add = [w if w is not None else 0.0 for w in _axis_words(block)]
            for k in range(9):
                offset[k] += add[k]
        self.canon.USE_TOOL_LENGTH_OFFSET(offset)
        old = self.tool_offset
        dx, dy = rotate(old[0] - offset[0], old[1] - offset[1], -self.rotation_xy)
        cur = self.current
        cur[0] += dx
        cur[1] += dy
        for k in range(2, 9):
            cur[k] += old[k] - offset[k]
        self.tool_offset = offset

    def convert_setup_tool(self, block: Block) -> None:
        """G10 L1 / L10 / L11: change a tool table entry."""
        direct = block.l_number == 1
        _, toolno = _is_near_int(block.p_number)
        idx = self.find_tool_index(toolno)
        words = _axis_words(block)
        if not (any(w is not None for w in words) or block.r_flag or block.q_flag
                or block.i_flag or block.j_flag):
            raise InterpError("G10 L1 without offsets has no effect")
        entry = self.tool_table[idx]
        toff = list(entry.offset)
        if direct:
            for k, value in enumerate(words):
                if value is not None:
                    toff[k] = self.p2u_len(value) if k not in (3, 4, 5) else value
        else:
            to_fixture = block.l_number == 11
            dest = 9 if to_fixture else self.origin_index
            t = self.find_current_in_system(dest, with_tlo=True)
            pars = self.parameters
            if to_fixture and pars[5210]:
                g92 = self._u2p_pose(pars[5211:5220])
                for k in range(9):
                    t[k] += g92[k]
            rot = pars[5210 + dest * 20]
            if block.x_flag and block.y_flag:
                tx, ty = rotate(t[0] - block.x_number, t[1] - block.y_number, rot)
                toff[0], toff[1] = self.p2u_len(tx), self.p2u_len(ty)
            elif block.x_flag or block.y_flag:
                ox, oy = rotate(self.u2p_len(toff[0]), self.u2p_len(toff[1]), -rot)
                if block.x_flag:
                    ox = 0.0
                    tx, ty = t[0] - block.x_number, 0.0
                else:
                    oy = 0.0
                    tx, ty = 0.0, t[1] - block.y_number
                ox, oy = rotate(ox, oy, rot)
                tx, ty = rotate(tx, ty, rot)
                toff[0], toff[1] = self.p2u_len(tx + ox), self.p2u_len(ty + oy)
            for k in range(2, 9):
                if words[k] is not None:
                    value = t[k] - words[k]
                    toff[k] = self.p2u_len(value) if k not in (3, 4, 5) else value
        entry.offset = toff
        if block.r_flag:
            entry.diameter = self.p2u_len(block.r_number) * 2.0
        if block.i_flag:
            entry.frontangle = block.i_number
        if block.j_flag:
            entry.backangle = block.j_number
        if block.q_number != -1.0:
            ok, q = _is_near_int(block.q_number)
            if not ok:
                raise InterpError("Q number in G10 is not an integer")
            if q > 9:
                raise InterpError("Invalid tool orientation")
            entry.orientation = q
        self.tool_table.set(idx, entry)
        canon = self.canon
        canon.SET_TOOL_TABLE_ENTRY(idx, entry.toolno, entry.offset, entry.diameter,
                                   entry.frontangle, entry.backangle, entry.orientation)
        if not self.random_toolchanger and self.current_pocket == idx:
            self.tool_table.set(0, entry)
        spindle = self.tool_table[0]
        pars = self.parameters
        if self.random_toolchanger:
            pars[5400] = spindle.toolno if spindle.toolno >= 0 else -1
        else:
            pars[5400] = spindle.toolno if spindle.toolno > 0 else 0
        self._set_tool_params_from(spindle)
        if not self.random_toolchanger and idx == self.current_pocket:
            canon.SET_TOOL_TABLE_ENTRY(0, entry.toolno, entry.offset, entry.diameter,
                                       entry.frontangle, entry.backangle, entry.orientation)

    def _set_tool_params_from(self, entry) -> None:
        pars = self.parameters
        pars[5401:5410] = entry.offset
        pars[5410] = entry.diameter
        pars[5411] = entry.frontangle
        pars[5412] = entry.backangle
        pars[5413] = entry.orientation

    def set_tool_parameters(self) -> None:
        spindle = self.tool_table[0]
        if not self.random_toolchanger and spindle.toolno <= 0:
            self.default_tool_parameters()
            return
        self.parameters[5400] = spindle.toolno
        self._set_tool_params_from(spindle)

    def default_tool_parameters(self) -> None:
        self.parameters[5400:5414] = [0.0] * 14

    def init_tool_parameters(self) -> None:
        if self.random_toolchanger:
            spindle = self.tool_table[0]
            self.parameters[5400] = spindle.toolno
            self._set_tool_params_from(spindle)
        elif self.tool_table[0].toolno == -1:
            self.default_tool_parameters()


# A line of nothing but an optional N word, an optional G0/G1 and plain-number axis words in
# XYZABC order (other lines take the general path).
_NUM = r"([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+))"
_FAST_LINE = re.compile(
    r"(?:n(\d+))?(?:g0*([01])(?![0-9.]))?(?=[xyzabc])" + "".join(
        f"(?:{letter}{_NUM})?" for letter in "xyzabc") + r"\Z")


_EMPTY_BLOCK = Block()  # stands for blank lines; never executed
_FAST_FIRST = frozenset("nNgGxXyYzZaAbBcC")


def _norm_c(z: complex) -> float:
    return z.real * z.real + z.imag * z.imag


class _G7xMachine:
    """Turns the lathe cycles' moves into ordinary G0/G1/G2/G3 conversions."""

    def __init__(self, interp: Interpreter, block: Block) -> None:
        self.interp = interp
        self.block = block

    def _to(self, end: complex) -> None:
        block = self.block
        block.x_flag = block.z_flag = True
        block.x_number, block.z_number = end.imag, end.real

    def straight_move(self, end: complex) -> None:
        self._to(end)
        self.interp.convert_straight(G_1, self.block)

    def straight_rapid(self, end: complex) -> None:
        self._to(end)
        self.interp.convert_straight(G_0, self.block)

    def circular_move(self, ccw: int, center: complex, end: complex) -> None:
        self._to(end)
        block = self.block
        block.i_flag = block.k_flag = True
        block.i_number, block.k_number = center.imag, center.real
        cur = self.interp.current
        if abs(cur[2] - block.z_number) >= 0.0001 or abs(cur[0] - block.x_number) >= 0.0001:
            self.interp.convert_arc(G_3 if ccw else G_2, block)


class _ToolTableView:
    """The interpreter's copy of the tool table (``settings.tool_table``), taken lazily."""

    def __init__(self, canon) -> None:
        self._canon = canon
        self._entries: dict = {}

    def __getitem__(self, idx: int):
        entry = self._entries.get(idx)
        if entry is None:
            entry = self._canon.GET_EXTERNAL_TOOL_TABLE(idx)
            self._entries[idx] = entry
        return entry.copy()

    def set(self, idx: int, entry) -> None:
        self._entries[idx] = entry.copy()


CONTEXT_VALID, CONTEXT_RESTORE_ON_RETURN = 1, 2


def _gen_settings(current_g, saved_g, current_f, saved_f) -> str:
    """The G-code text that brings the modal state back to a saved one (M72, M73)."""
    cmd = []
    g64_changed = False
    for i in range(5):
        if saved_f[i] != current_f[i]:
            if i == 1:
                cmd.append(f" F{saved_f[i]:.1f}")
            elif i == 2:
                cmd.append(f" S{saved_f[i]:.0f}")
            elif i in (3, 4):
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


def _axis_words(block: Block) -> list[float | None]:
    return [block.x_number if block.x_flag else None, block.y_number if block.y_flag else None,
            block.z_number if block.z_flag else None, block.a_number if block.a_flag else None,
            block.b_number if block.b_flag else None, block.c_number if block.c_flag else None,
            block.u_number if block.u_flag else None, block.v_number if block.v_flag else None,
            block.w_number if block.w_flag else None]


def _wrapped_msg(value: float, axis: str) -> str:
    return f"Invalid absolute position {value:5.2f} for wrapped rotary axis {axis}"


def _straight_length(end: list[float], start: list[float]) -> float:
    tiny = 1e-7
    if (abs(start[0] - end[0]) > tiny or abs(start[1] - end[1]) > tiny
            or abs(start[2] - end[2]) > tiny):
        return math.sqrt((end[0] - start[0]) ** 2 + (end[1] - start[1]) ** 2
                         + (end[2] - start[2]) ** 2)
    if (abs(start[6] - end[6]) > tiny or abs(start[7] - end[7]) > tiny
            or abs(start[8] - end[8]) > tiny):
        return math.sqrt((end[6] - start[6]) ** 2 + (end[7] - start[7]) ** 2
                         + (end[8] - start[8]) ** 2)
    return math.sqrt((end[3] - start[3]) ** 2 + (end[4] - start[4]) ** 2
                     + (end[5] - start[5]) ** 2)


def _find_turn(x1, y1, center_x, center_y, turn, x2, y2) -> float:
    if turn == 0:
        return 0.0
    alpha = math.atan2(y1 - center_y, x1 - center_x)
    beta = math.atan2(y2 - center_y, x2 - center_x)
    if turn > 0:
        if beta <= alpha:
            beta += 2 * math.pi
        return (beta - alpha) + (turn - 1) * (2 * math.pi)
    if alpha <= beta:
        alpha += 2 * math.pi
    return (beta - alpha) + (turn + 1) * (2 * math.pi)


def _arc_length(x1, y1, z1, cx, cy, turn, x2, y2, z2) -> float:
    radius = ldmath.hypot(cx - x1, cy - y1)
    theta = _find_turn(x1, y1, cx, cy, turn, x2, y2)
    if z2 == z1:
        return radius * abs(theta)
    return ldmath.hypot(radius * theta, z2 - z1)


def _c_format(fmt: str, value: float) -> str:
    if fmt == "%lf":
        return f"{value:f}"
    return fmt % value


def _realpath(path: str, base: str) -> str:
    expanded = os.path.expanduser(path)
    if not os.path.isabs(expanded):
        expanded = os.path.join(os.getcwd(), expanded)
    real = os.path.realpath(expanded)
    return real if os.path.exists(real) else ""


__all__ = [
    "CT_NONE",
    "G_54",
    "G_81",
    "G_82",
    "G_84",
    "G_86",
    "G_87",
    "G_88",
    "G_89",
    "Interpreter",
    "O_none",
    "rotate",
]
