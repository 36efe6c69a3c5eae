"""conv_s32_float: convert s32 to float (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("s32", "float")
