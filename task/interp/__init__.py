"""RS274NGC interpreter, a reimplementation of LinuxCNC 2.9's (INTERP-*, TOOL-017..029).

It reads a program line by line, executes each block in LinuxCNC's order of execution and
calls a canon (``canon.Canon``); ``canon.PrintingCanon`` prints the calls the way LinuxCNC's
``rs274`` does, and ``cli`` is ``cnc rs274``. Modules, one concern each:

========== ==================================================================
interp     the Interpreter: init/open/read/execute/synch/exit, block checks,
           order of execution, comments, G-code mode changes, M2/M30
reader     lexing a line into a Block: words, expressions, parameters, O-words
compiled   expressions compiled to closures, and line plans, for lines read
           again (loops, subroutines)
block      the Block and the G/M code tables (modal groups)
params     numbered and named parameters, the .var file
owords     subroutines, calls, loops and conditionals
motion     G0/G1/G33, arcs, probing, G76, splines, end points
offsets    G54..G59.3, G10 L2/L20, G28/G30, G52/G92
tools      T, M6, M61, G43/G49, G10 L1/L10/L11
mcodes     M codes and the M70..M73 modal state
cycles     canned cycles G73/G74/G81..G89
comp       cutter radius compensation
g7x        lathe cycles G70..G72
ldmath     LinuxCNC's long double and glibc arithmetic where it shows
stack      LinuxCNC's error stack (function names) for rs274 -s
========== ==================================================================
"""

from .canon import Canon, PrintingCanon
from .errors import InterpError
from .interp import Interpreter

__all__ = ["Canon", "InterpError", "Interpreter", "PrintingCanon"]
