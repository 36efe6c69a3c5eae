"""The ``emccanon`` module of user Python code: the canonical calls (PY-024).

Each function calls the canon of the interpreter whose Python code runs now
(``interpreter.this``), with LinuxCNC's arguments: in ``cnc rs274`` the calls are printed, in
task they become machine commands, in a preview they are drawn. ``enqueue_*`` calls wait
behind moves that cutter compensation holds back, as the interpreter's own calls do.
``GET_EXTERNAL_*`` calls read the world model, e.g. ``GET_EXTERNAL_DIGITAL_INPUT(0, 0)`` after
``WAIT(...)`` and ``yield INTERP_EXECUTE_FINISH`` (PY-017).
"""

from __future__ import annotations

from nml.axes import AXIS_LETTERS

from .. import canon as _c
from . import interpreter as _interpreter

# CANON_PLANE
CANON_PLANE_XY, CANON_PLANE_YZ, CANON_PLANE_XZ = _c.PLANE_XY, _c.PLANE_YZ, _c.PLANE_XZ
CANON_PLANE_UV, CANON_PLANE_VW, CANON_PLANE_UW = _c.PLANE_UV, _c.PLANE_VW, _c.PLANE_UW
# CANON_UNITS
CANON_UNITS_INCHES, CANON_UNITS_MM, CANON_UNITS_CM = _c.UNITS_INCHES, _c.UNITS_MM, _c.UNITS_CM
# CANON_MOTION_MODE
CANON_EXACT_STOP, CANON_EXACT_PATH, CANON_CONTINUOUS = _c.EXACT_STOP, _c.EXACT_PATH, _c.CONTINUOUS
# CANON_SPEED_FEED_MODE
CANON_SYNCHED, CANON_INDEPENDENT = 1, 2
# CANON_DIRECTION
CANON_STOPPED, CANON_CLOCKWISE, CANON_COUNTERCLOCKWISE = (
    _c.STOPPED,
    _c.CLOCKWISE,
    _c.COUNTERCLOCKWISE,
)
# CANON_FEED_REFERENCE
CANON_WORKPIECE, CANON_XYZ = _c.CANON_WORKPIECE, _c.CANON_XYZ
# CANON_SIDE
CANON_SIDE_RIGHT, CANON_SIDE_LEFT, CANON_SIDE_OFF = _c.SIDE_RIGHT, _c.SIDE_LEFT, _c.SIDE_OFF
# CANON_AXIS
(
    CANON_AXIS_X,
    CANON_AXIS_Y,
    CANON_AXIS_Z,
    CANON_AXIS_A,
    CANON_AXIS_B,
    CANON_AXIS_C,
    CANON_AXIS_U,
    CANON_AXIS_V,
    CANON_AXIS_W,
) = range(1, 10)


def _interp():
    view = _interpreter.this
    if view is None:
        raise RuntimeError("emccanon: no interpreter is running Python code")
    return view._interp


def _canon():
    return _interp().canon


def _pose(value) -> list[float]:
    """An EmcPose (or a sequence of 9 numbers) as a list."""
    if hasattr(value, "as_list"):
        return value.as_list()
    return [float(v) for v in value]


# calls that take LinuxCNC's arguments unchanged
_DIRECT = (
    "ARC_FEED",
    "CHANGE_TOOL",
    "CHANGE_TOOL_NUMBER",
    "CLEAR_AUX_OUTPUT_BIT",
    "CLEAR_MOTION_OUTPUT_BIT",
    "COMMENT",
    "DISABLE_ADAPTIVE_FEED",
    "DISABLE_FEED_HOLD",
    "DISABLE_FEED_OVERRIDE",
    "DISABLE_SPEED_OVERRIDE",
    "DWELL",
    "ENABLE_ADAPTIVE_FEED",
    "ENABLE_FEED_HOLD",
    "ENABLE_FEED_OVERRIDE",
    "ENABLE_SPEED_OVERRIDE",
    "FINISH",
    "FLOOD_OFF",
    "FLOOD_ON",
    "GET_BLOCK_DELETE",
    "GET_EXTERNAL_ADAPTIVE_FEED_ENABLE",
    "GET_EXTERNAL_ANALOG_INPUT",
    "GET_EXTERNAL_ANGLE_UNITS",
    "GET_EXTERNAL_AXIS_MASK",
    "GET_EXTERNAL_DIGITAL_INPUT",
    "GET_EXTERNAL_FEED_HOLD_ENABLE",
    "GET_EXTERNAL_FEED_OVERRIDE_ENABLE",
    "GET_EXTERNAL_FEED_RATE",
    "GET_EXTERNAL_FLOOD",
    "GET_EXTERNAL_LENGTH_UNITS",
    "GET_EXTERNAL_MIST",
    "GET_EXTERNAL_MOTION_CONTROL_MODE",
    "GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE",
    "GET_EXTERNAL_MOTION_CONTROL_TOLERANCE",
    "GET_EXTERNAL_PLANE",
    "GET_EXTERNAL_PROBE_TRIPPED_VALUE",
    "GET_EXTERNAL_QUEUE_EMPTY",
    "GET_EXTERNAL_SELECTED_TOOL_SLOT",
    "GET_EXTERNAL_SPEED",
    "GET_EXTERNAL_SPINDLE",
    "GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE",
    "GET_EXTERNAL_TC_FAULT",
    "GET_EXTERNAL_TC_REASON",
    "GET_EXTERNAL_TOOL_SLOT",
    "GET_EXTERNAL_TRAVERSE_RATE",
    "GET_OPTIONAL_PROGRAM_STOP",
    "LOG",
    "LOGAPPEND",
    "LOGCLOSE",
    "LOGOPEN",
    "MESSAGE",
    "MIST_OFF",
    "MIST_ON",
    "ON_RESET",
    "OPTIONAL_PROGRAM_STOP",
    "ORIENT_SPINDLE",
    "PALLET_SHUTTLE",
    "PROGRAM_END",
    "PROGRAM_STOP",
    "RELOAD_TOOLDATA",
    "RIGID_TAP",
    "SELECT_PLANE",
    "SELECT_TOOL",
    "SET_AUX_OUTPUT_BIT",
    "SET_AUX_OUTPUT_VALUE",
    "SET_BLOCK_DELETE",
    "SET_FEED_MODE",
    "SET_FEED_RATE",
    "SET_FEED_REFERENCE",
    "SET_G5X_OFFSET",
    "SET_G92_OFFSET",
    "SET_MOTION_CONTROL_MODE",
    "SET_MOTION_OUTPUT_BIT",
    "SET_MOTION_OUTPUT_VALUE",
    "SET_NAIVECAM_TOLERANCE",
    "SET_OPTIONAL_PROGRAM_STOP",
    "SET_SPINDLE_MODE",
    "SET_SPINDLE_SPEED",
    "SET_TRAVERSE_RATE",
    "SET_XY_ROTATION",
    "START_CHANGE",
    "START_SPEED_FEED_SYNCH",
    "STOP_SPEED_FEED_SYNCH",
    "STOP_SPINDLE_TURNING",
    "STRAIGHT_FEED",
    "STRAIGHT_PROBE",
    "STRAIGHT_TRAVERSE",
    "TURN_PROBE_OFF",
    "TURN_PROBE_ON",
    "USE_LENGTH_UNITS",
    "WAIT",
)


