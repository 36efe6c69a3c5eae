"""The EMC message catalogue: LinuxCNC 2.9's NML messages and type numbers (SPEC NML-053..072).

Class names, field names, type numbers and array sizes are LinuxCNC's, so code and
documentation written for LinuxCNC read the same here (``EMC_TRAJ_LINEAR_MOVE.end``,
``EMC_STAT.io.aux.estop``). Field types follow LinuxCNC's C types: ``double`` is ``f64``,
``int`` and C enums are ``i32``, ``unsigned char`` is ``u8`` and ``bool`` is ``boolean``.

Layout of this module, following SPEC NML-056..069:

- sizes, enums and constants;
- plain structs (``PmCartesian``, ``EmcPose``, ``StateTag``, ``CANON_TOOL_TABLE``);
- one section per message group: OPERATOR, JOINT/AXIS/JOG, TRAJ, SPINDLE, MOTION, TASK,
  TOOL, AUX, COOLANT, LUBE, IO, and the top-level EMC messages with ``EMC_STAT``.

Most groups have an intermediate base without a type number (``EMC_TRAJ_CMD_MSG``,
``EMC_JOINT_STAT_MSG`` ...), as in LinuxCNC. A class with ``type_id=N`` is registered under
that number; nothing else is needed to send and receive it (NML-049, NML-052).

Where a LinuxCNC status class declares a member with the same name as one of
``RCS_STAT_MSG`` (``EMC_TASK_STAT.state``, ``EMC_SPINDLE_STAT.state``), C++ keeps two
members; here the two share the one field (Python classes have one namespace), which
holds the subsystem's value (task state, spindle state).
"""

from __future__ import annotations

import enum
from collections.abc import Iterable

from nml.message import (
    RCS_CMD_MSG,
    RCS_STAT_MSG,
    MessageKind,
    Receiver,
    Requires,
    Struct,
    array,
    boolean,
    f32,
    f64,
    i32,
    string,
    u8,
    u32,
    u64,
)
from nml.pose import Pose

# ============================================================================ sizes

LINELEN = 255  # length of file names, MDI commands and operator messages
EMC_SYSTEM_CMD_LEN = 256
EMC_PLUGIN_CALL_LEN = 900  # MAX_NML_COMMAND_SIZE - 100 in LinuxCNC


def fit_text(text: str, size: int = LINELEN) -> str:
    """The longest start of ``text`` whose UTF-8 fits a C string field of ``size`` bytes
    (with its NUL), cut at a character boundary: as LinuxCNC, long operator messages, file
    names and MDI texts are cut short, never refused. (A text field refuses what does not
    fit, so a cut by characters, ``text[:255]``, fails on non-ASCII text.)"""
    return text.encode("utf-8")[: size - 1].decode("utf-8", errors="ignore")


EMCMOT_MAX_JOINTS = 16
EMCMOT_MAX_AXIS = 9
EMCMOT_MAX_SPINDLES = 8
EMCMOT_MAX_DIO = 64
EMCMOT_MAX_AIO = 64
EMCMOT_MAX_MISC_ERROR = 64

# Shorter aliases used throughout this project.
EMC_MAX_JOINTS = EMCMOT_MAX_JOINTS
EMC_MAX_AXES = EMCMOT_MAX_AXIS
EMC_MAX_SPINDLES = EMCMOT_MAX_SPINDLES
EMC_MAX_DIO = EMCMOT_MAX_DIO
EMC_MAX_AIO = EMCMOT_MAX_AIO

ACTIVE_G_CODES = 17
ACTIVE_M_CODES = 10
ACTIVE_SETTINGS = 5

CANON_POCKETS_MAX = 1001
CANON_TOOL_ENTRY_LEN = 256


# ============================================================================ enums


class EMC_TASK_MODE_ENUM(enum.IntEnum):
    """``EMC_TASK_STAT.mode``: who drives the machine."""

    MANUAL = 1
    AUTO = 2
    MDI = 3


class EMC_TASK_STATE_ENUM(enum.IntEnum):
    """``EMC_TASK_STAT.state``: the machine's power state."""

    ESTOP = 1
    ESTOP_RESET = 2
    OFF = 3
    ON = 4


# What manual motion (jogs, homing, the teleop vector) needs of task (``requires=``)
ON_IN_MANUAL = Requires(state=EMC_TASK_STATE_ENUM.ON, mode=EMC_TASK_MODE_ENUM.MANUAL)
# What a stop needs: nothing (a stop is never refused for the state or mode it comes in)
ANYTIME = Requires()


class EMC_TASK_EXEC_ENUM(enum.IntEnum):
    """``EMC_TASK_STAT.execState``: what task's executor is waiting for (6 is unused)."""

    ERROR = 1
    DONE = 2
    WAITING_FOR_MOTION = 3
    WAITING_FOR_MOTION_QUEUE = 4
    WAITING_FOR_IO = 5
    WAITING_FOR_MOTION_AND_IO = 7
    WAITING_FOR_DELAY = 8
    WAITING_FOR_SYSTEM_CMD = 9
    WAITING_FOR_SPINDLE_ORIENTED = 10


class EMC_TASK_INTERP_ENUM(enum.IntEnum):
    """``EMC_TASK_STAT.interpState``: what the interpreter is doing."""

    IDLE = 1
    READING = 2
    PAUSED = 3
    WAITING = 4


class EMC_TRAJ_MODE_ENUM(enum.IntEnum):
    """``EMC_TRAJ_STAT.mode``: joint-by-joint, coordinated or teleoperated motion."""

    FREE = 1
    COORD = 2
    TELEOP = 3


class EMC_TRAJ_TERM_COND(enum.IntEnum):
    """``EMC_TRAJ_SET_TERM_COND.cond``: how consecutive moves are joined (G61/G61.1/G64)."""

    STOP = 0
    EXACT = 1
    BLEND = 2


