"""conv_s32_bit: convert s32 to bit (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("s32", "bit")
