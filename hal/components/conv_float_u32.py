"""conv_float_u32: convert float to u32 (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("float", "u32")