class EMC_MOTION_TYPE(enum.IntEnum):
    """``EMC_TRAJ_LINEAR_MOVE.type`` and ``EMC_TRAJ_STAT.motion_type``."""

    TRAVERSE = 1
    FEED = 2
    ARC = 3
    TOOLCHANGE = 4
    PROBING = 5
    INDEXROTARY = 6


class EMC_IO_ABORT_REASON_ENUM(enum.IntEnum):
    """``EMC_TOOL_ABORT.reason`` and ``EMC_IO_STAT.reason``: why task aborted."""

    TASK_EXEC_ERROR = 1
    AUX_ESTOP = 2
    MOTION_OR_IO_RCS_ERROR = 3
    TASK_STATE_OFF = 4
    TASK_STATE_ESTOP_RESET = 5
    TASK_STATE_ESTOP = 6
    TASK_STATE_NOT_ON = 7
    TASK_ABORT = 8
    INTERPRETER_ERROR = 9
    INTERPRETER_ERROR_MDI = 10
    USER = 100  # first user-defined reason


class EmcJointType(enum.IntEnum):
    """``EMC_JOINT_SET_JOINT.jointType`` and ``EMC_JOINT_STAT.jointType``."""

    LINEAR = 1
    ANGULAR = 2


class KINEMATICS_TYPE(enum.IntEnum):
    """``EMC_TRAJ_STAT.kinematics_type``: which transforms the kinematics module offers."""

    IDENTITY = 1
    FORWARD_ONLY = 2
    INVERSE_ONLY = 3
    BOTH = 4


class CANON_UNITS(enum.IntEnum):
    """``EMC_TASK_STAT.programUnits``: units of the running program (G20/G21)."""

    INCHES = 1
    MM = 2
    CM = 3


class JOG_MODE(enum.IntEnum):
    """``jjogmode`` of the jog messages: jog a world axis (teleop) or a single joint."""

    TELEOP = 0
    JOINT = 1


class INPUT_TYPE(enum.IntEnum):
    """``EMC_AUX_INPUT_WAIT.input_type`` (M66 E/P words)."""

    ANALOG = 0
    DIGITAL = 1


class WAIT_MODE(enum.IntEnum):
    """``EMC_AUX_INPUT_WAIT.wait_type`` (M66 L word)."""

    IMMEDIATE = 0
    RISE = 1
    FALL = 2
    HIGH = 3
    LOW = 4


class EMC_DEBUG(enum.IntFlag):
    """Bits of the ``debug`` fields ([EMC]DEBUG in the INI file)."""

    CONFIG = 0x00000002
    VERSIONS = 0x00000008
    TASK_ISSUE = 0x00000010
    NML = 0x00000040
    MOTION_TIME = 0x00000080
    INTERP = 0x00000100
    RCS = 0x00000200
    INTERP_LIST = 0x00000800
    IOCONTROL = 0x00001000
    OWORD = 0x00002000
    REMAP = 0x00004000
    PYTHON = 0x00008000
    NAMEDPARAM = 0x00010000
    GDBONSIGNAL = 0x00020000
    PYTHON_TASK = 0x00040000
    STATE_TAGS = 0x00080000
    USER1 = 0x10000000
    USER2 = 0x20000000
    UNCONDITIONAL = 0x40000000
    ALL = 0x7FFFFFFF


class LOCAL_SPINDLE(enum.IntEnum):
    """Spindle actions of the ``linuxcnc`` Python module (``command.spindle()``)."""

    FORWARD = 1
    REVERSE = -1
    OFF = 0
    INCREASE = 10
    DECREASE = 11
    CONSTANT = 12


class LOCAL_JOG(enum.IntEnum):
    """Jog actions of the ``linuxcnc`` Python module (``command.jog()``)."""

    STOP = 0
    CONTINUOUS = 1
    INCREMENT = 2


class LOCAL_AUTO(enum.IntEnum):
    """Program actions of the ``linuxcnc`` Python module (``command.auto()``)."""

    RUN = 0
    PAUSE = 1
    RESUME = 2
    STEP = 3
    REVERSE = 4
    FORWARD = 5


class StateFlag(enum.IntEnum):
    """Bit numbers of ``StateTag.packed_flags``: interpreter modes that travel with a move."""

    UNITS = 0
    DISTANCE_MODE = 1
    TOOL_OFFSETS_ON = 2
    RETRACT_OLDZ = 3
    BLEND = 4
    EXACT_STOP = 5
    FEED_INVERSE_TIME = 6
    FEED_UPM = 7
    CSS_MODE = 8
    IJK_ABS = 9
    DIAMETER_MODE = 10
    G92_IS_APPLIED = 11
    SPINDLE_ON = 12
    SPINDLE_CW = 13
    MIST = 14
    FLOOD = 15
    FEED_OVERRIDE = 16
    SPEED_OVERRIDE = 17
    ADAPTIVE_FEED = 18
    FEED_HOLD = 19
    RESTORABLE = 20
    IN_REMAP = 21
    IN_SUB = 22
    EXTERNAL_FILE = 23


class StateField(enum.IntEnum):
    """Indexes of ``StateTag.fields`` (integer modal state)."""

    LINE_NUMBER = 0
    G_MODE_0 = 1
    CUTTER_COMP = 2
    MOTION_MODE = 3
    PLANE = 4
    M_MODES_4 = 5
    ORIGIN = 6
    TOOLCHANGE = 7


class StateFieldFloat(enum.IntEnum):
    """Indexes of ``StateTag.fields_float`` (numeric settings)."""

    LINE_NUMBER = 0
    FEED = 1
    SPEED = 2
    PATH_TOLERANCE = 3
    NAIVE_CAM_TOLERANCE = 4


# ============================================================================ structs


class PmCartesian(Struct):
    """A point or vector in XYZ."""

    x: f64
    y: f64
    z: f64


