"""conv_bit_u32: convert bit to u32 (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("bit", "u32")
