"""State tags: the interpreter's modal state that travels with each move (LinuxCNC's
StateTag and its interpreter's write_state_tag and active_modes).

The interpreter gives its canon a tag (``UPDATE_TAG``) before each move and at the end of
each block; task's canon puts the latest into every move it queues, motion reports the tag
of the move it is carrying out (EMC_TRAJ_STAT.tag), and task shows that move's modes while
a program runs and, after an abort, brings the interpreter back to them
(``Interpreter.restore_from_tag``): the interpreter reads ahead of motion, so its own
modes are those of a line motion has not reached.

A tag is a tuple in the order of LinuxCNC's state_tag_t: its 5 floats (``fields_float``),
8 ints (``fields``) and the packed flags; task/canon.py turns it into ``nml.emc.StateTag``
and back. The numbers below are LinuxCNC's GM_FIELD_* and GM_FLAG_* (nml.emc's
StateField, StateFieldFloat and StateFlag, which tests hold equal); they are repeated here
so that the interpreter does not load the message catalogue.
"""

from __future__ import annotations

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
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
)
from .common import CONSTANT_RPM, INVERSE_TIME, LEFT, MODE_ABSOLUTE, OLD_Z, RIGHT, UNITS_PER_MINUTE

# fields_float (flat positions 0..4)
FLOAT_LINE_NUMBER, FLOAT_FEED, FLOAT_SPEED, FLOAT_PATH_TOLERANCE, FLOAT_NAIVE_CAM_TOLERANCE = range(
    5
)
FLOAT_FIELDS = 5
# fields (flat positions 5..12)
LINE_NUMBER, G_MODE_0, CUTTER_COMP, MOTION_MODE, PLANE, M_MODES_4, ORIGIN, TOOLCHANGE = range(
    FLOAT_FIELDS, FLOAT_FIELDS + 8
)
FLAGS = FLOAT_FIELDS + 8  # the packed flags (flat position 13)
# bits of the packed flags
(
    FLAG_UNITS,
    FLAG_DISTANCE_MODE,
    FLAG_TOOL_OFFSETS_ON,
    FLAG_RETRACT_OLDZ,
    FLAG_BLEND,
    FLAG_EXACT_STOP,
    FLAG_FEED_INVERSE_TIME,
    FLAG_FEED_UPM,
    FLAG_CSS_MODE,
    FLAG_IJK_ABS,
    FLAG_DIAMETER_MODE,
    FLAG_G92_IS_APPLIED,
    FLAG_SPINDLE_ON,
    FLAG_SPINDLE_CW,
    FLAG_MIST,
    FLAG_FLOOD,
    FLAG_FEED_OVERRIDE,
    FLAG_SPEED_OVERRIDE,
    FLAG_ADAPTIVE_FEED,
    FLAG_FEED_HOLD,
    FLAG_RESTORABLE,
    FLAG_IN_REMAP,
    FLAG_IN_SUB,
    FLAG_EXTERNAL_FILE,
) = range(24)

_PLANE_CODES = {
    C.PLANE_XY: G_17,
    C.PLANE_XZ: G_18,
    C.PLANE_YZ: G_19,
    C.PLANE_UV: G_17_1,
    C.PLANE_UW: G_18_1,
    C.PLANE_VW: G_19_1,
}

Tag = tuple  # (5 floats, 8 ints, packed flags): see the module's docstring