class EmcPose(Struct):
    """A pose (``nml.pose.Pose``) in messages, in LinuxCNC's layout: ``tran`` holds X Y Z,
    then A B C and U V W. Code computes with ``Pose``; this is only its wire form, read
    and written whole (each a single copy of the nine numbers)."""

    tran: PmCartesian
    a: f64
    b: f64
    c: f64
    u: f64
    v: f64
    w: f64

    @classmethod
    def of(cls, values: Iterable[float]) -> EmcPose:
        """The wire form of a ``Pose`` (or of nine numbers X ... W)."""
        return cls.from_flat(tuple(values))

    def values(self) -> tuple[float, ...]:
        """The nine numbers X Y Z A B C U V W."""
        return self.flat_format.unpack(self._arr.tobytes())

    def pose(self) -> Pose:
        # all nine in one unpack: nine reads through the message's field views cost 3x
        # more, and motion pays it for every queued move
        return Pose(*self.flat_format.unpack(self._arr.tobytes()))

    def set(self, values: Iterable[float]) -> None:
        """Write a ``Pose`` (or nine numbers X ... W) in place."""
        self.byte_view()[:] = self.flat_format.pack(*values)


class StateTag(Struct):
    """Interpreter state attached to each queued move, reported back with the active move."""

    fields_float: array(f32, len(StateFieldFloat))
    fields: array(i32, len(StateField))
    packed_flags: u64


class CANON_TOOL_TABLE(Struct):
    """One tool table entry; ``pocketno`` 0 is the spindle, ``toolno`` 0 means no tool."""

    toolno: i32
    pocketno: i32
    offset: EmcPose
    diameter: f64
    frontangle: f64
    backangle: f64
    orientation: i32


# ============================================================================ OPERATOR (NML-056)
# Text for the operator, queued on the error channel (emcError) and shown by every GUI.


class EMC_OPERATOR_ERROR(
    RCS_CMD_MSG, type_id=11, kind=MessageKind.OPERATOR, receiver=Receiver.TASK
):
    id: i32
    error: string(LINELEN)


class EMC_OPERATOR_TEXT(RCS_CMD_MSG, type_id=12, kind=MessageKind.OPERATOR, receiver=Receiver.TASK):
    id: i32
    text: string(LINELEN)


class EMC_OPERATOR_DISPLAY(
    RCS_CMD_MSG, type_id=13, kind=MessageKind.OPERATOR, receiver=Receiver.TASK
):
    id: i32
    display: string(LINELEN)


# ============================================================================ JOINT (NML-057)


class EMC_JOINT_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.MOTION):
    """Configuration and control of one joint (``joint`` is its number), via task to motion."""

    joint: i32


class EMC_JOINT_SET_JOINT(EMC_JOINT_CMD_MSG, type_id=101):
    jointType: u8


class EMC_JOINT_SET_UNITS(EMC_JOINT_CMD_MSG, type_id=102):
    units: f64


class EMC_JOINT_SET_MIN_POSITION_LIMIT(EMC_JOINT_CMD_MSG, type_id=107):
    limit: f64


class EMC_JOINT_SET_MAX_POSITION_LIMIT(EMC_JOINT_CMD_MSG, type_id=108):
    limit: f64


class EMC_JOINT_SET_FERROR(EMC_JOINT_CMD_MSG, type_id=111):
    ferror: f64


NO_HOME_SEQUENCE = 999  # home_sequence of a joint without [JOINT_n]HOME_SEQUENCE (LinuxCNC's)


class EMC_JOINT_SET_HOMING_PARAMS(EMC_JOINT_CMD_MSG, type_id=112):
    home: f64
    offset: f64
    home_final_vel: f64
    search_vel: f64
    latch_vel: f64
    use_index: i32
    encoder_does_not_reset: i32
    ignore_limits: i32
    is_shared: i32
    home_sequence: i32
    volatile_home: i32
    locking_indexer: i32
    absolute_encoder: i32


class EMC_JOINT_SET_MIN_FERROR(EMC_JOINT_CMD_MSG, type_id=115):
    ferror: f64


class EMC_JOINT_SET_MAX_VELOCITY(EMC_JOINT_CMD_MSG, type_id=116):
    vel: f64


class EMC_JOINT_SET_MOTOR_OFFSET(EMC_JOINT_CMD_MSG, type_id=130):
    """Motor position of joint position 0; task sets it from [TRAJ]POSITION_FILE at start
    so the machine reappears where it was (LinuxCNC writes it into motion's memory)."""

    offset: f64


class EMC_JOINT_SET_MAX_ACCELERATION(EMC_JOINT_CMD_MSG, type_id=117):
    """[JOINT_n]MAX_ACCELERATION. Not an NML message in LinuxCNC 2.9, where task writes it
    straight into motion's shared memory; here every task -> motion command is NML."""

    acc: f64


class EMC_JOINT_INIT(EMC_JOINT_CMD_MSG, type_id=118): ...


class EMC_JOINT_HALT(EMC_JOINT_CMD_MSG, type_id=119): ...


class EMC_JOINT_ABORT(EMC_JOINT_CMD_MSG, type_id=120): ...


class EMC_JOINT_ENABLE(EMC_JOINT_CMD_MSG, type_id=121): ...


class EMC_JOINT_DISABLE(EMC_JOINT_CMD_MSG, type_id=122): ...


class EMC_JOINT_HOME(EMC_JOINT_CMD_MSG, type_id=123, requires=ON_IN_MANUAL): ...


class EMC_JOINT_ACTIVATE(EMC_JOINT_CMD_MSG, type_id=127): ...


class EMC_JOINT_DEACTIVATE(EMC_JOINT_CMD_MSG, type_id=128): ...


class EMC_JOINT_OVERRIDE_LIMITS(EMC_JOINT_CMD_MSG, type_id=129): ...


class EMC_JOINT_LOAD_COMP(EMC_JOINT_CMD_MSG, type_id=131):
    file: string(LINELEN)
    type: i32  # comp file format; 0: nominal, forward, reverse triplets


class EMC_JOINT_SET_BACKLASH(EMC_JOINT_CMD_MSG, type_id=134):
    backlash: f64


class EMC_JOINT_UNHOME(EMC_JOINT_CMD_MSG, type_id=135, requires=ON_IN_MANUAL): ...