def _direct(name: str):
    def call(*args):
        return getattr(_canon(), name)(*args)

    call.__name__ = call.__qualname__ = name
    call.__doc__ = f"The canonical call {name}."
    return call


for _name in _DIRECT:
    globals()[_name] = _direct(_name)


def START_SPINDLE_CLOCKWISE(spindle: int, wait_for_atspeed: int = 1) -> None:
    _canon().START_SPINDLE_CLOCKWISE(spindle)


def START_SPINDLE_COUNTERCLOCKWISE(spindle: int, wait_for_atspeed: int = 1) -> None:
    _canon().START_SPINDLE_COUNTERCLOCKWISE(spindle)


def SELECT_POCKET(pocket: int, tool: int) -> None:
    """Prepare ``tool`` (in ``pocket``): LinuxCNC 2.9 prepares by tool number."""
    _canon().SELECT_TOOL(tool)


def CANON_ERROR(text: str) -> None:
    if text:
        _canon().CANON_ERROR(text)


def USE_TOOL_LENGTH_OFFSET(offset) -> None:
    _canon().USE_TOOL_LENGTH_OFFSET(_pose(offset))


def SET_TOOL_TABLE_ENTRY(
    pocket: int,
    toolno: int,
    offset,
    diameter: float,
    frontangle: float,
    backangle: float,
    orientation: int,
) -> None:
    _canon().SET_TOOL_TABLE_ENTRY(
        pocket, toolno, _pose(offset), diameter, frontangle, backangle, orientation
    )


def GET_EXTERNAL_TOOL_TABLE(pocket: int):
    from .view import ToolView

    return ToolView(_canon().GET_EXTERNAL_TOOL_TABLE(pocket))


def GET_EXTERNAL_PROBE_VALUE() -> float:
    return float(_canon().GET_EXTERNAL_PROBE_TRIPPED_VALUE())


def _component(getter: str, index: int):
    def call() -> float:
        return getattr(_canon(), getter)()[index]

    return call


for _index, _axis in enumerate(AXIS_LETTERS):
    globals()[f"GET_EXTERNAL_POSITION_{_axis}"] = _component("GET_EXTERNAL_POSITION", _index)
    globals()[f"GET_EXTERNAL_PROBE_POSITION_{_axis}"] = _component(
        "GET_EXTERNAL_PROBE_POSITION", _index
    )
    globals()[f"GET_EXTERNAL_TOOL_LENGTH_{_axis}OFFSET"] = _component(
        "GET_EXTERNAL_TOOL_LENGTH_OFFSET", _index
    )


# the interpreter's queued calls (held back behind moves cutter compensation holds)
def _queued(name: str):
    def call(*args):
        return _interp()._enq(name, *args)

    call.__name__ = call.__qualname__ = f"enqueue_{name}"
    return call


for _name in (
    "SET_FEED_RATE",
    "SET_FEED_MODE",
    "DWELL",
    "MIST_ON",
    "MIST_OFF",
    "FLOOD_ON",
    "FLOOD_OFF",
    "START_SPINDLE_CLOCKWISE",
    "START_SPINDLE_COUNTERCLOCKWISE",
    "STOP_SPINDLE_TURNING",
    "SET_SPINDLE_MODE",
    "SET_SPINDLE_SPEED",
    "COMMENT",
    "START_CHANGE",
    "ORIENT_SPINDLE",
):
    globals()[f"enqueue_{_name}"] = _queued(_name)


def __getattr__(name: str):
    raise AttributeError(f"emccanon.{name} is not provided by this controller")
