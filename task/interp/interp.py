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
import time
from collections.abc import Callable

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from .block import (
    CT_NGC_M98_SUB,
    CT_NONE,
    G_0,
    G_1,
    G_2,
    G_3,
    G_4,
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
    G_28,
    G_30,
    G_33,
    G_33_1,
    G_40,
    G_41,
    G_41_1,
    G_42,
    G_42_1,
    G_43,
    G_43_1,
    G_43_2,
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
    G_92,
    G_93,
    G_94,
    G_95,
    G_96,
    G_97,
    G_98,
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
from .common import (
    CENTER_ARC_RADIUS_TOLERANCE_INCH,
    CENTER_ARC_RADIUS_TOLERANCE_MM,
    CONSTANT_RPM,
    CONSTANT_SURFACE,
    INCH_PER_MM,
    INVERSE_TIME,
    LEFT,
    MAX_EMS,
    MM_PER_INCH,
    MODE_ABSOLUTE,
    MODE_INCREMENTAL,
    NUM_SPINDLES_MAX,
    OLD_Z,
    R_PLANE,
    RIGHT,
    UNITS_PER_MINUTE,
    UNITS_PER_REVOLUTION,
    c_format,
    is_near_int,
    rotate,
    round_to_int,
)
from .comp import QOTHER, CompMixin
from .compiled import Compiler, LinePlan, plan_line
from .cycles import CyclesMixin
from .errors import (
    INTERP_ENDFILE,
    INTERP_EXECUTE_FINISH,
    INTERP_EXIT,
    INTERP_FILE_NOT_OPEN,
    INTERP_MIN_ERROR,
    INTERP_OK,
    InterpError,
)
from .mcodes import MCodesMixin
from .motion import MotionMixin
from .offsets import OffsetsMixin
from .owords import Context, OWordMixin
from .params import ParamsMixin
from .reader import LINELEN, ReaderMixin, close_and_downcase, downcase
from .remap import (
    CS_NORMAL,
    EMC_DEBUG_UNCONDITIONAL,
    MAX_NESTED_REMAPS,
    STEP_COMMENT,
    STEP_CONTROL_MODE,
    STEP_COORD_SYSTEM,
    STEP_CUTTER_COMP,
    STEP_DISTANCE_MODE,
    STEP_DWELL,
    STEP_FEED_MODE,
    STEP_G92_IS_APPLIED,
    STEP_IJK_DISTANCE_MODE,
    STEP_LATHE_DIAMETER_MODE,
    STEP_LENGTH_UNITS,
    STEP_M_GROUP,
    STEP_MGROUP4,
    STEP_MODAL_0,
    STEP_MOTION,
    STEP_PREPARE,
    STEP_RETRACT_MODE,
    STEP_SET_FEED_RATE,
    STEP_SET_PLANE,
    STEP_SET_SPINDLE_SPEED,
    STEP_SPINDLE_MODE,
    STEP_TOOL_LENGTH_OFFSET,
    RemapError,
    RemapMixin,
    parse_remaps,
)
from .stack import error_stack
from .statetag import state_tag
from .tools import ToolsMixin

LOAD_CHUNK_BYTES = 1 << 18  # (about 8,000 lines of G-code)


class Interpreter(
    ParamsMixin,
    ReaderMixin,
    RemapMixin,
    OWordMixin,
    MCodesMixin,
    OffsetsMixin,
    MotionMixin,
    CyclesMixin,
    CompMixin,
    ToolsMixin,
):
    """LinuxCNC's RS274NGC interpreter, talking to a canon."""

    def __init__(
        self,
        canon,
        *,
        ini=None,
        parameter_file: str = "",
        task: int = 0,
        hal: Callable[[str], float | None] | None = None,
        python_modules: dict | None = None,
    ) -> None:
        """``ini`` is a cnc.ini.IniFile or None; ``parameter_file`` the .var file; ``task``
        the value of #<_task>; ``hal`` looks up a HAL pin, signal or parameter by name for
        #<_hal[...]> (None: there is no HAL, as in rs274); ``python_modules`` more
        built-in modules for the embedded Python (task gives ``emctask``)."""
        self.canon = canon
        self.hal = hal
        canon.linetext = self._get_linetext
        # a canon that takes state tags (task's) gets one before each move (statetag.py)
        self._update_tag: Callable[[tuple], object] | None = getattr(canon, "UPDATE_TAG", None)
        self.ini = ini
        self.parameter_file = parameter_file
        self.task = task
        # where rs274's stray diagnostics go (a standalone run passes stderr)
        self.report: Callable[[str], object] = lambda text: None
        # remapping and embedded Python (remap.py, python/): none until init() reads an INI
        self.remaps = None
        self.g_remapped: dict = {}  # G code x 10 -> Remap (read_g)
        self.m_remapped: dict = {}
        self.is_f_remapped = False
        self.remap_level = 0
        self.remap_blocks: list[Block | None] = [None] * MAX_NESTED_REMAPS
        self.call_state = CS_NORMAL
        self.nested_executes = 0  # self.execute() of Python code under way
        self.saved_error = ""  # set_errormsg(): the message of a handler's INTERP_ERROR
        self.debugmask = 0
        self.log_level = 0
        self.python = None  # the [PYTHON] plug-in (python/plugin.py)
        self.python_view = None  # self of Python code (python/view.py)
        self.python_modules = python_modules or {}
        self.is_python_started = False  # namedparams and __init__ ran (once)
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
        self._fast = None  # a motion line taken by the fast path: (motion, ends, feed)
        self._planned = None  # a line read by its plan: (its execute function, argument)
        self._no_fast = False
        self._plans: dict[str, LinePlan] = {}  # raw line -> its plan (see compiled.py)
        self.has_error_stack = False  # errors carry LinuxCNC's function stack (rs274 -s)
        self._file_cache: dict[str, list[str]] = {}
        self._file_stamps: dict[str, tuple[int, int]] = {}  # (mtime, size) when read
        # called between the pieces of a large file being read (see _load_file)
        self.on_progress: Callable[[], None] | None = None
        self._compiled: dict = {}  # (line, position) -> compiled value (see compiled.py)
        self._compiler = Compiler(self)
        self._o_slots = [0.0] * 8  # the value stack O-word expressions share

    def _get_linetext(self) -> str:
        return self.linetext

    def write_canon_state_tag(self, block: Block | None) -> None:
        """Give the canon the modal state now, for the moves it queues next (LinuxCNC's
        write_canon_state_tag: at a move, and once a block has made all its changes)."""
        if self._update_tag is not None:
            self._update_tag(state_tag(self, block))

    def record_error_stack(self) -> None:
        """Make errors carry LinuxCNC's function stack (``rs274 -s``, see stack.py).

        Lines are then always read by the interpreting reader, never by compiled values or
        line plans, so that an error's traceback has the shape of LinuxCNC's reader.
        """
        self.has_error_stack = True
        self._compiled = _Uncached()
        self._plans = _Uncached()

    def _unwind_after_error(self) -> None:
        """An error returns from every call; inside Python's self.execute(), only from the
        calls it made (python_execute does that), not from the remap that runs it."""
        if not self.nested_executes:
            self.unwind_call()

    def _note_stack(self, error: InterpError) -> None:
        if self.has_error_stack and not error.stack:
            error.stack = error_stack(error.__traceback__, error.message)

    # ================================================================== init
    def init(self) -> int:
        try:
            return self._init()
        except InterpError as error:
            self._note_stack(error)
            raise

    def _init(self) -> int:
        self.tool_change_at_g30 = 0
        self.tool_change_quill_up = 0
        self.tool_change_with_spindle_on = 0
        self.a_axis_wrapped = self.b_axis_wrapped = self.c_axis_wrapped = 0
        self.random_toolchanger = 0
        self.a_indexer_jnum = self.b_indexer_jnum = self.c_indexer_jnum = -1
        self.return_value = 0.0
        self.value_returned = 0
        self.remap_level = 0
        self.call_state = CS_NORMAL
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
        self.origin_offset = [
            self.u2p_len(pars[k + 1]),
            self.u2p_len(pars[k + 2]),
            self.u2p_len(pars[k + 3]),
            pars[k + 4],
            pars[k + 5],
            pars[k + 6],
            self.u2p_len(pars[k + 7]),
            self.u2p_len(pars[k + 8]),
            self.u2p_len(pars[k + 9]),
        ]
        canon.SET_G5X_OFFSET(self.origin_index, *self.origin_offset)
        if self.disable_g92_persistence:
            for i in range(5210, 5220):
                pars[i] = 0.0
        if pars[5210]:
            self.axis_offset = [
                self.u2p_len(pars[5211]),
                self.u2p_len(pars[5212]),
                self.u2p_len(pars[5213]),
                pars[5214],
                pars[5215],
                pars[5216],
                self.u2p_len(pars[5217]),
                self.u2p_len(pars[5218]),
                self.u2p_len(pars[5219]),
            ]
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
        # A caller that must stay responsive (task) sets a time.monotonic() deadline: an
        # MDI subroutine call, which LinuxCNC runs whole within one execute(), then returns
        # INTERP_OK with call_level > 0 at the deadline, and execute() reads on from there.
        self.slice_deadline: float | None = None
        self.is_mdi_call_sliced = False
        self.selected_tool = 0
        self.selected_pocket = 0
        self.parameters[5599] = 1.0
        self._readers = self._make_readers(canon.GET_EXTERNAL_AXIS_MASK())
        self._plans.clear()  # plans depend on the axes
        self.synch()
        self.init_tool_parameters()
        if self.ini is not None and self.python is not None and not self.is_python_started:
            self.start_python()
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
        for axis, attr in (
            ("AXIS_A", "a_indexer_jnum"),
            ("AXIS_B", "b_indexer_jnum"),
            ("AXIS_C", "c_indexer_jnum"),
        ):
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
            (
                "CENTER_ARC_RADIUS_TOLERANCE_INCH",
                "center_arc_radius_tolerance_inch",
                CENTER_ARC_RADIUS_TOLERANCE_INCH,
            ),
            (
                "CENTER_ARC_RADIUS_TOLERANCE_MM",
                "center_arc_radius_tolerance_mm",
                CENTER_ARC_RADIUS_TOLERANCE_MM,
            ),
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
        self.debugmask = _debug_flags(ini.find("EMC", "DEBUG")) | EMC_DEBUG_UNCONDITIONAL
        self.log_level = get_int("RS274NGC", "LOG_LEVEL", 0)
        if self.python is None and ini.find("PYTHON", "TOPLEVEL") is not None:
            self.configure_python(ini)
        self._read_remaps(ini)

    def _read_remaps(self, ini) -> None:
        """[RS274NGC]REMAP lines (REMAP-003..011); every bad one is reported as file:line."""
        entries = ini.entries("RS274NGC", "REMAP")
        if not entries:
            self.remaps, self.g_remapped, self.m_remapped = None, {}, {}
            self.is_f_remapped = False
            return
        python = self.python
        try:
            table, warnings = parse_remaps(
                entries,
                find_ngc=self.find_ngc_file,
                find_python=None if python is None else lambda name: python.find("remap", name),
            )
        except RemapError as error:
            raise InterpError(str(error)) from None
        for warning in warnings:
            self.report(warning + "\n")
        self.remaps, self.g_remapped, self.m_remapped = table, table.g, table.m
        self.is_f_remapped = "F" in table.letter

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
        return [
            u(values[0]),
            u(values[1]),
            u(values[2]),
            values[3],
            values[4],
            values[5],
            u(values[6]),
            u(values[7]),
            u(values[8]),
        ]

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
        self.speed_override = [
            canon.GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE(s) for s in range(NUM_SPINDLES_MAX)
        ]
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
                    self.input_index, int(self.parameters[5399] != 0.0)
                )
            else:
                self.parameters[5399] = canon.GET_EXTERNAL_ANALOG_INPUT(
                    self.input_index, self.parameters[5399]
                )
            self.input_flag = False

    def set_probe_data(self) -> None:
        self.refresh_actual_position()
        probe = self.canon.GET_EXTERNAL_PROBE_POSITION()
        pars = self.parameters
        for k in range(9):
            value = probe[k]
            if (
                3 <= k <= 5
                and (self.a_axis_wrapped, self.b_axis_wrapped, self.c_axis_wrapped)[k - 3]
            ):
                value = math.fmod(value, 360.0)
                if value < 0:
                    value += 360.0
            pars[5061 + k] = value
        pars[5070] = float(self.canon.GET_EXTERNAL_PROBE_TRIPPED_VALUE())

    # ============================================================ open/close
    def _load_file(self, filename: str) -> list[str] | None:
        """The file's lines, each with its newline (as fgets gives them), read in pieces
        of LOAD_CHUNK_BYTES with ``on_progress()`` called between them: a caller that must
        stay alive (task beats its heartbeat) is not blocked for a whole large program."""
        lines: list[str] = []
        tail = ""
        progress = self.on_progress
        try:
            with open(filename, "rb") as handle:
                found = os.fstat(handle.fileno())
                stamp = (found.st_mtime_ns, found.st_size)
                if self._file_stamps.get(filename) == stamp and filename in self._file_cache:
                    return self._file_cache[filename]  # unchanged since read (a program re-run)
                while True:
                    data = handle.read(LOAD_CHUNK_BYTES)
                    if not data:
                        break
                    pieces = (tail + data.decode("latin-1")).split("\n")
                    tail = pieces.pop()  # an unfinished line: the next piece ends it
                    lines += [piece + "\n" for piece in pieces]
                    if progress is not None:
                        progress()
        except OSError:
            return None
        if tail:
            lines.append(tail)  # the last line had no newline
        self._file_stamps[filename] = stamp
        return lines

    def open(self, filename: str) -> int:
        try:
            return self._open(filename)
        except InterpError as error:
            self._note_stack(error)
            raise

    def _open(self, filename: str) -> int:
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
            self.linetext = line[: LINELEN - 1]  # fgets() leaves the raw line there
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
        self._fast = self._planned = None
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
        self.stop_python()
        return INTERP_OK

    def on_abort(self, reason: int, message: str = "") -> int:
        """After an abort: reset, and run [RS274NGC]ON_ABORT_COMMAND with the reason as its
        argument (REMAP-037); returns -1 when there is none, else its status."""
        command = self.abort_command(reason)
        if command is None:
            return -1
        return self.execute(command)

    def abort_command(self, reason: int) -> str | None:
        """What on_abort does before it runs ON_ABORT_COMMAND, for a caller that runs the
        command itself (task, as an MDI command): reset, forget the flags an interrupted
        remap may have left set; the command, an O-word call with the reason (LinuxCNC's
        EMC_ABORT_*) as its argument, or None when there is none."""
        self.reset()
        self.mdi_interrupt = False
        self.toolchange_flag = self.probe_flag = self.input_flag = False
        command = self.on_abort_command
        if not command:
            return None
        if command.lower().replace(" ", "").endswith("call"):  # O<on_abort> call [reason]
            return f"{command} [{reason}]"
        return command  # any other MDI line (e.g. M9) as it is

    # ================================================================= read
    def read(self, command: str | None = None) -> int:
        if self.call_state and command is None:
            # a Python handler waits to resume: its block is executed again (remap.py)
            status = self.resume_read()
            if status is not None:
                return status
        try:
            lines = self.file_lines
            if (
                command is None
                and self._plans  # (programs without O-words have none)
                and lines is not None
                and self.file_pos < len(lines)
                and not (self.probe_flag or self.toolchange_flag or self.input_flag)
            ):
                # a line read before: its plan, if it has one (see compiled.py); here, not
                # in _read, as loops read little else (a Python call less for each line)
                plan = self._plans.get(lines[self.file_pos])
                if plan is not None:
                    self._fast = self._planned = None
                    if plan.read(self):
                        return INTERP_OK
                    return self._read(command, has_plan=True)
            return self._read(command)
        except InterpError as error:
            self._note_stack(error)
            self._unwind_after_error()
            raise

    def _read(self, command: str | None, has_plan: bool = False) -> int:
        """Read a line (``has_plan``: the line's plan declined to read it)."""
        self._fast = self._planned = None  # a line read but never executed is dropped
        lines = self.file_lines
        raw = None
        if (
            command is None
            and lines is not None
            and self.file_pos < len(lines)
            and not (self.probe_flag or self.toolchange_flag or self.input_flag)
        ):
            raw = lines[self.file_pos]
            # the common case first: a plain motion line from the file (see _fast_read)
            # (a comment, a NUL or anything unusual makes _FAST_LINE fail: general path)
            if not has_plan and raw[:1] in _FAST_FIRST and len(raw) < LINELEN - 1:
                text = raw.rstrip(" \t\n\r\f\v")
                line = downcase(text)
                match = _FAST_LINE.match(line)
                if (
                    match is not None
                    and not self._no_fast
                    and self._fast_read(match.group(2), match.groups()[2:])
                ):
                    canon = self.canon
                    pars = self.parameters
                    pars[5600] = canon.GET_EXTERNAL_TC_FAULT()
                    pars[5601] = canon.GET_EXTERNAL_TC_REASON()
                    pars[5420:5429] = self.current
                    pars[5021:5030] = self.abs_position()
                    self.file_pos += 1
                    self.sequence_number += 1
                    self.linetext = text
                    self.blocktext = line
                    self.line_length = len(line)
                    self.parameter_assignments = ()
                    return INTERP_OK
        self.read_inputs()
        if command is None and self.file_lines is None:
            return INTERP_FILE_NOT_OPEN
        self.parameters[5420:5429] = self.current
        self.parameters[5021:5030] = self.abs_position()
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
                if raw is not None and self.offset_map:
                    # (only programs with O-words read lines again: the others never
                    # fill the plan table)
                    self._plan_line(raw)
                match = _FAST_LINE.match(self.blocktext)
                if (
                    match is not None
                    and not self._no_fast
                    and self._fast_read(match.group(2), match.groups()[2:])
                ):
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

    def _plan_line(self, raw: str) -> None:
        """Plan a file line the second time it is read (the first read only notes it)."""
        plans = self._plans
        plan = plans.get(raw)
        if plan is None:
            plans[raw] = _SEEN_ONCE
        elif plan is _SEEN_ONCE and "\x00" not in raw:
            plans[raw] = plan_line(self._compiler, self.linetext, self.blocktext) or _NO_PLAN

    def begin_planned_line(self, plan: LinePlan) -> int:
        """What reading a line does before parsing it (read_inputs, read_text), for a line
        taken by its plan; returns the line's position."""
        canon = self.canon
        pars = self.parameters
        pars[5600] = canon.GET_EXTERNAL_TC_FAULT()
        pars[5601] = canon.GET_EXTERNAL_TC_REASON()
        pars[5420:5429] = self.current
        pars[5021:5030] = self.abs_position()
        offset = self.file_pos
        self.file_pos = offset + 1
        self.sequence_number += 1
        self.linetext = plan.text
        self.blocktext = plan.line
        self.line_length = len(plan.line)
        self.parameter_assignments = []
        return offset

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
                raw = raw[: raw.index("\x00")]  # C strings end at NUL
            self.file_pos = pos + 1
            self.sequence_number += 1
            if len(raw) >= LINELEN - 1:
                self.linetext = raw[: LINELEN - 1]
                raise InterpError("Command too long")
            raw = raw.rstrip(" \t\n\r\f\v")
            self.linetext = raw
            if "(" in raw or ";" in raw or "\n" in raw:
                line = close_and_downcase(raw)
            else:
                line = downcase(raw)
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
    def _fast_read(self, g: str | None, words, feed: float | None = None) -> bool:
        """Take a plain ``[Nn] [G0|G1] X.. Y.. Z.. [F..]`` line without building a Block:
        its end point, to move to when executed. ``words`` are the values of X Y Z A B C
        (numbers or their text; None where the line has none); ``feed`` the F word's value
        (not negative), if the line has one.

        Only lines whose outcome is certain go this way (no error possible, no special
        state); everything else takes the general path, so the result is the same.
        """
        if self.skipping_o or self.cutter_comp_side or self.lathe_diameter_mode:
            return False
        if g is None:
            move = self.motion_mode
            if move != G_0 and move != G_1:
                return False
        else:
            move = G_1 if g == "1" else G_0
        if feed is None:
            if move == G_1 and (self.feed_mode != UNITS_PER_MINUTE or self.feed_rate == 0.0):
                return False
        elif self.feed_mode != UNITS_PER_MINUTE or (move == G_1 and feed == 0.0):
            return False
        if (words[3] is not None or words[4] is not None or words[5] is not None) and (
            self.a_axis_wrapped
            or self.b_axis_wrapped
            or self.c_axis_wrapped
            or self.a_indexer_jnum != -1
            or self.b_indexer_jnum != -1
            or self.c_indexer_jnum != -1
        ):
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
        self._fast = (move, ends, feed)
        return True

    def _fast_execute(self) -> int:
        move, ends, feed = self._fast
        self._fast = None
        if feed is not None:  # (as execute_block sets it, before the motion)
            self.feed_rate = feed
            self._enq("SET_FEED_RATE", feed)
        self.cycle_il_flag = False
        self.arc_not_allowed = False
        self.motion_mode = move
        self.write_canon_state_tag(None)
        if move == G_0:
            self.canon.STRAIGHT_TRAVERSE(self.sequence_number, *ends)
        else:
            self.canon.STRAIGHT_FEED(self.sequence_number, *ends)
        self.current = ends
        return INTERP_OK

    def _fast_assign(self, _unused: None) -> int:
        """Execute a line of parameter settings taken by its plan (as _execute would)."""
        self.apply_parameter_assignments()
        return INTERP_OK

    def apply_parameter_assignments(self) -> None:
        """Set the parameters the line read assigned: RS274/NGC sets them all together,
        after the line is read, so ``#1=2 #2=#1`` reads the old #1."""
        pars = self.parameters
        for index, value in self.parameter_assignments:
            pars[index] = value
        if self.named_parameter_assignments:
            for name, value in self.named_parameter_assignments:
                self.store_named_param(name, value)
            self.named_parameter_assignments = []

    def parse_line(self, line: str, block: Block) -> None:
        self.read_items(block, line)
        if not self.skipping_o:
            self.enhance_block(block)
            self.check_items(block)
            if self.remaps is not None:
                self.find_remappings(block)

    # ================================================================ execute
    def execute(self, command: str | None = None) -> int:
        if command is None:
            # a line taken by the fast path or by its plan: straight to its execution
            if self._fast is not None:
                return self._fast_execute()
            planned = self._planned
            if planned is not None:
                self._planned = None
                try:
                    return planned[0](planned[1])
                except InterpError as error:
                    self._note_stack(error)
                    self._unwind_after_error()
                    raise
        try:
            return self._execute(command)
        except InterpError as error:
            self._note_stack(error)
            self._unwind_after_error()
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
        planned = self._planned
        if planned is not None:
            self._planned = None
            return planned[0](planned[1])
        block = self.block
        if self.is_mdi_call_sliced or block.o_name is not None or self.mdi_interrupt:
            if self.is_mdi_call_sliced:  # the last slice ended inside an MDI call: read on
                self.is_mdi_call_sliced = False
                mdi_mode = True
            else:
                status = self.convert_control_functions(block)
                if status != INTERP_OK:
                    return status
                if self.mdi_interrupt:
                    self.mdi_interrupt = False
                    mdi_mode = True
            if mdi_mode:
                return self.run_mdi_call(is_finishing=True)
            self.mdi_interrupt = False
            return INTERP_OK
        if self.skipping_o:
            return INTERP_OK
        self.apply_parameter_assignments()
        if self.line_length != 0:
            if block.remappings:
                return self.execute_remapped_block(block, mdi_mode)
            return self.execute_block(block)
        return INTERP_OK

    def run_mdi_call(self, is_finishing: bool) -> int:
        """An MDI line's subroutine call (or remap) runs to its end, in slices up to
        ``slice_deadline``; ``is_finishing``: then FINISH() (an MDI line's own call)."""
        while self.call_level:
            deadline = self.slice_deadline
            if deadline is not None and time.monotonic() >= deadline:
                self.is_mdi_call_sliced = True
                return INTERP_OK
            status = self.read()
            if status > INTERP_MIN_ERROR:  # e.g. seeking a subroutine no file defines
                raise InterpError("File not open")
            status = self.execute()
            if status != INTERP_OK:
                if status == INTERP_EXECUTE_FINISH:
                    self.mdi_interrupt = True
                return status
        self.mdi_interrupt = False
        if is_finishing:
            self.canon.FINISH()
            self.offset_map.clear()
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
        axis_flag = (
            block.x_flag
            or block.y_flag
            or block.z_flag
            or block.a_flag
            or block.b_flag
            or block.c_flag
            or block.u_flag
            or block.v_flag
            or block.w_flag
        )
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
                if (
                    not axis_flag
                    and not polar_flag
                    and mode1
                    not in (
                        G_0,
                        G_1,
                        G_2,
                        G_3,
                        G_5_2,
                        G_70,
                        G_71,
                        G_71_1,
                        G_71_2,
                        G_72,
                        G_72_1,
                        G_72_2,
                    )
                    and not self.is_user_gcode(mode1)
                ):
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
                    "Between G5.2 and G5.3 codes, only additional G5.2 codes are allowed."
                )
        elif mode0 == G_53:
            if block.motion_to_be not in (G_0, G_1):
                raise InterpError("Must use g0 or g1 with g53")
            dm = block.g_modes[GM_DISTANCE_MODE]
            if dm == G_91 or (dm != G_90 and self.distance_mode == MODE_INCREMENTAL):
                raise InterpError("Cannot use g53 incremental")

    def check_other_codes(self, block: Block) -> None:
        if self.remaps is not None and self.has_user_code(block):
            return  # the remap's argspec says which words it takes
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
            g_modes[7] in (G_41, G_42, G_41_1, G_42_1) or g7x or g_modes[14] == G_96
        ):
            raise InterpError(
                "D word with no G41, G41.1, G42, G42.1, G71, G71.1, G71.2 or G96 to use it"
            )
        if block.dollar_flag and not (
            motion in (G_76, G_33, G_33_1, G_95, G_96, G_97)
            or m_modes[7] in (3, 4, 5, 19)
            or m_modes[9] == 51
            or block.s_flag
        ):
            raise InterpError(
                "$ (spindle selection) word with no M3, M4, M5, M19, M51, G33, G33.1, G76, G95,"
                " G96 or G97 to use it"
            )
        if block.e_flag and not (
            motion in (G_76, G_33, G_33_1, G_70) or m_modes[5] in (66, 67, 68)
        ):
            raise InterpError("E word with no G70, G76, M66, M67 or M68 to use it")
        if block.h_flag and not (
            g_modes[GM_TOOL_LENGTH_OFFSET] in (G_43, G_43_2) or motion == G_76
        ):
            raise InterpError("H word with no G43 or G76 to use it")
        if block.i_flag and not (
            motion
            in (G_2, G_3, 50, 51, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2, G_76, G_87, G_33_1)
            or g_modes[GM_MODAL_0] == G_10
        ):
            raise InterpError("I word with no G2, G3, G5, G5.1, G10, G33.1, G76, or G87 to use it")
        if block.j_flag and not (
            motion in (G_2, G_3, 50, 51, G_76, G_87) or g_modes[GM_MODAL_0] == G_10
        ):
            raise InterpError("J word with no G2, G3, G5, G5.1, G10, G76 or G87 to use it")
        if block.k_flag and motion not in (G_2, G_3, G_33, G_33_1, G_76, G_87):
            raise InterpError("K word with no G2, G3, G33, G33.1, G76, or G87 to use it")
        if block.l_number != -1 and not (
            G_81 <= motion <= G_89
            or motion in (G_76, G_5_2, G_73)
            or g_modes[GM_MODAL_0] == G_10
            or g_modes[GM_CUTTER_COMP] in (G_41, G_41_1, G_42, G_42_1)
            or m_modes[5] == 66
            or block.o_type == M_98
        ):
            raise InterpError(
                "L word with no G10, cutter compensation, canned cycle, "
                "digital/analog input, M98 or NURBS code"
            )
        if block.p_flag:
            if not (
                g_modes[GM_MODAL_0] in (G_10, G_4)
                or g_modes[GM_CONTROL_MODE] == G_64
                or motion in (G_76, G_82, G_86, G_88, G_89, 50, G_5_2, G_70, G_2, G_3, G_74, G_84)
                or m_modes[9] in (50, 51, 52, 53)
                or m_modes[5] in (62, 63, 64, 65, 66)
                or m_modes[7] == 19
                or block.user_m == 1
                or block.o_type == M_98
            ):
                raise InterpError(
                    "P word with no G2 G3 G4 G10 G64 G5 G5.2 G76 G82 G86 G88 G89"
                    " or M50 M51 M52 M53 M62 M63 M64 M65 M66 M98 or user M code to use it"
                )
            p_value = round_to_int(block.p_number)
            if (motion in (G_2, G_3) or m_modes[7] == 19) and abs(p_value - block.p_number) > 0.001:
                raise InterpError("P value not an integer with M19 G2 or G3")
            if m_modes[7] == 19 and (p_value > 2 or p_value < 0):
                raise InterpError("P value must be 0,1,or 2 with M19")
            if motion in (G_2, G_3) and p_value < 1:
                raise InterpError("P value should be 1 or greater with G2 or G3")
        if block.q_number != -1.0 and not (
            motion in (G_83, G_73, 50, G_76, G_70, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2)
            or block.user_m == 1
            or m_modes[5] in (66, 67, 68)
            or g_modes[GM_MODAL_0] == G_10
            or m_modes[6] == 61
            or g_modes[GM_CONTROL_MODE] == G_64
            or m_modes[7] == 19
        ):
            raise InterpError(
                "Q word with no G5, G10, G64, G73, G76, G83, M19, M66, M67, M68 "
                "or user M code that uses it"
            )
        if block.r_flag:
            if not (
                motion in (G_2, G_3, G_76, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2, G_73, G_74)
                or G_81 <= motion <= G_89
                or g_modes[GM_CUTTER_COMP] in (G_41_1, G_42_1)
                or g_modes[GM_MODAL_0] == G_10
                or m_modes[7] == 19
            ):
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
        """Execute a block in LinuxCNC's order of execution (execute_block_steps is the same
        order, step by step, for blocks with remapped codes)."""
        block.line_number = self.sequence_number
        if block.comment:
            self.convert_comment(block.comment)
        if block.g_modes[GM_SPINDLE_MODE] != -1:
            self._spindle_mode_step(block)
        if block.g_modes[GM_FEED_MODE] != -1:
            self._feed_mode_step(block)
        if block.f_flag and self.feed_mode != INVERSE_TIME:
            self.feed_rate = block.f_number
            self._enq("SET_FEED_RATE", block.f_number)
        if block.s_flag:
            self._speed_step(block)
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
        self.write_canon_state_tag(block)
        return INTERP_OK

    def execute_block_steps(self, block: Block) -> int:
        """execute_block for a block with remapped codes (remap.py): each step runs once
        (``block.breadcrumbs``), up to a remapped one, which starts its remap and returns
        ``-step``; executed again when that remap has finished, the block continues."""
        done = block.breadcrumbs
        remapped = block.remappings
        remaps = self.remaps
        block.line_number = self.sequence_number
        g_modes = block.g_modes
        m_modes = block.m_modes
        if block.comment and _once(done, STEP_COMMENT):
            self.convert_comment(block.comment)
        if g_modes[GM_SPINDLE_MODE] != -1 and _once(done, STEP_SPINDLE_MODE):
            self._spindle_mode_step(block)
        if g_modes[GM_FEED_MODE] != -1 and _once(done, STEP_FEED_MODE):
            self._feed_mode_step(block)
        if block.f_flag and self.feed_mode != INVERSE_TIME and _once(done, STEP_SET_FEED_RATE):
            if STEP_SET_FEED_RATE in remapped:
                return self.convert_remapped_code(block, STEP_SET_FEED_RATE, remaps.letter["F"])
            self.feed_rate = block.f_number
            self._enq("SET_FEED_RATE", block.f_number)
        if block.s_flag and _once(done, STEP_SET_SPINDLE_SPEED):
            if STEP_SET_SPINDLE_SPEED in remapped:
                step = STEP_SET_SPINDLE_SPEED
                return self.convert_remapped_code(block, step, remaps.letter["S"])
            self._speed_step(block)
        if block.t_flag and _once(done, STEP_PREPARE):
            if STEP_PREPARE in remapped:
                return self.convert_remapped_code(block, STEP_PREPARE, remaps.letter["T"])
            self.convert_tool_select(block)
        for group, step, convert in _M_STEPS:
            code = m_modes[group]
            if code != -1 and _once(done, step):
                if step in remapped:
                    return self.convert_remapped_code(block, step, remaps.m[code])
                convert(self, block, code)
        if g_modes[GM_MODAL_0] == G_4 and _once(done, STEP_DWELL):
            self._enq("DWELL", block.p_number)
        for group, step, convert in _G_STEPS:
            if g_modes[group] != -1 and _once(done, step):
                convert(self, g_modes[group], block)
        motion = block.motion_to_be
        if motion != -1 and _once(done, STEP_MOTION):
            if STEP_MOTION in remapped:
                return self.convert_remapped_code(block, STEP_MOTION, remaps.g[motion])
            self.convert_motion(motion, block)
        if m_modes[4] != -1 and _once(done, STEP_MGROUP4):
            if STEP_MGROUP4 in remapped:
                return self.convert_remapped_code(block, STEP_MGROUP4, remaps.m[m_modes[4]])
            status = self.convert_stop(block)
            if status != INTERP_OK:
                return status
        if self.probe_flag or self.input_flag or self.toolchange_flag:
            return INTERP_EXECUTE_FINISH
        self.write_canon_state_tag(block)
        return INTERP_OK

    def _spindle_mode_step(self, block: Block) -> None:
        """G96/G97"""
        self.active_spindle = 0
        if block.dollar_flag:
            if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                raise InterpError("Invalid spindle ($) number in Spindle Mode command")
            self.active_spindle = int(block.dollar_number)
        self.convert_spindle_mode(self.active_spindle, block)

    def _feed_mode_step(self, block: Block) -> None:
        """G93/G94/G95"""
        self.active_spindle = 0
        if block.dollar_flag:
            if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                raise InterpError("Invalid spindle ($) number in Spindle Feed command")
            self.active_spindle = int(block.dollar_number)
        self.convert_feed_mode(block.g_modes[GM_FEED_MODE])

    def _g92_applied(self, g_code: int, block: Block) -> None:
        with contextlib.suppress(InterpError):  # LinuxCNC ignores this status
            self.convert_axis_offsets(g_code, block)

    def _speed_step(self, block: Block) -> None:
        """S"""
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
        elif lc.startswith("py,"):
            self.run_python(body[3:])
        elif lc.startswith("pyrun,"):
            self.run_python(body[6:])
        elif lc.startswith("pyreload"):
            self.require_python().reload_if_changed()
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
            self._last_expansion = done + self._last_expansion[len(done) :]
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
                    try:
                        exists, value = self.find_named_param("".join(name))
                    except InterpError:  # a namedparams function failed: no value
                        exists = False
                    found = bool(exists)
                else:
                    out.append("#")
                    continue
                if found:
                    pvalue = 0.0 if abs(value) < 0.0001 else value
                    text = c_format(fmt, pvalue)
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
                    self._enq(
                        "SET_SPINDLE_MODE", s, abs(block.d_number_float) if block.d_flag else 1e30
                    )

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
            self.convert_distance_mode(g[GM_DISTANCE_MODE])
        if g[GM_IJK_DISTANCE_MODE] != -1:
            self.convert_ijk_distance_mode(g[GM_IJK_DISTANCE_MODE])
        if g[GM_RETRACT_MODE] != -1:
            self.convert_retract_mode(g[GM_RETRACT_MODE])
        if g[GM_MODAL_0] != -1:
            self.convert_modal_0(g[GM_MODAL_0], block)
        if g[GM_G92_IS_APPLIED] != -1:
            with contextlib.suppress(InterpError):  # LinuxCNC ignores this status
                self.convert_axis_offsets(g[GM_G92_IS_APPLIED], block)
        if block.motion_to_be != -1:
            self.convert_motion(block.motion_to_be, block)

    def convert_distance_mode(self, g_code: int) -> None:
        mode = MODE_ABSOLUTE if g_code == G_90 else MODE_INCREMENTAL
        if mode != self.distance_mode:
            self._enq(
                "COMMENT",
                "interpreter: distance mode changed to "
                + ("absolute" if mode == MODE_ABSOLUTE else "incremental"),
            )
            self.distance_mode = mode

    def convert_ijk_distance_mode(self, g_code: int) -> None:
        mode = MODE_ABSOLUTE if g_code == G_90_1 else MODE_INCREMENTAL
        if mode != self.ijk_distance_mode:
            self._enq(
                "COMMENT",
                "interpreter: IJK distance mode changed to "
                + ("absolute" if mode == MODE_ABSOLUTE else "incremental"),
            )
            self.ijk_distance_mode = mode

    def convert_retract_mode(self, g_code: int) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot change retract mode with cutter radius compensation on")
        if g_code == G_98:
            self._enq("COMMENT", "interpreter: retract mode set to old_z")
            self.retract_mode = OLD_Z
        else:
            self._enq("COMMENT", "interpreter: retract mode set to r_plane")
            self.retract_mode = R_PLANE

    def convert_set_plane(self, g_code: int) -> None:
        side = self.cutter_comp_side
        if side:
            if (
                (g_code == G_17 and self.plane != C.PLANE_XY)
                or (g_code == G_18 and self.plane != C.PLANE_XZ)
                or (g_code == G_19 and self.plane != C.PLANE_YZ)
            ):
                raise InterpError("Cannot change planes with cutter radius compensation on")
            if g_code == G_19:
                raise InterpError("Cutter radius compensation allowed only in XY, XZ planes")
        plane = {
            G_17: C.PLANE_XY,
            G_18: C.PLANE_XZ,
            G_19: C.PLANE_YZ,
            G_17_1: C.PLANE_UV,
            G_18_1: C.PLANE_UW,
            G_19_1: C.PLANE_VW,
        }[g_code]
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
        if (
            self.cutter_comp_side
            and self.cutter_comp_radius > 0.0
            and not self.cutter_comp_firstmove
        ):
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
                ok, tool = is_near_int(block.d_number_float)
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
        self._enq(
            "COMMENT",
            "interpreter: cutter radius compensation on " + ("right" if side == RIGHT else "left"),
        )
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

    # ================================================================= stop
    def convert_stop(self, block: Block) -> int:
        canon = self.canon
        cx, cy, _ = (
            self.comp_get_current() if self.plane in (C.PLANE_XY, C.PLANE_XZ) else (0.0, 0.0, 0.0)
        )
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
    def unwind_call(self, level: int = 0) -> None:
        """Return from every call (after an error), or from those above call ``level``."""
        while self.call_level > level:
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
        if level:
            return
        if self.remap_level and not self.sequence_number:
            # the line of the remapped code, in a program (LinuxCNC leaves the 0 of
            # enter_remap; for an MDI line there is no line to tell)
            outermost = self.remap_blocks[1]
            if not outermost.is_mdi_remap:
                self.sequence_number = outermost.saved_line_number
        self.sub_name = None
        self.remap_level = 0
        self.call_state = CS_NORMAL
        self.defining_sub = 0
        self.skipping_o = None
        self.skipping_to_sub = None
        self.offset_map.clear()
        self.mdi_interrupt = False
        self.is_mdi_call_sliced = False
        self.qc_reset()

    def _open_cached(self, filename: str) -> list[str] | None:
        lines = self._file_cache.get(filename)
        if lines is None:
            lines = self._load_file(filename)
            if lines is not None:
                self._file_cache[filename] = lines
        return lines


