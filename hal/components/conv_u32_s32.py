"""conv_u32_s32: convert u32 to s32 (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("u32", "s32")
