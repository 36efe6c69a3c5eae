"""RS274NGC interpreter (INTERP-*, TOOL-017..029): see ``interp.Interpreter`` and ``canon``."""

from .canon import Canon, PrintingCanon
from .errors import InterpError
from .interp import Interpreter

__all__ = ["Canon", "InterpError", "Interpreter", "PrintingCanon"]
