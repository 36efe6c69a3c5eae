"""conv_bit_s32: convert bit to s32 (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("bit", "s32")
