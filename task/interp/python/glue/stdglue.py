"""Standard glue: prolog and epilog functions for remapped T, M6, M61, S, F and G-code cycles
(REMAP-047..052), with LinuxCNC's stdglue names and meaning, for Python 3.

Use from a configuration's ``remap.py``::

    from stdglue import *

and in the INI, e.g.::

    REMAP=T   prolog=prepare_prolog ngc=prepare epilog=prepare_epilog
    REMAP=M6  modalgroup=6 prolog=change_prolog ngc=change epilog=change_epilog
    REMAP=M61 modalgroup=6 prolog=settool_prolog ngc=settool epilog=settool_epilog
    REMAP=S   prolog=setspeed_prolog ngc=setspeed epilog=setspeed_epilog
    REMAP=F   prolog=setfeed_prolog ngc=setfeed epilog=setfeed_epilog
    REMAP=G84.3 modalgroup=1 argspec=xyzabcuvwqplr prolog=cycle_prolog ngc=g843 epilog=cycle_epilog

Each prolog checks the block and exposes parameters to the NGC procedure; the procedure
returns a positive value (``o<..> endsub [1]``) for success; the epilog reads back the
parameters (which the procedure may have changed) and does what the built-in code would have
done. If the procedure used the built-in code itself (``T#<tool>`` inside the T remap), the
epilog does nothing more.

Exposed parameters: T ``#<tool>`` ``#<pocket>``; M6 ``#<tool_in_spindle>``
``#<selected_tool>`` ``#<current_pocket>`` ``#<selected_pocket>``; M61 ``#<tool>``
``#<pocket>``; S ``#<speed>``; F ``#<feed>``. Pockets are the tool table's pocket numbers,
as LinuxCNC's stdglue has them (with sequential pocket numbers they are the table's
indexes, which the interpreter uses).

Errors use ``set_errormsg`` and ``INTERP_ERROR`` (LinuxCNC also reports those from a prolog,
which it does not for a returned message), so this module behaves the same under LinuxCNC.
"""

import emccanon
from emccanon import MESSAGE  # noqa: F401  (configurations use it through "import *")
from interpreter import *  # noqa: F403  (as LinuxCNC's stdglue: remap.py gets INTERP_OK ...)
from interpreter import INTERP_ERROR, INTERP_EXECUTE_FINISH, INTERP_OK, INVERSE_TIME

TOLERANCE_EQUAL = 0.0001
# iocontrol's tool changer fault (#5600) and its reason (#5601; negative: a hard fault)
TC_FAULT, TC_REASON = 5600, 5601


def _fail(self, message):
    self.set_errormsg(message)
    return INTERP_ERROR


def _procedure_returned(self, code):
    """None when the remap's NGC procedure returned a value, else the error status."""
    if self.value_returned:
        return None
    remap = self.blocks[self.remap_level].executing_remap
    return _fail(
        self,
        f"the {remap.name} remap procedure {remap.remap_ngc or remap.remap_py} "
        "did not return a value",
    )


def _builtin_used(self):
    """The procedure used the built-in code itself: nothing is left to do."""
    return self.blocks[self.remap_level].builtin_used


def _changer_hard_fault(self):
    """A hard fault of the tool changer (iocontrol v2), as an error message, or None; a soft
    fault is reported and execution goes on."""
    if self.params[TC_FAULT] > 0.0:
        reason = int(self.params[TC_REASON])
        if reason < 0:
            return f"Toolchanger hard fault {reason}"
        print(f"Toolchanger soft fault {reason}")
    return None


# ----------------------------------------------------------------- S, F
def setspeed_prolog(self, **words):
    """REMAP=S: exposes #<speed>."""
    block = self.blocks[self.remap_level]
    if not block.s_flag:
        return _fail(self, "S requires a value")
    self.params["speed"] = block.s_number
    return INTERP_OK


def setspeed_epilog(self, **words):
    failed = _procedure_returned(self, "S")
    if failed is not None:
        return failed
    if self.return_value < -TOLERANCE_EQUAL:
        return _fail(self, f"S: remap procedure returned {self.return_value:f}")
    if not _builtin_used(self):
        speed = self.params["speed"]
        self.speed[0] = speed
        emccanon.enqueue_SET_SPINDLE_SPEED(0, speed)
    return INTERP_OK


