"""The parsed block (one line of NC code) and the code tables (INTERP-003)."""

from __future__ import annotations

# G codes are stored as 10 x the number, as LinuxCNC does (G38.2 -> 382).
G_0, G_1, G_2, G_3, G_4, G_5, G_5_1, G_5_2, G_5_3 = 0, 10, 20, 30, 40, 50, 51, 52, 53
G_7, G_8, G_10 = 70, 80, 100
G_17, G_17_1, G_18, G_18_1, G_19, G_19_1 = 170, 171, 180, 181, 190, 191
G_20, G_21, G_28, G_28_1, G_30, G_30_1 = 200, 210, 280, 281, 300, 301
G_33, G_33_1, G_38_2, G_38_3, G_38_4, G_38_5 = 330, 331, 382, 383, 384, 385
G_40, G_41, G_41_1, G_42, G_42_1, G_43, G_43_1, G_43_2, G_49 = (
    400,
    410,
    411,
    420,
    421,
    430,
    431,
    432,
    490,
)
G_52, G_53, G_54, G_55, G_56, G_57, G_58, G_59 = 520, 530, 540, 550, 560, 570, 580, 590
G_59_1, G_59_2, G_59_3, G_61, G_61_1, G_64 = 591, 592, 593, 610, 611, 640
G_70, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2, G_73, G_74, G_76 = (
    700,
    710,
    711,
    712,
    720,
    721,
    722,
    730,
    740,
    760,
)
G_80, G_81, G_82, G_83, G_84, G_85, G_86, G_87, G_88, G_89 = (
    800,
    810,
    820,
    830,
    840,
    850,
    860,
    870,
    880,
    890,
)
G_90, G_90_1, G_91, G_91_1, G_92, G_92_1, G_92_2, G_92_3 = 900, 901, 910, 911, 920, 921, 922, 923
G_93, G_94, G_95, G_96, G_97, G_98, G_99 = 930, 940, 950, 960, 970, 980, 990

# modal groups (index into Block.g_modes)
GM_MODAL_0, GM_MOTION, GM_SET_PLANE, GM_DISTANCE_MODE, GM_IJK_DISTANCE_MODE = 0, 1, 2, 3, 4
GM_FEED_MODE, GM_LENGTH_UNITS, GM_CUTTER_COMP, GM_TOOL_LENGTH_OFFSET = 5, 6, 7, 8
GM_RETRACT_MODE, GM_COORD_SYSTEM, GM_CONTROL_MODE, GM_SPINDLE_MODE = 10, 12, 13, 14
GM_LATHE_DIAMETER_MODE, GM_G92_IS_APPLIED = 15, 16

_G_GROUPS = {
    0: [G_4, G_10, G_28, G_28_1, G_30, G_30_1, G_52, G_53, G_92, G_92_1, G_92_2, G_92_3],
    1: [
        G_0,
        G_1,
        G_2,
        G_3,
        G_5,
        G_5_1,
        G_5_2,
        G_33,
        G_33_1,
        G_38_2,
        G_38_3,
        G_38_4,
        G_38_5,
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
        G_85,
        G_86,
        G_87,
        G_88,
        G_89,
    ],
    2: [G_17, G_17_1, G_18, G_18_1, G_19, G_19_1],
    3: [G_90, G_91],
    4: [G_90_1, G_91_1],
    5: [G_93, G_94, G_95],
    6: [G_20, G_21],
    7: [G_40, G_41, G_41_1, G_42, G_42_1],
    8: [G_43, G_43_1, G_43_2, G_49],
    10: [G_98, G_99],
    12: [G_54, G_55, G_56, G_57, G_58, G_59, G_59_1, G_59_2, G_59_3],
    13: [G_61, G_61_1, G_64],
    14: [G_96, G_97],
    15: [G_7, G_8],
    16: [G_92_2, G_92_3],
}
# LinuxCNC's _gees: G5.3 is group 0; G92.1, G92.2 and G92.3 are group 16 (overriding the
# group 0 entries above); G5, G5.1 and G5.2 are motion.
GEES: dict[int, int] = {}
for _group, _codes in _G_GROUPS.items():
    for _code in _codes:
        GEES[_code] = _group
