"""The EMC message catalogue (SPEC NML-053..072).

Type numbers are LinuxCNC 2.9's (``src/emc/nml_intf/emc.hh``), written out here as a table;
every message is filled with a distinct non-default value in every field and must come
back unchanged through both encodings.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

import pytest

from nml import emc
from nml.codec import Encoding, decode, encode
from nml.message import RCS_CMD_MSG, RCS_STAT_MSG, Array, MessageKind, Nested, Scalar, Struct, Text
from nml.registry import REGISTRY

# Every EMC message type of LinuxCNC 2.9 and its number, grouped as in SPEC NML-056..069.
# LinuxCNC spells three TRAJ names differently from the SPEC text: EMC_TRAJ_SET_SPINDLESYNC
# (SPEC: ..._SPINDLE_SYNC), EMC_TRAJ_SET_FO_ENABLE and EMC_TRAJ_SET_SO_ENABLE (SPEC: F0, S0).
LINUXCNC_TYPES = {
    # OPERATOR (NML-056)
    "EMC_OPERATOR_ERROR": 11,
    "EMC_OPERATOR_TEXT": 12,
    "EMC_OPERATOR_DISPLAY": 13,
    # JOINT (NML-057)
    "EMC_JOINT_SET_JOINT": 101,
    "EMC_JOINT_SET_UNITS": 102,
    "EMC_JOINT_SET_MIN_POSITION_LIMIT": 107,
    "EMC_JOINT_SET_MAX_POSITION_LIMIT": 108,
    "EMC_JOINT_SET_FERROR": 111,
    "EMC_JOINT_SET_HOMING_PARAMS": 112,
    "EMC_JOINT_SET_MIN_FERROR": 115,
    "EMC_JOINT_SET_MAX_VELOCITY": 116,
    "EMC_JOINT_INIT": 118,
    "EMC_JOINT_HALT": 119,
    "EMC_JOINT_ABORT": 120,
    "EMC_JOINT_ENABLE": 121,
    "EMC_JOINT_DISABLE": 122,
    "EMC_JOINT_HOME": 123,
    "EMC_JOINT_ACTIVATE": 127,
    "EMC_JOINT_DEACTIVATE": 128,
    "EMC_JOINT_OVERRIDE_LIMITS": 129,
    "EMC_JOINT_LOAD_COMP": 131,
    "EMC_JOINT_SET_BACKLASH": 134,
    "EMC_JOINT_UNHOME": 135,
    "EMC_JOINT_STAT": 198,
    # AXIS (NML-058)
    "EMC_AXIS_STAT": 199,
    # JOG (NML-059)
    "EMC_JOG_CONT": 124,
    "EMC_JOG_INCR": 125,
    "EMC_JOG_ABS": 126,
    "EMC_JOG_STOP": 136,
    # TRAJ (NML-060)
    "EMC_TRAJ_SET_AXES": 201,
    "EMC_TRAJ_SET_UNITS": 202,
    "EMC_TRAJ_SET_CYCLE_TIME": 203,
    "EMC_TRAJ_SET_MODE": 204,
    "EMC_TRAJ_SET_VELOCITY": 205,
    "EMC_TRAJ_SET_ACCELERATION": 206,
    "EMC_TRAJ_SET_MAX_VELOCITY": 207,
    "EMC_TRAJ_SET_MAX_ACCELERATION": 208,
    "EMC_TRAJ_SET_SCALE": 209,
    "EMC_TRAJ_SET_MOTION_ID": 210,
    "EMC_TRAJ_INIT": 211,
    "EMC_TRAJ_HALT": 212,
    "EMC_TRAJ_ENABLE": 213,
    "EMC_TRAJ_DISABLE": 214,
    "EMC_TRAJ_ABORT": 215,
    "EMC_TRAJ_PAUSE": 216,
    "EMC_TRAJ_STEP": 217,
    "EMC_TRAJ_RESUME": 218,
    "EMC_TRAJ_DELAY": 219,
    "EMC_TRAJ_LINEAR_MOVE": 220,
    "EMC_TRAJ_CIRCULAR_MOVE": 221,
    "EMC_TRAJ_SET_TERM_COND": 222,
    "EMC_TRAJ_SET_OFFSET": 223,
    "EMC_TRAJ_SET_G5X": 224,
    "EMC_TRAJ_SET_HOME": 225,
    "EMC_TRAJ_SET_ROTATION": 226,
    "EMC_TRAJ_SET_G92": 227,
    "EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG": 228,
    "EMC_TRAJ_PROBE": 229,
    "EMC_TRAJ_SET_TELEOP_ENABLE": 230,
    "EMC_TRAJ_SET_SPINDLESYNC": 232,
    "EMC_TRAJ_SET_SPINDLE_SCALE": 233,
    "EMC_TRAJ_SET_FO_ENABLE": 234,
    "EMC_TRAJ_SET_SO_ENABLE": 235,
    "EMC_TRAJ_SET_FH_ENABLE": 236,
    "EMC_TRAJ_RIGID_TAP": 237,
    "EMC_TRAJ_SET_RAPID_SCALE": 238,
    "EMC_TRAJ_STAT": 299,
    # MOTION (NML-061)
    "EMC_MOTION_INIT": 301,
    "EMC_MOTION_HALT": 302,
    "EMC_MOTION_ABORT": 303,
    "EMC_MOTION_SET_AOUT": 304,
    "EMC_MOTION_SET_DOUT": 305,
    "EMC_MOTION_ADAPTIVE": 306,
    "EMC_MOTION_STAT": 399,
    # TASK (NML-062)
    "EMC_TASK_INIT": 501,
    "EMC_TASK_HALT": 502,
    "EMC_TASK_ABORT": 503,
    "EMC_TASK_SET_MODE": 504,
    "EMC_TASK_SET_STATE": 505,
    "EMC_TASK_PLAN_OPEN": 506,
    "EMC_TASK_PLAN_RUN": 507,
    "EMC_TASK_PLAN_READ": 508,
    "EMC_TASK_PLAN_EXECUTE": 509,
    "EMC_TASK_PLAN_PAUSE": 510,
    "EMC_TASK_PLAN_STEP": 511,
    "EMC_TASK_PLAN_RESUME": 512,
    "EMC_TASK_PLAN_END": 513,
    "EMC_TASK_PLAN_CLOSE": 514,
    "EMC_TASK_PLAN_INIT": 515,
    "EMC_TASK_PLAN_SYNCH": 516,
    "EMC_TASK_PLAN_SET_OPTIONAL_STOP": 517,
    "EMC_TASK_PLAN_SET_BLOCK_DELETE": 518,
    "EMC_TASK_PLAN_OPTIONAL_STOP": 519,
    "EMC_TASK_PLAN_REVERSE": 520,
    "EMC_TASK_PLAN_FORWARD": 521,
    "EMC_TASK_STAT": 599,
    # TOOL (NML-063)
    "EMC_TOOL_INIT": 1101,
    "EMC_TOOL_HALT": 1102,
    "EMC_TOOL_ABORT": 1103,
    "EMC_TOOL_PREPARE": 1104,
    "EMC_TOOL_LOAD": 1105,
    "EMC_TOOL_UNLOAD": 1106,
    "EMC_TOOL_LOAD_TOOL_TABLE": 1107,
    "EMC_TOOL_SET_OFFSET": 1108,
    "EMC_TOOL_SET_NUMBER": 1109,
    "EMC_TOOL_START_CHANGE": 1110,
    "EMC_TOOL_STAT": 1199,
    # AUX (NML-064)
    "EMC_AUX_ESTOP_ON": 1206,
    "EMC_AUX_ESTOP_OFF": 1207,
    "EMC_AUX_ESTOP_RESET": 1208,
    "EMC_AUX_INPUT_WAIT": 1209,
    "EMC_AUX_STAT": 1299,
    # SPINDLE (NML-065)
    "EMC_SPINDLE_ON": 1304,
    "EMC_SPINDLE_OFF": 1305,
    "EMC_SPINDLE_INCREASE": 1309,
    "EMC_SPINDLE_DECREASE": 1310,
    "EMC_SPINDLE_CONSTANT": 1311,
    "EMC_SPINDLE_BRAKE_RELEASE": 1312,
    "EMC_SPINDLE_BRAKE_ENGAGE": 1313,
    "EMC_SPINDLE_SPEED": 1316,
    "EMC_SPINDLE_ORIENT": 1317,
    "EMC_SPINDLE_WAIT_ORIENT_COMPLETE": 1318,
    "EMC_SPINDLE_STAT": 1399,
    # COOLANT (NML-066)
    "EMC_COOLANT_MIST_ON": 1404,
    "EMC_COOLANT_MIST_OFF": 1405,
    "EMC_COOLANT_FLOOD_ON": 1406,
    "EMC_COOLANT_FLOOD_OFF": 1407,
    "EMC_COOLANT_STAT": 1499,
    # LUBE (NML-067)
    "EMC_LUBE_ON": 1504,
    "EMC_LUBE_OFF": 1505,
    "EMC_LUBE_STAT": 1599,
    # IO (NML-068)
    "EMC_IO_PLUGIN_CALL": 1113,
    "EMC_IO_INIT": 1601,
    "EMC_IO_HALT": 1602,
    "EMC_IO_ABORT": 1603,
    "EMC_IO_SET_CYCLE_TIME": 1604,
    "EMC_IO_STAT": 1699,
    # others (NML-069)
    "EMC_NULL": 21,
    "EMC_SET_DEBUG": 22,
    "EMC_SYSTEM_CMD": 30,
    "EMC_EXEC_PLUGIN_CALL": 1112,
    "EMC_INIT": 1901,
    "EMC_HALT": 1902,
    "EMC_ABORT": 1903,
    "EMC_STAT": 1999,
}

# The numbers SPEC NML-053 gives explicitly (EMC_IO_GENERIC, 1605, is the README's example
# of adding a type, not part of the catalogue).
SPEC_NML_053 = {
    "EMC_TOOL_INIT": 1101,
    "EMC_TOOL_HALT": 1102,
    "EMC_TOOL_ABORT": 1103,
    "EMC_TOOL_PREPARE": 1104,
    "EMC_TOOL_LOAD": 1105,
    "EMC_TOOL_UNLOAD": 1106,
    "EMC_TOOL_LOAD_TOOL_TABLE": 1107,
    "EMC_TOOL_SET_OFFSET": 1108,
    "EMC_TOOL_SET_NUMBER": 1109,
    "EMC_TOOL_START_CHANGE": 1110,
    "EMC_TOOL_STAT": 1199,
    "EMC_IO_INIT": 1601,
}

CATALOGUE = [cls for cls in REGISTRY.all() if cls.__module__ == emc.__name__]

EMC_STATUS_BUFFER_SIZE = 20480  # emcStatus in LinuxCNC's linuxcnc.nml
BUFFER_HEADER_ALLOWANCE = 64


# ----------------------------------------------------------------------------- sample values


def sample_values(struct: type[Struct], numbers: Iterator[int]) -> dict[str, Any]:
    """Values for every field of ``struct``, each distinct and different from the default."""
    return {field.name: _sample(field.marker, numbers) for field in struct.fields}


def _sample(marker: Any, numbers: Iterator[int]) -> Any:
    if isinstance(marker, Nested):
        return sample_values(marker.struct, numbers)
    if isinstance(marker, Array):
        return [_sample_item(marker.item, numbers) for _ in range(marker.length)]
    if isinstance(marker, Text):
        return _sample_text(marker.length, next(numbers))
    return _sample_scalar(marker, next(numbers))


def _sample_item(item: Scalar | type[Struct], numbers: Iterator[int]) -> Any:
    if isinstance(item, Scalar):
        return _sample_scalar(item, next(numbers))
    return sample_values(item, numbers)


def _sample_scalar(marker: Scalar, n: int) -> Any:
    """A value exactly representable in the field's type, never 0 (nor -1, RCS's default)."""
    code = marker.code
    if code == "?":
        return True
    if code == "<f8":
        return n + 0.125
    if code == "<f4":
        return (n % 4096) + 0.5
    if code == "<i1":
        return -(n % 100) - 2
    if code == "<u1":
        return n % 250 + 1
    if code.startswith("<i"):
        return n if n % 2 else -n - 1
    return n + 2**31 if code == "<u8" else n


def _sample_text(length: int, n: int) -> str:
    """Text filling the field to its last byte, with a two-byte UTF-8 character in it."""
    head = f"{n}\u00e9"
    return head + "x" * (length - len(head.encode("utf-8")))


def leaves(values: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    if isinstance(values, dict):
        for name, value in values.items():
            yield from leaves(value, f"{path}.{name}")
    elif isinstance(values, list):
        for index, value in enumerate(values):
            yield from leaves(value, f"{path}[{index}]")
    else:
        yield path, values


# ----------------------------------------------------------------------------- numbers and names


# Task -> motion settings that LinuxCNC 2.9 writes into motion's shared memory instead of
# sending as NML messages; here they are NML messages too, in free numbers of their group.
OUR_TYPES = {
    "EMC_JOINT_SET_MAX_ACCELERATION": 117,
    "EMC_JOINT_SET_MOTOR_OFFSET": 130,
    "EMC_AXIS_SET_MIN_POSITION_LIMIT": 141,
    "EMC_AXIS_SET_MAX_POSITION_LIMIT": 142,
    "EMC_AXIS_SET_MAX_VELOCITY": 143,
    "EMC_AXIS_SET_MAX_ACCELERATION": 144,
    "EMC_SPINDLE_SET_PARAMS": 1301,
    # LinuxCNC 2.7's number (2.9 dropped the message): teleop's velocity vector (MOT-055)
    "EMC_TRAJ_SET_TELEOP_VECTOR": 231,
}


def test_catalogue_is_linuxcnc_types_with_their_numbers() -> None:
    assert {cls.NAME: cls.TYPE for cls in CATALOGUE} == LINUXCNC_TYPES | OUR_TYPES
    assert not set(OUR_TYPES.values()) & set(LINUXCNC_TYPES.values())


def test_spec_nml_053_numbers() -> None:
    assert {name: getattr(emc, name).TYPE for name in SPEC_NML_053} == SPEC_NML_053


@pytest.mark.parametrize(("name", "number"), LINUXCNC_TYPES.items())
def test_symbol_lookup_both_ways(name: str, number: int) -> None:
    cls = getattr(emc, name)
    assert REGISTRY.symbol(number) == name
    assert REGISTRY.by_type(number) is cls
    assert REGISTRY.by_name(name) is cls


def test_intermediate_bases_are_not_registered() -> None:
    bases = [
        emc.EMC_JOINT_CMD_MSG,
        emc.EMC_JOG_CMD_MSG,
        emc.EMC_TRAJ_CMD_MSG,
        emc.EMC_MOTION_CMD_MSG,
        emc.EMC_SPINDLE_CMD_MSG,
        emc.EMC_TASK_CMD_MSG,
        emc.EMC_TOOL_CMD_MSG,
        emc.EMC_AUX_CMD_MSG,
        emc.EMC_COOLANT_CMD_MSG,
        emc.EMC_LUBE_CMD_MSG,
        emc.EMC_IO_CMD_MSG,
        emc.EMC_CMD_MSG,
        emc.EMC_TASK_STAT_MSG,
        emc.EMC_STAT_MSG,
    ]
    for base in bases:
        assert REGISTRY.by_name(base.__name__) is None
    assert issubclass(emc.EMC_TRAJ_LINEAR_MOVE, emc.EMC_TRAJ_CMD_MSG)
    assert issubclass(emc.EMC_JOINT_HOME, emc.EMC_JOINT_CMD_MSG)
    assert issubclass(emc.EMC_TOOL_PREPARE, emc.EMC_TOOL_CMD_MSG)
    assert issubclass(emc.EMC_IO_INIT, emc.EMC_IO_CMD_MSG)
    assert issubclass(emc.EMC_TASK_PLAN_OPEN, emc.EMC_TASK_CMD_MSG)


@pytest.mark.parametrize("cls", CATALOGUE, ids=lambda cls: cls.NAME)
def test_kind(cls: type) -> None:
    if cls.NAME.endswith("_STAT"):
        assert cls.KIND is MessageKind.STATUS
        assert issubclass(cls, RCS_STAT_MSG)
    elif cls.NAME.startswith("EMC_OPERATOR_"):
        assert cls.KIND is MessageKind.OPERATOR
    else:
        assert cls.KIND is MessageKind.COMMAND
        assert issubclass(cls, RCS_CMD_MSG)


def test_operator_messages() -> None:
    for cls, text_field in [
        (emc.EMC_OPERATOR_ERROR, "error"),
        (emc.EMC_OPERATOR_TEXT, "text"),
        (emc.EMC_OPERATOR_DISPLAY, "display"),
    ]:
        msg = cls(id=4, **{text_field: "spindle not at speed"})
        out = decode(encode(msg, Encoding.MSGPACK))
        assert (out.id, getattr(out, text_field)) == (4, "spindle not at speed")


# ----------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("encoding", list(Encoding), ids=lambda e: e.name)
@pytest.mark.parametrize("cls", CATALOGUE, ids=lambda cls: cls.NAME)
def test_round_trip_with_every_field_set(cls: type, encoding: Encoding) -> None:
    values = sample_values(cls, itertools.count(1))
    defaults = dict(leaves(cls().to_python()))
    unchanged = [path for path, value in leaves(values) if value == defaults[path]]
    assert not unchanged, f"sample values equal the defaults at {unchanged}"

    msg = cls.from_python(values)
    assert msg.to_python() == values
    out = decode(encode(msg, encoding), where="test")
    assert type(out) is cls
    assert out.to_python() == values
    assert out == msg


# ----------------------------------------------------------------------------- EMC_STAT


@pytest.mark.parametrize("encoding", list(Encoding), ids=lambda e: e.name)
def test_emc_stat_nested_access(encoding: Encoding) -> None:
    stat = emc.EMC_STAT()
    stat.task.mode = emc.EMC_TASK_MODE_ENUM.AUTO
    stat.task.interpState = emc.EMC_TASK_INTERP_ENUM.READING
    stat.task.file = "/home/cnc/part.ngc"
    stat.task.activeGCodes[1] = 170
    stat.motion.traj.position.tran.x = 12.5
    stat.motion.traj.position.a = 90.0
    stat.motion.joint[3].homed = 1
    stat.motion.axis[8].velocity = 3.25
    stat.motion.spindle[7].speed = 1200.0
    stat.motion.synch_di[63] = 1
    stat.motion.analog_output[2] = 4.5
    stat.io.aux.estop = 1
    stat.io.tool.toolInSpindle = 17
    stat.io.tool.toolTableCurrent.offset.tran.z = 0.75
    stat.io.coolant.flood = 1
    stat.io.lube.level = 1

    out = decode(encode(stat, encoding))
    assert isinstance(out, emc.EMC_STAT)
    assert out.task.mode == emc.EMC_TASK_MODE_ENUM.AUTO
    assert emc.EMC_TASK_INTERP_ENUM(out.task.interpState) is emc.EMC_TASK_INTERP_ENUM.READING
    assert out.task.file == "/home/cnc/part.ngc"
    assert out.task.activeGCodes[1] == 170
    assert out.motion.traj.position.tran.x == 12.5
    assert out.motion.traj.position.a == 90.0
    assert out.motion.joint[3].homed == 1
    assert out.motion.joint[2].homed == 0
    assert out.motion.axis[8].velocity == 3.25
    assert out.motion.spindle[7].speed == 1200.0
    assert out.motion.synch_di[63] == 1
    assert out.motion.analog_output[2] == 4.5
    assert out.io.aux.estop == 1
    assert out.io.tool.toolInSpindle == 17
    assert out.io.tool.toolTableCurrent.offset.tran.z == 0.75
    assert out.io.coolant.flood == 1
    assert out.io.lube.level == 1


def test_emc_stat_arrays_have_linuxcnc_sizes() -> None:
    motion = emc.EMC_STAT().motion
    assert len(motion.joint) == emc.EMC_MAX_JOINTS == 16
    assert len(motion.axis) == emc.EMC_MAX_AXES == 9
    assert len(motion.spindle) == emc.EMC_MAX_SPINDLES == 8
    assert len(motion.synch_di) == len(motion.synch_do) == emc.EMC_MAX_DIO == 64
    assert len(motion.analog_input) == len(motion.analog_output) == emc.EMC_MAX_AIO == 64
    task = emc.EMC_STAT().task
    assert (len(task.activeGCodes), len(task.activeMCodes), len(task.activeSettings)) == (17, 10, 5)


def test_emc_stat_fits_linuxcnc_status_buffer() -> None:
    assert emc.EMC_STAT.fixed_size() <= EMC_STATUS_BUFFER_SIZE - BUFFER_HEADER_ALLOWANCE


def test_text_fields_hold_linelen_bytes() -> None:
    assert emc.LINELEN == 255
    emc.EMC_TASK_PLAN_OPEN(file="f" * emc.LINELEN)
    with pytest.raises(ValueError, match="do not fit"):
        emc.EMC_TASK_PLAN_OPEN(file="f" * (emc.LINELEN + 1))


def test_spindle_on_waits_for_speed_by_default() -> None:
    assert emc.EMC_SPINDLE_ON().wait_for_spindle_at_speed == 1
    assert emc.EMC_SPINDLE_ON(wait_for_spindle_at_speed=0).wait_for_spindle_at_speed == 0


# ----------------------------------------------------------------------------- enums


@pytest.mark.parametrize(
    ("enum_class", "expected"),
    [
        (emc.EMC_TASK_MODE_ENUM, {"MANUAL": 1, "AUTO": 2, "MDI": 3}),
        (emc.EMC_TASK_STATE_ENUM, {"ESTOP": 1, "ESTOP_RESET": 2, "OFF": 3, "ON": 4}),
        (
            emc.EMC_TASK_EXEC_ENUM,
            {
                "ERROR": 1,
                "DONE": 2,
                "WAITING_FOR_MOTION": 3,
                "WAITING_FOR_MOTION_QUEUE": 4,
                "WAITING_FOR_IO": 5,
                "WAITING_FOR_MOTION_AND_IO": 7,
                "WAITING_FOR_DELAY": 8,
                "WAITING_FOR_SYSTEM_CMD": 9,
                "WAITING_FOR_SPINDLE_ORIENTED": 10,
            },
        ),
        (emc.EMC_TASK_INTERP_ENUM, {"IDLE": 1, "READING": 2, "PAUSED": 3, "WAITING": 4}),
        (emc.EMC_TRAJ_MODE_ENUM, {"FREE": 1, "COORD": 2, "TELEOP": 3}),
        (
            emc.EMC_MOTION_TYPE,
            {
                "TRAVERSE": 1,
                "FEED": 2,
                "ARC": 3,
                "TOOLCHANGE": 4,
                "PROBING": 5,
                "INDEXROTARY": 6,
            },
        ),
        (emc.EMC_TRAJ_TERM_COND, {"STOP": 0, "EXACT": 1, "BLEND": 2}),
        (emc.CANON_UNITS, {"INCHES": 1, "MM": 2, "CM": 3}),
        (emc.EmcJointType, {"LINEAR": 1, "ANGULAR": 2}),
        (
            emc.KINEMATICS_TYPE,
            {"IDENTITY": 1, "FORWARD_ONLY": 2, "INVERSE_ONLY": 3, "BOTH": 4},
        ),
        (emc.JOG_MODE, {"TELEOP": 0, "JOINT": 1}),
        (emc.LOCAL_JOG, {"STOP": 0, "CONTINUOUS": 1, "INCREMENT": 2}),
    ],
    ids=lambda value: getattr(value, "__name__", ""),
)
def test_enum_values_are_linuxcnc(enum_class: type, expected: dict[str, int]) -> None:
    assert {member.name: member.value for member in enum_class} == expected