def setfeed_prolog(self, **words):
    """REMAP=F: exposes #<feed>."""
    block = self.blocks[self.remap_level]
    if not block.f_flag:
        return _fail(self, "F requires a value")
    self.params["feed"] = block.f_number
    return INTERP_OK


def setfeed_epilog(self, **words):
    failed = _procedure_returned(self, "F")
    if failed is not None:
        return failed
    if not _builtin_used(self):
        self.feed_rate = self.params["feed"]
        emccanon.enqueue_SET_FEED_RATE(self.feed_rate)
    return INTERP_OK


# --------------------------------------------------------------------- T
def prepare_prolog(self, **words):
    """REMAP=T: exposes #<tool> and #<pocket> (-1 for T0, unloading)."""
    block = self.blocks[self.remap_level]
    if not block.t_flag:
        return _fail(self, "T requires a tool number")
    tool = block.t_number
    if tool:
        status, pocket = self.find_tool_pocket(tool)
        if status != INTERP_OK:
            return _fail(self, f"T{tool}: pocket not found")
    else:
        pocket = -1
    self.params["tool"] = tool
    self.params["pocket"] = pocket
    return INTERP_OK


def prepare_epilog(self, **words):
    failed = _procedure_returned(self, "T")
    if failed is not None:
        return failed
    if _builtin_used(self):
        return INTERP_OK
    if self.return_value > 0:
        self.selected_tool = int(self.params["tool"])
        self.selected_pocket = int(self.params["pocket"])
        emccanon.SELECT_TOOL(self.selected_tool)
        return INTERP_OK
    tool = int(self.params["tool"])
    return _fail(self, f"T{tool}: aborted (return code {self.return_value:.1f})")


# -------------------------------------------------------------------- M6
def change_prolog(self, **words):
    """REMAP=M6: exposes #<tool_in_spindle>, #<selected_tool>, #<current_pocket> and
    #<selected_pocket>."""
    fault = _changer_hard_fault(self)
    if fault:
        return _fail(self, fault)
    if self.selected_pocket < 0:
        return _fail(self, "M6: no tool prepared")
    if self.cutter_comp_side:
        return _fail(self, "Cannot change tools with cutter radius compensation on")
    self.params["tool_in_spindle"] = self.current_tool
    self.params["selected_tool"] = self.selected_tool
    self.params["current_pocket"] = self.current_pocket
    self.params["selected_pocket"] = self.selected_pocket
    return INTERP_OK


def change_epilog(self, **words):
    """Commits the change (CHANGE_TOOL, the new tool's parameters) and makes task
    synchronise before it reads on (the tool, its offsets and the position change)."""
    failed = _procedure_returned(self, "M6")
    if failed is not None:
        yield failed
        return
    fault = _changer_hard_fault(self)
    if fault:
        yield _fail(self, fault)
        return
    if _builtin_used(self):
        yield INTERP_OK
        return
    if self.return_value > 0.0:
        self.selected_pocket = int(self.params["selected_pocket"])
        emccanon.CHANGE_TOOL(self.selected_pocket)
        self.current_pocket = self.selected_pocket
        self.selected_pocket = -1
        self.selected_tool = -1
        self.set_tool_parameters()
        self.toolchange_flag = True
        yield INTERP_EXECUTE_FINISH
    else:
        # let the messages of the procedure out first
        yield INTERP_EXECUTE_FINISH
        yield _fail(self, f"M6 aborted (return code {self.return_value:.1f})")


# ------------------------------------------------------------------- M61
def settool_prolog(self, **words):
    """REMAP=M61: exposes #<tool> and #<pocket>."""
    block = self.blocks[self.remap_level]
    if not block.q_flag:
        return _fail(self, "M61 requires a Q parameter")
    tool = int(block.q_number)
    if tool < -TOLERANCE_EQUAL:
        return _fail(self, "M61: Q value < 0")
    status, pocket = self.find_tool_pocket(tool)
    if status != INTERP_OK:
        return _fail(self, f"M61 failed: requested tool {tool} not in table")
    self.params["tool"] = tool
    self.params["pocket"] = pocket
    return INTERP_OK