class EMC_JOINT_STAT_MSG(RCS_STAT_MSG):
    joint: i32


class EMC_JOINT_STAT(EMC_JOINT_STAT_MSG, type_id=198):
    jointType: u8
    units: f64
    backlash: f64
    minPositionLimit: f64
    maxPositionLimit: f64
    maxFerror: f64
    minFerror: f64
    ferrorCurrent: f64
    ferrorHighMark: f64
    output: f64  # commanded position
    input: f64  # feedback position
    velocity: f64
    inpos: u8
    homing: u8
    homed: u8
    fault: u8
    enabled: u8
    minSoftLimit: u8
    maxSoftLimit: u8
    minHardLimit: u8
    maxHardLimit: u8
    overrideLimits: u8


# ============================================================================ AXIS (NML-058)


class EMC_AXIS_STAT_MSG(RCS_STAT_MSG):
    """Status of one world axis (X Y Z A B C U V W: ``axis`` 0..8)."""

    axis: i32


class EMC_AXIS_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.MOTION):
    """Configuration of one world axis (``axis`` 0..8 for X..W), from [AXIS_L] via task.
    LinuxCNC 2.9 passes these through motion's shared memory; here they are NML messages,
    numbered in the free 14x block of the joint/axis group."""

    axis: i32


class EMC_AXIS_SET_MIN_POSITION_LIMIT(EMC_AXIS_CMD_MSG, type_id=141):
    limit: f64


class EMC_AXIS_SET_MAX_POSITION_LIMIT(EMC_AXIS_CMD_MSG, type_id=142):
    limit: f64


class EMC_AXIS_SET_MAX_VELOCITY(EMC_AXIS_CMD_MSG, type_id=143):
    vel: f64


class EMC_AXIS_SET_MAX_ACCELERATION(EMC_AXIS_CMD_MSG, type_id=144):
    acc: f64


class EMC_AXIS_STAT(EMC_AXIS_STAT_MSG, type_id=199):
    minPositionLimit: f64
    maxPositionLimit: f64
    velocity: f64


# ============================================================================ JOG (NML-059)


class EMC_JOG_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.MOTION, requires=ON_IN_MANUAL):
    """Manual jogging of a joint (``jjogmode`` JOG_MODE.JOINT) or a world axis (TELEOP)."""

    joint_or_axis: i32


class EMC_JOG_CONT(EMC_JOG_CMD_MSG, type_id=124):
    vel: f64
    jjogmode: i32
    # The requester's heartbeat slot on the safety board (nml/safety.py) and its pid: motion
    # stops the jog when that slot goes quiet (a UI killed or stuck mid-jog). lease_pid 0:
    # no lease, the jog stops after the lease timeout unless renewed by a new EMC_JOG_CONT.
    lease_slot: i32
    lease_pid: i32


class EMC_JOG_INCR(EMC_JOG_CMD_MSG, type_id=125):
    incr: f64
    vel: f64
    jjogmode: i32


class EMC_JOG_ABS(EMC_JOG_CMD_MSG, type_id=126):
    pos: f64
    vel: f64
    jjogmode: i32


class EMC_JOG_STOP(EMC_JOG_CMD_MSG, type_id=136, requires=ANYTIME):
    jjogmode: i32


# ============================================================================ TRAJ (NML-060)


class EMC_TRAJ_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.MOTION):
    """The trajectory planner: settings, queued moves and program flow.

    ``tag`` carries the interpreter state of the program line a command comes from.
    """

    tag: StateTag


class EMC_TRAJ_SET_AXES(EMC_TRAJ_CMD_MSG, type_id=201):
    axes: i32


class EMC_TRAJ_SET_UNITS(EMC_TRAJ_CMD_MSG, type_id=202):
    linearUnits: f64  # user units per mm
    angularUnits: f64  # user units per degree


class EMC_TRAJ_SET_CYCLE_TIME(EMC_TRAJ_CMD_MSG, type_id=203):
    cycleTime: f64


class EMC_TRAJ_SET_MODE(EMC_TRAJ_CMD_MSG, type_id=204):
    mode: i32  # EMC_TRAJ_MODE_ENUM


class EMC_TRAJ_SET_VELOCITY(EMC_TRAJ_CMD_MSG, type_id=205):
    velocity: f64
    ini_maxvel: f64


class EMC_TRAJ_SET_ACCELERATION(EMC_TRAJ_CMD_MSG, type_id=206):
    acceleration: f64


class EMC_TRAJ_SET_MAX_VELOCITY(EMC_TRAJ_CMD_MSG, type_id=207):
    velocity: f64


class EMC_TRAJ_SET_MAX_ACCELERATION(EMC_TRAJ_CMD_MSG, type_id=208):
    acceleration: f64


class EMC_TRAJ_SET_SCALE(EMC_TRAJ_CMD_MSG, type_id=209):
    scale: f64


class EMC_TRAJ_SET_MOTION_ID(EMC_TRAJ_CMD_MSG, type_id=210):
    id: i32


class EMC_TRAJ_INIT(EMC_TRAJ_CMD_MSG, type_id=211): ...


class EMC_TRAJ_HALT(EMC_TRAJ_CMD_MSG, type_id=212): ...


class EMC_TRAJ_ENABLE(EMC_TRAJ_CMD_MSG, type_id=213): ...


class EMC_TRAJ_DISABLE(EMC_TRAJ_CMD_MSG, type_id=214): ...


class EMC_TRAJ_ABORT(EMC_TRAJ_CMD_MSG, type_id=215): ...


class EMC_TRAJ_PAUSE(EMC_TRAJ_CMD_MSG, type_id=216): ...


class EMC_TRAJ_STEP(EMC_TRAJ_CMD_MSG, type_id=217): ...


class EMC_TRAJ_RESUME(EMC_TRAJ_CMD_MSG, type_id=218): ...


class EMC_TRAJ_DELAY(EMC_TRAJ_CMD_MSG, type_id=219, receiver=Receiver.TASK):
    delay: f64  # seconds