GEES[G_5_3] = 0
GEES[G_92_1] = 16
GEES[G_92_2] = 16
GEES[G_92_3] = 16

# M code -> modal group (LinuxCNC's _ems)
EMS: dict[int, int] = {
    0: 4,
    1: 4,
    2: 4,
    3: 7,
    4: 7,
    5: 7,
    6: 6,
    7: 8,
    8: 8,
    9: 8,
    19: 7,
    30: 4,
    48: 9,
    49: 9,
    50: 9,
    51: 9,
    52: 9,
    53: 9,
    60: 4,
    61: 6,
    62: 5,
    63: 5,
    64: 5,
    65: 5,
    66: 5,
    67: 5,
    68: 5,
    70: 7,
    71: 7,
    72: 7,
    73: 7,
    99: 4,
}
for _m in range(100, 200):
    EMS[_m] = 10

# o-word types
(
    O_none,
    O_sub,
    O_endsub,
    O_call,
    O_do,
    O_while,
    O_if,
    O_elseif,
    O_else,
    O_endif,
    O_break,
    O_continue,
    O_endwhile,
    O_return,
    O_repeat,
    O_endrepeat,
    M_98,
    M_99,
    O_,
) = range(19)
O_OPS = [
    "O_none",
    "O_sub",
    "O_endsub",
    "O_call",
    "O_do",
    "O_while",
    "O_if",
    "O_elseif",
    "O_else",
    "O_endif",
    "O_break",
    "O_continue",
    "O_endwhile",
    "O_return",
    "O_repeat",
    "O_endrepeat",
    "M_98",
    "M_99",
    "O_",
]
# call types (a call frame's kind; Python O-word procedures and remaps may yield and resume)
CT_NONE, CT_NGC_OWORD_SUB, CT_NGC_M98_SUB, CT_PYTHON_OWORD_SUB, CT_REMAP = 0, 1, 2, 3, 4


def is_a_cycle(motion: int) -> bool:
    return G_80 < motion < G_90 or motion in (G_73, G_74)


class Block:
    """One parsed line; word flags default to False and numbers to LinuxCNC's sentinels.

    The defaults are class attributes, so making a block costs two lists; a reader sets
    only the words the line has.
    """

    a_flag = b_flag = c_flag = d_flag = dollar_flag = e_flag = f_flag = h_flag = False
    i_flag = j_flag = k_flag = l_flag = p_flag = q_flag = r_flag = s_flag = t_flag = False
    u_flag = v_flag = w_flag = x_flag = y_flag = z_flag = radius_flag = theta_flag = False
    a_number = b_number = c_number = d_number_float = dollar_number = e_number = 0.0
    f_number = i_number = j_number = k_number = r_number = s_number = 0.0
    u_number = v_number = w_number = x_number = y_number = z_number = radius = theta = 0.0
    t_number = 0
    comment = ""
    h_number = -1
    l_number = -1
    line_number = -1
    n_number = -1
    motion_to_be = -1
    m_count = 0
    user_m = 0
    p_number = -1.0
    q_number = -1.0
    offset = 0
    o_type = O_none
    o_name: str | None = None
    call_type = -1
    params: list[float] | None = None
    param_cnt = 0
    # remapping (remap.py): the steps of this block that run a remap, the steps done, the
    # remap running now, whether a remapped code meant its built-in inside its own procedure
    remappings: set[int] | None = None
    breadcrumbs: set[int] | None = None
    executing_remap = None
    builtin_used = False
    phase = 0
    saved_line_number = 0
    is_mdi_remap = False  # found in an MDI line (its saved_line_number is no program line)

    def __init__(self) -> None:
        self.g_modes = [-1] * 17
        self.m_modes = [-1] * 11


class OWordBlock(Block):
    """The block of an O-word line read by its plan: reading sets only O-word fields (and
    the comment), so the G and M code tables are shared, read-only, not made per line."""

    g_modes = (-1,) * 17  # type: ignore[assignment]
    m_modes = (-1,) * 11  # type: ignore[assignment]

    def __init__(self) -> None:
        pass