def state_tag(interp, block) -> Tag:
    """The interpreter's modal state now, at ``block`` (None: a line without one, as the
    fast path's), as LinuxCNC's write_state_tag packs it. One difference: SPINDLE_ON is
    set when spindle 0 turns (LinuxCNC 2.9 sets it when it is stopped, fixed since)."""
    in_remap = interp.remap_level > 0
    in_sub = interp.call_level > 0 and not in_remap
    origin = interp.origin_index
    turning = interp.spindle_turning[0]
    control = interp.control_mode
    feed_mode = interp.feed_mode
    # (comparisons, not bool(): this runs at every move and block end)
    flags = (
        (interp.length_units == C.UNITS_INCHES) << FLAG_UNITS
        | (interp.distance_mode == MODE_ABSOLUTE) << FLAG_DISTANCE_MODE
        | any(interp.tool_offset) << FLAG_TOOL_OFFSETS_ON
        | (interp.retract_mode == OLD_Z) << FLAG_RETRACT_OLDZ
        | (control == C.CONTINUOUS) << FLAG_BLEND
        | (control == C.EXACT_STOP) << FLAG_EXACT_STOP
        | (feed_mode == INVERSE_TIME) << FLAG_FEED_INVERSE_TIME
        | (feed_mode == UNITS_PER_MINUTE) << FLAG_FEED_UPM
        | (interp.spindle_mode[0] == CONSTANT_RPM) << FLAG_CSS_MODE
        | (interp.ijk_distance_mode == MODE_ABSOLUTE) << FLAG_IJK_ABS
        | (interp.lathe_diameter_mode != 0) << FLAG_DIAMETER_MODE
        | (interp.parameters[5210] != 0) << FLAG_G92_IS_APPLIED
        | (turning != C.STOPPED) << FLAG_SPINDLE_ON
        | (turning == C.CLOCKWISE) << FLAG_SPINDLE_CW
        | (interp.mist != 0) << FLAG_MIST
        | (interp.flood != 0) << FLAG_FLOOD
        | (interp.feed_override != 0) << FLAG_FEED_OVERRIDE
        | (interp.speed_override[0] != 0) << FLAG_SPEED_OVERRIDE
        | (interp.adaptive_feed != 0) << FLAG_ADAPTIVE_FEED
        | (interp.feed_hold != 0) << FLAG_FEED_HOLD
        | (not in_remap and not in_sub) << FLAG_RESTORABLE
        | in_remap << FLAG_IN_REMAP
        | in_sub << FLAG_IN_SUB
        | (interp.filename != interp.sub_context[0].filename) << FLAG_EXTERNAL_FILE
    )
    side = interp.cutter_comp_side
    line = int(interp.sequence_number)
    origin = int(origin)  # (a float when read from the parameter file)
    return (
        float(line),
        interp.feed_rate,
        interp.speed[0],
        interp.tolerance,
        interp.naivecam_tolerance,
        line,
        -1 if block is None else block.g_modes[0],
        G_42 if side == RIGHT else G_41 if side == LEFT else G_40,
        int(interp.motion_mode),
        _PLANE_CODES.get(interp.plane, -1),
        -1 if block is None else block.m_modes[4],
        530 + 10 * origin if origin < 7 else 584 + origin,
        -1 if block is None else block.m_modes[6],
        flags,
    )


def is_valid(tag: Tag) -> bool:
    """A tag some move carried (LinuxCNC's StateTag::is_valid): not the empty tag of a
    status before any move, nor of a move from before the program's first lines."""
    return tag[LINE_NUMBER] > 1 and tag[ORIGIN] >= 540 and tag[PLANE] >= 170


def is_restorable(tag: Tag) -> bool:
    """A tag the interpreter may be brought back to after an abort: valid, and not taken
    inside a subroutine or a remap (whose caller's state is not in it)."""
    return is_valid(tag) and bool(tag[FLAGS] >> FLAG_RESTORABLE & 1)


def active_modes(tag: Tag) -> tuple[list[int], list[int], list[float]]:
    """The G codes, M codes and settings a tag holds, in the layout of the interpreter's
    active_g_codes, active_m_codes and active_settings (LinuxCNC's active_modes)."""
    flags = tag[FLAGS]

    def flag(bit: int) -> bool:
        return bool(flags >> bit & 1)

    line = tag[LINE_NUMBER]
    g_codes = [
        line,
        tag[MOTION_MODE],
        tag[G_MODE_0],
        tag[PLANE],
        tag[CUTTER_COMP],
        G_20 if flag(FLAG_UNITS) else G_21,
        G_90 if flag(FLAG_DISTANCE_MODE) else G_91,
        G_93 if flag(FLAG_FEED_INVERSE_TIME) else G_94 if flag(FLAG_FEED_UPM) else G_95,
        tag[ORIGIN],
        G_43 if flag(FLAG_TOOL_OFFSETS_ON) else G_49,
        G_98 if flag(FLAG_RETRACT_OLDZ) else G_99,
        G_64 if flag(FLAG_BLEND) else G_61_1 if flag(FLAG_EXACT_STOP) else G_61,
        -1,
        G_97 if flag(FLAG_CSS_MODE) else G_96,
        G_90_1 if flag(FLAG_IJK_ABS) else G_91_1,
        G_7 if flag(FLAG_DIAMETER_MODE) else G_8,
        G_92_3 if flag(FLAG_G92_IS_APPLIED) else G_92_2,
    ]
    if flag(FLAG_FEED_OVERRIDE):
        overrides = 48 if flag(FLAG_SPEED_OVERRIDE) else 50
    else:
        overrides = 51 if flag(FLAG_SPEED_OVERRIDE) else 49
    m_codes = [
        line,
        tag[M_MODES_4],
        (3 if flag(FLAG_SPINDLE_CW) else 4) if flag(FLAG_SPINDLE_ON) else 5,
        tag[TOOLCHANGE],
        7 if flag(FLAG_MIST) else -1 if flag(FLAG_FLOOD) else 9,
        8 if flag(FLAG_FLOOD) else -1,
        overrides,
        52 if flag(FLAG_ADAPTIVE_FEED) else -1,
        53 if flag(FLAG_FEED_HOLD) else -1,
        0,
    ]
    settings = [float(line), *tag[FLOAT_FEED:FLOAT_FIELDS]]
    return g_codes, m_codes, settings