def settool_epilog(self, **words):
    failed = _procedure_returned(self, "M61")
    if failed is not None:
        return failed
    if _builtin_used(self):
        return INTERP_OK
    if self.return_value > 0.0:
        self.current_tool = int(self.params["tool"])
        self.current_pocket = int(self.params["pocket"])
        emccanon.CHANGE_TOOL_NUMBER(self.current_pocket)
        self.toolchange_flag = True
        self.set_tool_parameters()
        return INTERP_OK
    return _fail(self, f"M61 aborted (return code {self.return_value:.1f})")


def set_tool_number(self, **words):
    """REMAP=M61 modalgroup=6 python=set_tool_number: M61 in Python alone, doing what the
    built-in does."""
    block = self.blocks[self.remap_level]
    if not block.q_flag:
        return _fail(self, "M61 requires a Q parameter")
    tool = int(block.q_number)
    if block.q_number < -TOLERANCE_EQUAL:
        return _fail(self, f"M61 failed: Q={tool}")
    status, pocket = self.find_tool_pocket(tool)
    if status != INTERP_OK:
        return _fail(self, f"M61 failed: requested tool {tool} not in table")
    self.current_pocket = pocket
    self.current_tool = tool
    emccanon.CHANGE_TOOL_NUMBER(pocket)
    self.toolchange_flag = True
    self.set_tool_parameters()
    return INTERP_OK


def ignore_m6(self, **words):
    """REMAP=M6 python=ignore_m6: M6 does nothing."""
    return INTERP_OK


# ------------------------------------------------------------ G cycles
_UVW = ("u", "v", "w", "a", "b", "c")
_XYZ = ("x", "y", "z", "a", "b", "c")
# plane -> (axis words a cycle in that plane cannot take, the plane's name)
_PLANES = {
    emccanon.CANON_PLANE_XY: (_UVW, "XY"),
    emccanon.CANON_PLANE_YZ: (_UVW, "YZ"),
    emccanon.CANON_PLANE_XZ: (_UVW, "XZ"),
    emccanon.CANON_PLANE_UV: (_XYZ, "UV"),
    emccanon.CANON_PLANE_VW: (_XYZ, "VW"),
    emccanon.CANON_PLANE_UW: (_XYZ, "UW"),
}


def init_stdglue(self):
    """Call from TOPLEVEL's ``__init__(self)``: the cycles' sticky words."""
    self.sticky_params = {}


def cycle_prolog(self, **words):
    """A G code remapped as a canned cycle (REMAP-041..045): the words of the block merged
    into those of the cycle's previous blocks (a block with the G code starts afresh), all
    exported to the procedure as #<x>, #<y> ... #<l> (1 unless given), checked as a canned
    cycle's are."""
    block = self.blocks[self.remap_level]
    remap = block.executing_remap
    sticky = getattr(self, "sticky_params", None)
    if sticky is None:
        sticky = self.sticky_params = {}
    if block.g_modes[1] == remap.motion_code or remap.name not in sticky:
        sticky[remap.name] = {}  # the first block of the cycle
    words_now = sticky[remap.name]
    incompatible, plane = _PLANES[self.plane]
    for word in words:
        if word in incompatible:
            return _fail(
                self,
                f"{remap.name}: Cannot put a {word.upper()} in a canned cycle in the {plane} plane",
            )
    if "p" in words and words["p"] < 0.0:
        return _fail(self, f"{remap.name}: P word must be >= 0 if used ({words['p']:.4f})")
    words_now.update((word, value) for word, value in words.items() if word != "l")
    if "r" not in words_now:
        return _fail(self, f"{remap.name}: cycle requires R word")
    if words_now["r"] <= 0.0:
        return _fail(self, f"{remap.name}: R word must be > 0 if used ({words_now['r']:.4f})")
    if self.feed_rate == 0.0:
        return _fail(self, f"{remap.name}: feed rate must be > 0")
    if self.feed_mode == INVERSE_TIME:
        return _fail(self, f"{remap.name}: Cannot use inverse time feed with canned cycles")
    if self.cutter_comp_side:
        return _fail(self, f"{remap.name}: Cannot use canned cycles with cutter compensation on")
    self.params["motion_code"] = block.g_modes[1]
    for word, value in words_now.items():
        self.params[word] = value
    self.params["l"] = words.get("l", 1)
    return INTERP_OK


def cycle_epilog(self, **words):
    """A following block without a motion code runs the cycle again (REMAP-044)."""
    self.motion_mode = self.blocks[self.remap_level].executing_remap.motion_code
    return INTERP_OK
