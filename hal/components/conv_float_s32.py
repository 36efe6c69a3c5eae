"""conv_float_s32: convert float to s32 (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("float", "s32")