class EMC_TRAJ_LINEAR_MOVE(EMC_TRAJ_CMD_MSG, type_id=220):
    type: i32  # EMC_MOTION_TYPE
    end: EmcPose
    vel: f64
    ini_maxvel: f64
    acc: f64
    feed_mode: i32
    indexer_jnum: i32
    id: i32  # motion id (the line motion reports); 0: the last EMC_TRAJ_SET_MOTION_ID's


class EMC_TRAJ_CIRCULAR_MOVE(EMC_TRAJ_CMD_MSG, type_id=221):
    end: EmcPose
    center: PmCartesian
    normal: PmCartesian
    turn: i32
    type: i32  # EMC_MOTION_TYPE
    vel: f64
    ini_maxvel: f64
    acc: f64
    feed_mode: i32
    id: i32  # motion id (the line motion reports); 0: the last EMC_TRAJ_SET_MOTION_ID's


class EMC_TRAJ_SET_TERM_COND(EMC_TRAJ_CMD_MSG, type_id=222):
    cond: i32  # EMC_TRAJ_TERM_COND
    tolerance: f64  # allowed path deviation when blending


class EMC_TRAJ_SET_OFFSET(EMC_TRAJ_CMD_MSG, type_id=223, waits_for_motion=True):
    offset: EmcPose


class EMC_TRAJ_SET_G5X(EMC_TRAJ_CMD_MSG, type_id=224, receiver=Receiver.TASK):
    g5x_index: i32
    origin: EmcPose


class EMC_TRAJ_SET_HOME(EMC_TRAJ_CMD_MSG, type_id=225):
    home: EmcPose


class EMC_TRAJ_SET_ROTATION(EMC_TRAJ_CMD_MSG, type_id=226, receiver=Receiver.TASK):
    rotation: f64


class EMC_TRAJ_SET_G92(EMC_TRAJ_CMD_MSG, type_id=227, receiver=Receiver.TASK):
    origin: EmcPose


class EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG(EMC_TRAJ_CMD_MSG, type_id=228, waits_for_motion=True): ...


class EMC_TRAJ_PROBE(EMC_TRAJ_CMD_MSG, type_id=229, waits_for_motion=True):
    pos: EmcPose
    type: i32
    vel: f64
    ini_maxvel: f64
    acc: f64
    probe_type: u8
    id: i32  # motion id (the line motion reports); 0: the last EMC_TRAJ_SET_MOTION_ID's


class EMC_TRAJ_SET_TELEOP_ENABLE(
    EMC_TRAJ_CMD_MSG,
    type_id=230,
    receiver=Receiver.TASK,
    requires=Requires(mode=EMC_TASK_MODE_ENUM.MANUAL),
):
    enable: i32


class EMC_TRAJ_SET_TELEOP_VECTOR(EMC_TRAJ_CMD_MSG, type_id=231, requires=ON_IN_MANUAL):
    """LinuxCNC 2.7's (2.9 dropped it, MOT-013): the cartesian velocity teleop mode
    follows, per axis in machine units per second (MOT-016, MOT-055)."""

    vector: EmcPose


class EMC_TRAJ_SET_SPINDLESYNC(EMC_TRAJ_CMD_MSG, type_id=232):
    spindle: i32
    feed_per_revolution: f64
    velocity_mode: boolean


class EMC_TRAJ_SET_SPINDLE_SCALE(EMC_TRAJ_CMD_MSG, type_id=233):
    spindle: i32
    scale: f64


class EMC_TRAJ_SET_FO_ENABLE(EMC_TRAJ_CMD_MSG, type_id=234):
    mode: u8  # 0: feed override locked at 100 %


class EMC_TRAJ_SET_SO_ENABLE(EMC_TRAJ_CMD_MSG, type_id=235):
    spindle: i32
    mode: u8  # 0: spindle override locked at 100 %


class EMC_TRAJ_SET_FH_ENABLE(EMC_TRAJ_CMD_MSG, type_id=236):
    mode: u8  # 0: feed hold disabled


class EMC_TRAJ_RIGID_TAP(EMC_TRAJ_CMD_MSG, type_id=237, waits_for_motion=True):
    pos: EmcPose
    vel: f64
    ini_maxvel: f64
    acc: f64
    scale: f64
    id: i32  # motion id (the line motion reports); 0: the last EMC_TRAJ_SET_MOTION_ID's


# The moves that carry their motion id: task stamps it into the move rather than sending
# EMC_TRAJ_SET_MOTION_ID before it (one command per move, as LinuxCNC's emcmotCommand.id).
MOVES_WITH_MOTION_ID = (
    EMC_TRAJ_LINEAR_MOVE,
    EMC_TRAJ_CIRCULAR_MOVE,
    EMC_TRAJ_PROBE,
    EMC_TRAJ_RIGID_TAP,
)


class EMC_TRAJ_SET_RAPID_SCALE(EMC_TRAJ_CMD_MSG, type_id=238):
    scale: f64


class EMC_TRAJ_STAT_MSG(RCS_STAT_MSG): ...


class EMC_TRAJ_STAT(EMC_TRAJ_STAT_MSG, type_id=299):
    linearUnits: f64
    angularUnits: f64
    cycleTime: f64
    joints: i32
    spindles: i32
    axis_mask: i32
    mode: i32  # EMC_TRAJ_MODE_ENUM
    enabled: boolean
    inpos: boolean
    queue: i32
    activeQueue: i32
    queueFull: boolean
    id: i32
    paused: boolean
    scale: f64
    rapid_scale: f64
    position: EmcPose  # commanded
    actualPosition: EmcPose  # from feedback through forward kinematics
    velocity: f64
    acceleration: f64
    maxVelocity: f64
    maxAcceleration: f64
    probedPosition: EmcPose
    probe_tripped: boolean
    probing: boolean
    probeval: i32
    kinematics_type: i32  # KINEMATICS_TYPE
    motion_type: i32  # EMC_MOTION_TYPE
    distance_to_go: f64
    dtg: EmcPose
    current_vel: f64
    feed_override_enabled: boolean
    adaptive_feed_enabled: boolean
    feed_hold_enabled: boolean
    tag: StateTag


