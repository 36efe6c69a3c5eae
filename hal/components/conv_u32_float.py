"""conv_u32_float: convert u32 to float (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("u32", "float")
