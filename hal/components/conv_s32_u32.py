"""conv_s32_u32: convert s32 to u32 (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("s32", "u32")