# ============================================================================ SPINDLE (NML-065)


class EMC_SPINDLE_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.MOTION):
    """Spindle control; ``spindle`` is the spindle's number (0..EMCMOT_MAX_SPINDLES-1)."""

    spindle: i32


class EMC_SPINDLE_SET_PARAMS(EMC_SPINDLE_CMD_MSG, type_id=1301):
    """The speed limits of one spindle, from [SPINDLE_n] via task (rpm, all positive).
    LinuxCNC 2.9 passes them through motion's shared memory (EMCMOT_SET_SPINDLE_PARAMS);
    here it is an NML message, numbered in the free start of the spindle group."""

    max_forward: f64
    min_forward: f64
    max_reverse: f64
    min_reverse: f64


class EMC_SPINDLE_ON(EMC_SPINDLE_CMD_MSG, type_id=1304, waits_for_motion=True):
    speed: f64  # rpm, or the maximum rpm in constant surface speed mode
    factor: f64  # constant surface speed numerator; 0 for a fixed rpm
    xoffset: f64
    wait_for_spindle_at_speed: i32 = 1


class EMC_SPINDLE_OFF(EMC_SPINDLE_CMD_MSG, type_id=1305, waits_for_motion=True):
    wait_for_spindle_at_speed: i32


class EMC_SPINDLE_INCREASE(EMC_SPINDLE_CMD_MSG, type_id=1309):
    speed: f64


class EMC_SPINDLE_DECREASE(EMC_SPINDLE_CMD_MSG, type_id=1310):
    speed: f64


class EMC_SPINDLE_CONSTANT(EMC_SPINDLE_CMD_MSG, type_id=1311):
    speed: f64


class EMC_SPINDLE_BRAKE_RELEASE(EMC_SPINDLE_CMD_MSG, type_id=1312): ...


class EMC_SPINDLE_BRAKE_ENGAGE(EMC_SPINDLE_CMD_MSG, type_id=1313): ...


class EMC_SPINDLE_SPEED(EMC_SPINDLE_CMD_MSG, type_id=1316, waits_for_motion=True):
    speed: f64
    factor: f64
    xoffset: f64


class EMC_SPINDLE_ORIENT(EMC_SPINDLE_CMD_MSG, type_id=1317, waits_for_motion=True):
    orientation: f64  # degrees
    mode: i32


class EMC_SPINDLE_WAIT_ORIENT_COMPLETE(EMC_SPINDLE_CMD_MSG, type_id=1318, waits_for_motion=True):
    timeout: f64  # seconds


class EMC_SPINDLE_STAT_MSG(RCS_STAT_MSG): ...


class EMC_SPINDLE_STAT(EMC_SPINDLE_STAT_MSG, type_id=1399):
    speed: f64
    spindle_scale: f64
    css_maximum: f64
    css_factor: f64
    state: i32
    direction: i32  # 1 forward, -1 reverse, 0 stopped
    brake: i32
    increasing: i32
    enabled: i32
    orient_state: i32
    orient_fault: i32
    spindle_override_enabled: boolean
    homed: boolean


# ============================================================================ MOTION (NML-061)


class EMC_MOTION_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.MOTION):
    """The motion controller as a whole; its status aggregates traj, joints, axes, spindles."""


class EMC_MOTION_INIT(EMC_MOTION_CMD_MSG, type_id=301): ...


class EMC_MOTION_HALT(EMC_MOTION_CMD_MSG, type_id=302): ...


class EMC_MOTION_ABORT(EMC_MOTION_CMD_MSG, type_id=303): ...


class EMC_MOTION_SET_AOUT(EMC_MOTION_CMD_MSG, type_id=304):
    index: u8
    start: f64
    end: f64
    now: u8  # 1: set at once; 0: with the next move

    def waits_for_motion(self) -> bool:
        """M64/M65/M68 (``now``) wait for the moves before them; M62/M63/M67 go with the
        next move into motion's queue."""
        return bool(self.now)


class EMC_MOTION_SET_DOUT(EMC_MOTION_CMD_MSG, type_id=305):
    index: u8
    start: u8
    end: u8
    now: u8

    def waits_for_motion(self) -> bool:
        """M64/M65/M68 (``now``) wait for the moves before them; M62/M63/M67 go with the
        next move into motion's queue."""
        return bool(self.now)


class EMC_MOTION_ADAPTIVE(EMC_MOTION_CMD_MSG, type_id=306, waits_for_motion=True):
    status: u8  # 1 start, 0 stop


class EMC_MOTION_STAT_MSG(RCS_STAT_MSG):
    heartbeat: u32


class EMC_MOTION_STAT(EMC_MOTION_STAT_MSG, type_id=399):
    traj: EMC_TRAJ_STAT
    joint: array(EMC_JOINT_STAT, EMCMOT_MAX_JOINTS)
    axis: array(EMC_AXIS_STAT, EMCMOT_MAX_AXIS)
    spindle: array(EMC_SPINDLE_STAT, EMCMOT_MAX_SPINDLES)
    synch_di: array(i32, EMCMOT_MAX_DIO)
    synch_do: array(i32, EMCMOT_MAX_DIO)
    analog_input: array(f64, EMCMOT_MAX_AIO)
    analog_output: array(f64, EMCMOT_MAX_AIO)
    misc_error: array(i32, EMCMOT_MAX_MISC_ERROR)
    debug: i32
    on_soft_limit: i32
    external_offsets_applied: i32
    eoffset_pose: EmcPose
    numExtraJoints: i32
    jogging_active: boolean


# ============================================================================ TASK (NML-062)


class EMC_TASK_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.TASK):
    """Task: mode, machine state, program and MDI execution."""


class EMC_TASK_INIT(EMC_TASK_CMD_MSG, type_id=501): ...


class EMC_TASK_HALT(EMC_TASK_CMD_MSG, type_id=502): ...


