"""conv_u32_bit: convert u32 to bit (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("u32", "bit")