# A line of nothing but an optional N word, an optional G0/G1 and plain-number axis words in
# XYZABC order (other lines take the general path).
_NUM = r"([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+))"
_FAST_LINE = re.compile(
    r"(?:n(\d+))?(?:g0*([01])(?![0-9.]))?(?=[xyzabc])"
    + "".join(f"(?:{letter}{_NUM})?" for letter in "xyzabc")
    + r"\Z"
)
_EMPTY_BLOCK = Block()  # stands for blank lines; never executed


class _Uncached(dict):
    """A cache that keeps nothing: every line and value is read afresh."""

    def __setitem__(self, key, value) -> None:
        pass


class _NoPlan(LinePlan):
    """A line without a plan: read the general way."""

    def read(self, interp) -> bool:
        return False


_SEEN_ONCE = _NoPlan("", "")  # read once so far
_NO_PLAN = _NoPlan("", "")  # cannot be planned
_FAST_FIRST = frozenset("nNgGxXyYzZaAbBcC")


# execute_block_steps: convert_m's groups and convert_g's steps, in their order
_M_STEPS = (
    (5, STEP_M_GROUP[5], MCodesMixin.convert_m_group5),
    (6, STEP_M_GROUP[6], MCodesMixin.convert_m_group6),
    (7, STEP_M_GROUP[7], MCodesMixin.convert_m_group7),
    (8, STEP_M_GROUP[8], MCodesMixin.convert_m_group8),
    (9, STEP_M_GROUP[9], MCodesMixin.convert_m_group9),
    (10, STEP_M_GROUP[10], MCodesMixin.convert_m_group10),
)
_G_STEPS = (
    (GM_SET_PLANE, STEP_SET_PLANE, lambda i, code, b: i.convert_set_plane(code)),
    (GM_LENGTH_UNITS, STEP_LENGTH_UNITS, lambda i, code, b: i.convert_length_units(code)),
    (
        GM_LATHE_DIAMETER_MODE,
        STEP_LATHE_DIAMETER_MODE,
        lambda i, code, b: i.convert_lathe_diameter_mode(code, b),
    ),
    (GM_CUTTER_COMP, STEP_CUTTER_COMP, lambda i, code, b: i.convert_cutter_compensation(code, b)),
    (
        GM_TOOL_LENGTH_OFFSET,
        STEP_TOOL_LENGTH_OFFSET,
        lambda i, code, b: i.convert_tool_length_offset(code, b),
    ),
    (GM_COORD_SYSTEM, STEP_COORD_SYSTEM, lambda i, code, b: i.convert_coordinate_system(code)),
    (
        GM_CONTROL_MODE,
        STEP_CONTROL_MODE,
        lambda i, code, b: i.convert_control_mode(code, b.p_number, b.q_number),
    ),
    (GM_DISTANCE_MODE, STEP_DISTANCE_MODE, lambda i, code, b: i.convert_distance_mode(code)),
    (
        GM_IJK_DISTANCE_MODE,
        STEP_IJK_DISTANCE_MODE,
        lambda i, code, b: i.convert_ijk_distance_mode(code),
    ),
    (GM_RETRACT_MODE, STEP_RETRACT_MODE, lambda i, code, b: i.convert_retract_mode(code)),
    (GM_MODAL_0, STEP_MODAL_0, lambda i, code, b: i.convert_modal_0(code, b)),
    (GM_G92_IS_APPLIED, STEP_G92_IS_APPLIED, lambda i, code, b: i._g92_applied(code, b)),
)


def _once(done: set[int], step: int) -> bool:
    """LinuxCNC's ONCE(): whether ``step`` of a block is still to run (and tick it off)."""
    if step in done:
        return False
    done.add(step)
    return True


def _debug_flags(value: str | None) -> int:
    """[EMC]DEBUG: a number, often hexadecimal (0x00004000)."""
    if value is None:
        return 0
    word = value.split()[0] if value.split() else "0"
    try:
        return int(word, 0)
    except ValueError:
        try:
            return int(float(word))
        except ValueError:
            return 0


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