class EMC_TASK_ABORT(EMC_TASK_CMD_MSG, type_id=503):
    # the safety board request (nml/safety.py) this command repeats, 0 if none: task acts on
    # whichever of the two reaches it first, and only once
    request: u64


class EMC_TASK_SET_MODE(EMC_TASK_CMD_MSG, type_id=504):
    mode: i32  # EMC_TASK_MODE_ENUM


class EMC_TASK_SET_STATE(EMC_TASK_CMD_MSG, type_id=505):
    state: i32  # EMC_TASK_STATE_ENUM
    request: u64  # with ESTOP: the safety board request it repeats (see EMC_TASK_ABORT)


class EMC_TASK_PLAN_OPEN(EMC_TASK_CMD_MSG, type_id=506):
    file: string(LINELEN)


class EMC_TASK_PLAN_RUN(
    EMC_TASK_CMD_MSG,
    type_id=507,
    requires=Requires(state=EMC_TASK_STATE_ENUM.ON, mode=EMC_TASK_MODE_ENUM.AUTO),
):
    line: i32  # first line to run; 0 and 1 both mean the start


class EMC_TASK_PLAN_READ(EMC_TASK_CMD_MSG, type_id=508): ...


class EMC_TASK_PLAN_EXECUTE(
    EMC_TASK_CMD_MSG,
    type_id=509,
    requires=Requires(state=EMC_TASK_STATE_ENUM.ON, mode=EMC_TASK_MODE_ENUM.MDI),
):
    command: string(LINELEN)


class EMC_TASK_PLAN_PAUSE(EMC_TASK_CMD_MSG, type_id=510): ...


class EMC_TASK_PLAN_STEP(EMC_TASK_CMD_MSG, type_id=511): ...


class EMC_TASK_PLAN_RESUME(EMC_TASK_CMD_MSG, type_id=512): ...


class EMC_TASK_PLAN_END(EMC_TASK_CMD_MSG, type_id=513): ...


class EMC_TASK_PLAN_CLOSE(EMC_TASK_CMD_MSG, type_id=514): ...


class EMC_TASK_PLAN_INIT(EMC_TASK_CMD_MSG, type_id=515): ...


class EMC_TASK_PLAN_SYNCH(EMC_TASK_CMD_MSG, type_id=516): ...


class EMC_TASK_PLAN_SET_OPTIONAL_STOP(EMC_TASK_CMD_MSG, type_id=517):
    state: boolean


class EMC_TASK_PLAN_SET_BLOCK_DELETE(EMC_TASK_CMD_MSG, type_id=518):
    state: boolean


class EMC_TASK_PLAN_OPTIONAL_STOP(EMC_TASK_CMD_MSG, type_id=519): ...


class EMC_TASK_PLAN_REVERSE(EMC_TASK_CMD_MSG, type_id=520): ...


class EMC_TASK_PLAN_FORWARD(EMC_TASK_CMD_MSG, type_id=521): ...


class EMC_TASK_STAT_MSG(RCS_STAT_MSG):
    heartbeat: u32


class EMC_TASK_STAT(EMC_TASK_STAT_MSG, type_id=599):
    mode: i32  # EMC_TASK_MODE_ENUM
    state: i32  # EMC_TASK_STATE_ENUM (shares RCS_STAT_MSG.state, see the module doc)
    execState: i32  # EMC_TASK_EXEC_ENUM
    interpState: i32  # EMC_TASK_INTERP_ENUM
    callLevel: i32  # subroutine nesting depth, 0 outside subroutines
    motionLine: i32
    currentLine: i32
    readLine: i32
    optional_stop_state: boolean
    block_delete_state: boolean
    input_timeout: boolean
    file: string(LINELEN)
    command: string(LINELEN)
    ini_filename: string(LINELEN)
    g5x_offset: EmcPose
    g5x_index: i32
    g92_offset: EmcPose
    rotation_xy: f64
    toolOffset: EmcPose
    activeGCodes: array(i32, ACTIVE_G_CODES)
    activeMCodes: array(i32, ACTIVE_M_CODES)
    activeSettings: array(f64, ACTIVE_SETTINGS)
    programUnits: i32  # CANON_UNITS
    interpreter_errcode: i32
    task_paused: i32
    delayLeft: f64  # seconds left of a G4 dwell or M66 wait
    queuedMDIcommands: i32


# ============================================================================ TOOL (NML-063)


class EMC_TOOL_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.IO, waits_for_motion=True):
    """The tool change handshake with iocontrol, and the tool table.

    The tool table is not part of the status (as in LinuxCNC 2.9, it lives in the tool data
    store); the status carries only the data of the tool in the spindle.
    """


class EMC_TOOL_INIT(EMC_TOOL_CMD_MSG, type_id=1101): ...


class EMC_TOOL_HALT(EMC_TOOL_CMD_MSG, type_id=1102): ...


class EMC_TOOL_ABORT(EMC_TOOL_CMD_MSG, type_id=1103):
    reason: i32  # EMC_IO_ABORT_REASON_ENUM


class EMC_TOOL_PREPARE(EMC_TOOL_CMD_MSG, type_id=1104):
    tool: i32


class EMC_TOOL_LOAD(EMC_TOOL_CMD_MSG, type_id=1105): ...


class EMC_TOOL_UNLOAD(EMC_TOOL_CMD_MSG, type_id=1106): ...


class EMC_TOOL_LOAD_TOOL_TABLE(EMC_TOOL_CMD_MSG, type_id=1107):
    file: string(LINELEN)  # empty: the configured tool table


class EMC_TOOL_SET_OFFSET(EMC_TOOL_CMD_MSG, type_id=1108):
    pocket: i32
    toolno: i32
    offset: EmcPose
    diameter: f64
    frontangle: f64
    backangle: f64
    orientation: i32


class EMC_TOOL_SET_NUMBER(EMC_TOOL_CMD_MSG, type_id=1109):
    tool: i32  # index in the tool table of the tool now in the spindle (M61; as LinuxCNC 2.9)


