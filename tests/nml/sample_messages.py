"""Throwaway message types for NML transport tests (type numbers far from LinuxCNC's)."""

from nml.message import RCS_CMD_MSG, RCS_STAT_MSG, array, f64, i32, i64, string


class TEST_CMD(RCS_CMD_MSG, type_id=90001):
    writer: i32
    index: i64
    text: string(64)


class TEST_STAT(RCS_STAT_MSG, type_id=90002):
    counter: i64
    values: array(f64, 2000)  # 16 kB, about the size of EMC_STAT: torn writes would show


class TEST_BIG(RCS_CMD_MSG, type_id=90003):
    payload: array(f64, 4096)
