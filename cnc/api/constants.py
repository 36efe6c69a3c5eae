"""LinuxCNC's constants, with the names and values of its ``linuxcnc`` module.

Plain ints with no imports, so that ``cnc.STATE_ESTOP`` costs nothing. The values are
LinuxCNC's protocol numbers, also declared by the NML catalogue (``nml.emc``); a test checks
that the two agree.
"""

from __future__ import annotations

# Where LinuxCNC's files would be; this controller has no installed tree.
PREFIX = ""
SHARE = ""
version = "2.9 (cnc)"

# EmcJointType: stat.joint[n]["jointType"]
LINEAR = 1
ANGULAR = 2

# stat.task_state, command.state()
STATE_ESTOP = 1
STATE_ESTOP_RESET = 2
STATE_OFF = 3
STATE_ON = 4

# stat.task_mode, command.mode()
MODE_MANUAL = 1
MODE_AUTO = 2
MODE_MDI = 3

# stat.interp_state
INTERP_IDLE = 1
INTERP_READING = 2
INTERP_PAUSED = 3
INTERP_WAITING = 4

# stat.exec_state (6 is unused, as in LinuxCNC)
EXEC_ERROR = 1
EXEC_DONE = 2
EXEC_WAITING_FOR_MOTION = 3
EXEC_WAITING_FOR_MOTION_QUEUE = 4
EXEC_WAITING_FOR_IO = 5
EXEC_WAITING_FOR_MOTION_AND_IO = 7
EXEC_WAITING_FOR_DELAY = 8
EXEC_WAITING_FOR_SYSTEM_CMD = 9
EXEC_WAITING_FOR_SPINDLE_ORIENTED = 10

# stat.state, command.wait_complete()
RCS_DONE = 1
RCS_EXEC = 2
RCS_ERROR = 3

# command.spindle()
SPINDLE_FORWARD = 1
SPINDLE_REVERSE = -1
SPINDLE_OFF = 0
SPINDLE_INCREASE = 10
SPINDLE_DECREASE = 11
SPINDLE_CONSTANT = 12

# command.mist(), command.flood(), command.brake(); stat.mist, stat.flood
MIST_ON = 1
MIST_OFF = 0
FLOOD_ON = 1
FLOOD_OFF = 0
BRAKE_ENGAGE = 1
BRAKE_RELEASE = 0

# command.jog()
JOG_STOP = 0
JOG_CONTINUOUS = 1
JOG_INCREMENT = 2

# command.auto()
AUTO_RUN = 0
AUTO_PAUSE = 1
AUTO_RESUME = 2
AUTO_STEP = 3
AUTO_REVERSE = 4
AUTO_FORWARD = 5

# stat.motion_mode, command.traj_mode()
TRAJ_MODE_FREE = 1
TRAJ_MODE_COORD = 2
TRAJ_MODE_TELEOP = 3

# stat.motion_type (0: no motion)
MOTION_TYPE_TRAVERSE = 1
MOTION_TYPE_FEED = 2
MOTION_TYPE_ARC = 3
MOTION_TYPE_TOOLCHANGE = 4
MOTION_TYPE_PROBING = 5
MOTION_TYPE_INDEXROTARY = 6

# stat.kinematics_type
KINEMATICS_IDENTITY = 1
KINEMATICS_FORWARD_ONLY = 2
KINEMATICS_INVERSE_ONLY = 3
KINEMATICS_BOTH = 4

# stat.debug, command.debug(): bits of [EMC]DEBUG
DEBUG_CONFIG = 0x00000002
DEBUG_VERSIONS = 0x00000008
DEBUG_TASK_ISSUE = 0x00000010
DEBUG_NML = 0x00000040
DEBUG_MOTION_TIME = 0x00000080
DEBUG_INTERP = 0x00000100
DEBUG_RCS = 0x00000200
DEBUG_INTERP_LIST = 0x00000800
DEBUG_OWORD = 0x00002000
DEBUG_REMAP = 0x00004000
DEBUG_PYTHON = 0x00008000
DEBUG_STATE_TAGS = 0x00080000

# Sizes of stat.joint and stat.axis
MAX_JOINTS = 16
MAX_AXIS = 9

# error_channel.poll() kinds: the message type numbers (NML_* are LinuxCNC's generic ones)
NML_ERROR = 1
NML_TEXT = 2
NML_DISPLAY = 3
OPERATOR_ERROR = 11
OPERATOR_TEXT = 12
OPERATOR_DISPLAY = 13

__all__ = [name for name in dir() if not name.startswith("_") and name != "annotations"]
