"""conv_bit_float: convert bit to float (see _conv.py)."""

from hal.components._conv import make

COMPONENT = make("bit", "float")