class EMC_TOOL_START_CHANGE(EMC_TOOL_CMD_MSG, type_id=1110): ...


class EMC_TOOL_STAT_MSG(RCS_STAT_MSG): ...


class EMC_TOOL_STAT(EMC_TOOL_STAT_MSG, type_id=1199):
    pocketPrepped: i32
    toolInSpindle: i32  # 0: no tool
    toolFromPocket: i32
    toolTableCurrent: CANON_TOOL_TABLE  # data of the tool in the spindle


# ============================================================================ AUX (NML-064)


class EMC_AUX_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.IO, waits_for_motion=True):
    """Emergency stop, and waiting on an input (M66)."""


class EMC_AUX_ESTOP_ON(EMC_AUX_CMD_MSG, type_id=1206): ...


class EMC_AUX_ESTOP_OFF(EMC_AUX_CMD_MSG, type_id=1207): ...


class EMC_AUX_ESTOP_RESET(EMC_AUX_CMD_MSG, type_id=1208): ...


class EMC_AUX_INPUT_WAIT(
    EMC_AUX_CMD_MSG, type_id=1209, receiver=Receiver.TASK, waits_for_motion=False
):
    index: i32
    input_type: i32  # INPUT_TYPE
    wait_type: i32  # WAIT_MODE
    timeout: f64  # seconds


class EMC_AUX_STAT_MSG(RCS_STAT_MSG): ...


class EMC_AUX_STAT(EMC_AUX_STAT_MSG, type_id=1299):
    estop: i32  # non-zero while in emergency stop


# ============================================================================ COOLANT (NML-066)


class EMC_COOLANT_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.IO, waits_for_motion=True):
    """Mist (M7) and flood (M8) coolant, both off with M9."""


class EMC_COOLANT_MIST_ON(EMC_COOLANT_CMD_MSG, type_id=1404): ...


class EMC_COOLANT_MIST_OFF(EMC_COOLANT_CMD_MSG, type_id=1405): ...


class EMC_COOLANT_FLOOD_ON(EMC_COOLANT_CMD_MSG, type_id=1406): ...


class EMC_COOLANT_FLOOD_OFF(EMC_COOLANT_CMD_MSG, type_id=1407): ...


class EMC_COOLANT_STAT_MSG(RCS_STAT_MSG): ...


class EMC_COOLANT_STAT(EMC_COOLANT_STAT_MSG, type_id=1499):
    mist: i32
    flood: i32


# ============================================================================ LUBE (NML-067)


class EMC_LUBE_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.IO, waits_for_motion=True):
    """The lubrication pump."""


class EMC_LUBE_ON(EMC_LUBE_CMD_MSG, type_id=1504): ...


class EMC_LUBE_OFF(EMC_LUBE_CMD_MSG, type_id=1505): ...


class EMC_LUBE_STAT_MSG(RCS_STAT_MSG): ...


class EMC_LUBE_STAT(EMC_LUBE_STAT_MSG, type_id=1599):
    on: i32
    level: i32  # 0 low, 1 ok


# ============================================================================ IO (NML-068)
# EMC_IO_PLUGIN_CALL is declared with the top-level messages (its base is EMC_CMD_MSG).


class EMC_IO_CMD_MSG(RCS_CMD_MSG, receiver=Receiver.IO, waits_for_motion=True):
    """iocontrol as a whole; its status aggregates tool, coolant, aux and lube."""


class EMC_IO_INIT(EMC_IO_CMD_MSG, type_id=1601): ...


class EMC_IO_HALT(EMC_IO_CMD_MSG, type_id=1602): ...


class EMC_IO_ABORT(EMC_IO_CMD_MSG, type_id=1603): ...


class EMC_IO_SET_CYCLE_TIME(EMC_IO_CMD_MSG, type_id=1604):
    cycleTime: f64


class EMC_IO_STAT_MSG(RCS_STAT_MSG):
    heartbeat: u32


class EMC_IO_STAT(EMC_IO_STAT_MSG, type_id=1699):
    cycleTime: f64
    debug: i32
    reason: i32  # EMC_IO_ABORT_REASON_ENUM of the last abort or fault
    fault: i32  # 1: the last tool change failed
    tool: EMC_TOOL_STAT
    coolant: EMC_COOLANT_STAT
    aux: EMC_AUX_STAT
    lube: EMC_LUBE_STAT


# ============================================================================ EMC (NML-069)
# Messages for the controller as a whole, and EMC_STAT: the status every GUI reads from
# the emcStatus buffer (``stat.task``, ``stat.motion``, ``stat.io``; NML-070).


class EMC_NULL(RCS_CMD_MSG, type_id=21): ...


class EMC_SET_DEBUG(RCS_CMD_MSG, type_id=22):
    debug: i32  # EMC_DEBUG bits


class EMC_SYSTEM_CMD(RCS_CMD_MSG, type_id=30, receiver=Receiver.TASK):
    string: string(EMC_SYSTEM_CMD_LEN)


class EMC_CMD_MSG(RCS_CMD_MSG):
    """Commands for the whole controller."""


class EMC_EXEC_PLUGIN_CALL(EMC_CMD_MSG, type_id=1112, receiver=Receiver.IO, waits_for_motion=True):
    len: i32
    call: string(EMC_PLUGIN_CALL_LEN)


class EMC_IO_PLUGIN_CALL(EMC_CMD_MSG, type_id=1113, receiver=Receiver.IO, waits_for_motion=True):
    len: i32
    call: string(EMC_PLUGIN_CALL_LEN)


class EMC_INIT(EMC_CMD_MSG, type_id=1901): ...


class EMC_HALT(EMC_CMD_MSG, type_id=1902): ...


class EMC_ABORT(EMC_CMD_MSG, type_id=1903): ...


class EMC_STAT_MSG(RCS_STAT_MSG): ...


class EMC_STAT(EMC_STAT_MSG, type_id=1999):
    task: EMC_TASK_STAT
    motion: EMC_MOTION_STAT
    io: EMC_IO_STAT
    debug: i32
