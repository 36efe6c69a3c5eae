"""Remapping: ``[RS274NGC]REMAP=`` lines and the execution of remapped codes (REMAP-001..063).

A remapped code behaves like a call of an O-word procedure (``ngc=``) or of a Python
function (``python=``), with optional Python ``prolog=`` and ``epilog=`` handlers around an
NGC procedure. The binding is configuration: each ``REMAP=<code> <option>=<value> ...`` line
is checked at start-up and every problem reported as ``file:line: cause``.

How a block with remapped codes runs (LinuxCNC's model, so that output and timing match):

- Reading a line notes which of its steps (``STEP_*``, the order of execution) are
  remapped (``find_remappings``). A remapped code used inside its own procedure means the
  built-in code for T, S, F, M6, M61, M0, M1, M60 and M62..M68; any other self-reference is
  an error ("remapping recursion").
- Executing the block pushes it on the remap stack (``remap_level``, at most 9 deep) and runs
  its steps in order (``Interpreter.execute_block_steps``), each once, up to the first
  remapped one; that step reads ``O <procedure> call`` (with ``[..]`` arguments for an
  argspec with ``@``) as the block to execute next.
- The call sets up a call frame, the argspec's words as local parameters (or keyword
  arguments of the Python handlers), and runs the prolog, then the Python body or the NGC
  procedure. The NGC procedure's ``endsub``/``return`` runs the epilog, returns, and
  continues the block with its next remapped step or its remaining steps
  (``remap_finished``), then pops the remap stack.
- A Python handler that yields ``INTERP_EXECUTE_FINISH`` stops the interpreter there
  (``call_state``): the caller (task, rs274) synchronises and calls ``read()`` and
  ``execute()`` again; reading then keeps the block, and executing it resumes the handler
  after its ``yield``.
"""

from __future__ import annotations

import copy
import re
from collections.abc import Callable

from .block import (
    CT_NGC_OWORD_SUB,
    CT_PYTHON_OWORD_SUB,
    CT_REMAP,
    EMS,
    GEES,
    M_98,
    M_99,
    Block,
    O_call,
    O_endsub,
    O_return,
)
from .errors import (
    INTERP_ERROR,
    INTERP_EXECUTE_FINISH,
    INTERP_EXIT,
    INTERP_MIN_ERROR,
    INTERP_OK,
    InterpError,
)
from .params import PA_GLOBAL, PA_PYTHON, PA_READONLY

MAX_NESTED_REMAPS = 10  # remap stack slots; slot 0 is the block being executed

# the steps of a block in execution order (LinuxCNC's phases); a remapped step's number is
# also the phase of its remap
(
    STEP_COMMENT,
    STEP_SPINDLE_MODE,
    STEP_FEED_MODE,
    STEP_SET_FEED_RATE,
    STEP_SET_SPINDLE_SPEED,
    STEP_PREPARE,
    STEP_M_5,
    STEP_M_6,
    STEP_RETAIN_G43,
    STEP_M_7,
    STEP_M_8,
    STEP_M_9,
    STEP_M_10,
    STEP_DWELL,
    STEP_SET_PLANE,
    STEP_LENGTH_UNITS,
    STEP_LATHE_DIAMETER_MODE,
    STEP_CUTTER_COMP,
    STEP_TOOL_LENGTH_OFFSET,
    STEP_COORD_SYSTEM,
    STEP_CONTROL_MODE,
    STEP_DISTANCE_MODE,
    STEP_IJK_DISTANCE_MODE,
    STEP_RETRACT_MODE,
    STEP_MODAL_0,
    STEP_G92_IS_APPLIED,
    STEP_MOTION,
    STEP_MGROUP4,
) = range(1, 29)
STEP_M_GROUP = {5: STEP_M_5, 6: STEP_M_6, 7: STEP_M_7, 8: STEP_M_8, 9: STEP_M_9, 10: STEP_M_10}

# where a resumed Python handler continues (Interpreter.call_state)
CS_NORMAL, CS_REEXEC_PROLOG, CS_REEXEC_PYBODY, CS_REEXEC_EPILOG, CS_REEXEC_PYOSUB = range(5)

# [EMC]DEBUG bits (REMAP-056); the traces print with [RS274NGC]LOG_LEVEL >= 2
EMC_DEBUG_OWORD = 0x00002000
EMC_DEBUG_REMAP = 0x00004000
EMC_DEBUG_PYTHON = 0x00008000
EMC_DEBUG_NAMEDPARAM = 0x00010000
EMC_DEBUG_PYTHON_TASK = 0x00040000
EMC_DEBUG_UNCONDITIONAL = 0x40000000
EMC_DEBUG_USER1 = 0x10000000
EMC_DEBUG_USER2 = 0x20000000

# codes LinuxCNC runs through a remap (M_REMAPPABLE): unallocated M1..M99, M200..M999, and
# the built-in codes open to redefinition
_M_REDEFINABLE = frozenset((0, 1, 6, 9, 60, 61, 62, 63, 64, 65, 66, 67, 68))
# built-ins that mean themselves inside their own remap procedure (by group)
_BUILTIN_IN_OWN_PROCEDURE = {5: frozenset(range(62, 69)), 6: frozenset((6, 61))}
_STOP_CODES = ("M0", "M1", "M60")
# G codes REMAP-060 lists as allocated besides those this interpreter knows
_G_ALLOCATED = frozenset((600, *range(930, 1000, 10)))
_ARGSPEC = re.compile(r"[A-NP-Za-np-z>^@]*")  # LinuxCNC's word set: no O
_WORD_LETTERS = "abcdefhijklpqrstuvwxyz"
# REMAP option keywords in LinuxCNC's order of matching (a keyword may be abbreviated)
_KEYWORDS = ("modalgroup", "argspec", "prolog", "epilog", "ngc", "python")


class RemapError(Exception):
    """Bad REMAP= lines; ``str()`` lists every problem as ``file:line: cause``."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("\n".join(problems))
        self.problems = problems


class Remap:
    """One REMAP= line (LinuxCNC's ``remap`` struct, visible to Python as
    ``blocks[n].executing_remap``)."""

    __slots__ = (
        "argspec",
        "epilog_func",
        "file",
        "line",
        "modal_group",
        "motion_code",
        "name",
        "prolog_func",
        "remap_ngc",
        "remap_py",
    )

    def __init__(self, name: str, file: str, line: int) -> None:
        self.name = name
        self.file = file
        self.line = line
        self.argspec: str | None = None
        self.modal_group = -1
        self.motion_code = -2147483648  # INT_MIN: not a G code
        self.prolog_func: str | None = None
        self.remap_py: str | None = None
        self.remap_ngc: str | None = None
        self.epilog_func: str | None = None

    @property
    def function(self) -> str:
        """The procedure the remap calls (REMAP_FUNC)."""
        return self.remap_ngc or self.remap_py or ""

    @property
    def uses_python(self) -> bool:
        return bool(self.remap_py or self.prolog_func or self.epilog_func)

    def __str__(self) -> str:
        return (
            f"Remap({self.name} argspec={self.argspec} modal_group={self.modal_group} "
            f"prolog={self.prolog_func} ngc={self.remap_ngc} python={self.remap_py} "
            f"epilog={self.epilog_func}) "
        )


class RemapTable:
    """The remaps of a configuration, by code."""

    def __init__(self) -> None:
        self.by_name: dict[str, Remap] = {}  # upper-case code -> remap
        self.g: dict[int, Remap] = {}  # G code x 10 -> remap
        self.m: dict[int, Remap] = {}
        self.letter: dict[str, Remap] = {}  # "T", "S", "F"

    def get(self, code: str) -> Remap | None:
        return self.by_name.get(code.upper())


def is_m_remappable(code: int) -> bool:
    """Whether LinuxCNC runs M<code> through its remap (M_REMAPPABLE)."""
    return 199 < code < 1000 or (0 < code < 100 and code not in EMS) or code in _M_REDEFINABLE


def is_g_remappable(code: int) -> bool:
    """Whether G<code/10> is free for a remap (REMAP-059/060)."""
    return 0 < code < 1000 and code not in GEES and code not in _G_ALLOCATED


def parse_remaps(
    entries,
    *,
    find_ngc: Callable[[str], object],
    find_python: Callable[[str], object] | None,
) -> tuple[RemapTable, list[str]]:
    """The remaps of ``entries`` (cnc.ini IniValue's of [RS274NGC]REMAP) and warnings.

    ``find_ngc(name)`` finds an NGC procedure file, ``find_python(name)`` a callable of the
    ``remap`` module (None: there is no Python plug-in). Raises RemapError listing every
    problem.
    """
    table = RemapTable()
    problems: list[str] = []
    warnings: list[str] = []
    for entry in entries:
        text = entry.value.split("#", 1)[0]  # LinuxCNC drops a trailing comment
        where = f"{entry.file}:{entry.line}: REMAP={entry.value}"
        try:
            remap = _parse_remap(text, entry, find_ngc, find_python, warnings)
        except _LineError as problem:
            problems.append(f"{where}: {problem}")
            continue
        except _IgnoredLineError as reason:
            # LinuxCNC accepts these lines but never runs them: say so, and go on
            warnings.append(f"{where}: {reason}; this line is ignored")
            continue
        key = remap.name.upper()
        if key in table.by_name:
            first = table.by_name[key]
            problems.append(
                f"{where}: {remap.name} is already remapped at {first.file}:{first.line}"
            )
            continue
        table.by_name[key] = remap
        letter = key[0]
        if letter == "G":
            table.g[remap.motion_code] = remap
        elif letter == "M":
            table.m[int(key[1:])] = remap
        else:
            table.letter[letter] = remap
    if problems:
        raise RemapError(problems)
    return table, warnings


class _LineError(Exception):
    """A REMAP= line that cannot work."""


class _IgnoredLineError(Exception):
    """A REMAP= line of a code that cannot be remapped."""


def _parse_remap(text, entry, find_ngc, find_python, warnings) -> Remap:
    words = text.split()
    if not words or "=" in words[0]:
        raise _LineError("the code to remap is missing (REMAP=<code> <option>=<value> ...)")
    code = words[0]
    remap = Remap(code, entry.file, entry.line)
    kind = code[0].upper()
    number = code[1:]
    if kind in "TSF" and not number:
        pass
    elif kind in "GM":
        if not re.fullmatch(r"[0-9]+(\.[0-9])?" if kind == "G" else r"[0-9]+", number):
            raise _LineError(f"{code}: not a code (T, S, F, M<number> or G<number>[.<digit>])")
        if len(number) > 1 and number[0] == "0" and number[1] != ".":
            raise _LineError(f"{code}: write the code without leading zeros ({kind}{number[1:]})")
        value = round(float(number) * 10) if kind == "G" else int(number)
        if kind == "M" and 100 <= value <= 199:
            raise _IgnoredLineError(
                f"{code} cannot be remapped (M100..M199 are user-defined M codes)"
            )
        if kind == "M" and not is_m_remappable(value):
            raise _IgnoredLineError(f"{code} is a built-in M code that cannot be remapped")
        if kind == "G" and not is_g_remappable(value):
            raise _IgnoredLineError(f"{code} is an allocated G code that cannot be remapped")
        if kind == "G":
            remap.motion_code = value
    else:
        raise _LineError(f"{code}: cannot remap this code (T, S, F, M<number> or G<number>)")
    for word in words[1:]:
        keyword, equals, value = word.partition("=")
        option = next((k for k in _KEYWORDS if keyword and k.startswith(keyword.lower())), None)
        if option is None:
            raise _LineError(f"unknown option '{keyword}'")
        if not equals:
            raise _LineError(f"option '{keyword}' needs '=<value>'")
        if not value and option != "argspec":
            raise _LineError(f"option '{keyword}' has an empty value")
        if option == "modalgroup":
            try:
                remap.modal_group = int(value)
            except ValueError:
                raise _LineError(f"modalgroup={value}: not a number") from None
        elif option == "argspec":
            if not _ARGSPEC.fullmatch(value):
                bad = next(ch for ch in value if not _ARGSPEC.fullmatch(ch))
                raise _LineError(f"argspec={value}: '{bad}' is not a word letter, '@', '^' or '>'")
            remap.argspec = value
        elif option in ("prolog", "epilog", "python"):
            if find_python is None:
                raise _LineError(f"{option}= needs the Python plug-in ([PYTHON]TOPLEVEL)")
            if not find_python(value):
                raise _LineError(
                    f"{option}={value}: not a function of the remap module "
                    "(TOPLEVEL must import remap)"
                )
            if option == "prolog":
                remap.prolog_func = value
            elif option == "epilog":
                remap.epilog_func = value
            else:
                remap.remap_py = value
        else:
            if not find_ngc(value):
                raise _LineError(
                    f"ngc={value}: {value}.ngc not found in PROGRAM_PREFIX or SUBROUTINE_PATH"
                )
            remap.remap_ngc = value
    if remap.remap_ngc and remap.remap_py:
        raise _LineError("give either ngc= or python=, not both")
    if not remap.remap_ngc and not remap.remap_py:
        raise _LineError("no procedure: give ngc=<basename> or python=<function>")
    if kind in "TSF":
        if remap.modal_group != -1:
            warnings.append(
                f"{entry.file}:{entry.line}: REMAP={entry.value}: modalgroup is ignored for "
                f"{kind} (its place in a block is fixed)"
            )
            remap.modal_group = -1
    elif remap.modal_group == -1:
        remap.modal_group = 1 if kind == "G" else 10
        # LinuxCNC's warning, word for word
        warnings.append(
            f"warning: code '{code}' : no modalgroup=<int> given, using default group "
            f"{remap.modal_group} : {entry.line}:REMAP = {entry.value}"
        )
    elif kind == "G" and remap.modal_group != 1:
        raise _LineError(f"modalgroup={remap.modal_group}: G codes can only be remapped in group 1")
    elif kind == "M" and not 4 <= remap.modal_group <= 10:
        raise _LineError(
            f"modalgroup={remap.modal_group}: M codes can be remapped in groups 4 to 10"
        )
    return remap


class RemapMixin:
    """Remapped codes and Python calls; mixed into the Interpreter."""

    # --------------------------------------------------------------- reading
    def is_user_gcode(self, code: int) -> bool:
        return self.remaps is not None and code in self.remaps.g

    def has_user_code(self, block: Block) -> bool:
        """A remapped G or M code in the block: its words are the remap's (argspec)."""
        remaps = self.remaps
        if block.motion_to_be in remaps.g:
            return True
        return any(code != -1 and code in remaps.m for code in block.m_modes)

    def find_remappings(self, block: Block) -> None:
        """Note the block's remapped steps (``block.remappings``)."""
        remaps = self.remaps
        steps = set()
        cblock = self.remap_blocks[self.remap_level] if self.remap_level else block
        if remaps.letter:
            for flag, letter, step in (
                (block.f_flag, "F", STEP_SET_FEED_RATE),
                (block.s_flag, "S", STEP_SET_SPINDLE_SPEED),
                (block.t_flag, "T", STEP_PREPARE),
            ):
                remap = remaps.letter.get(letter) if flag else None
                if remap is not None:
                    if self.remap_in_progress(remap):
                        cblock.builtin_used = True  # the built-in inside its own procedure
                    else:
                        steps.add(step)
        m_modes = block.m_modes
        if block.m_count:
            for group in (5, 6, 7, 8, 9, 10):
                code = m_modes[group]
                remap = remaps.m.get(code) if code != -1 else None
                if remap is None:
                    continue
                if self.remap_in_progress(remap):
                    if code in _BUILTIN_IN_OWN_PROCEDURE.get(group, ()):
                        continue  # the built-in
                    self._recursion(remap)
                steps.add(STEP_M_GROUP[group])
            code = m_modes[4]
            remap = remaps.m.get(code) if code != -1 else None
            if remap is not None:
                if any(self.remap_in_progress(remaps.get(name)) for name in _STOP_CODES):
                    cblock.builtin_used = True
                else:
                    steps.add(STEP_MGROUP4)
        for motion in (block.g_modes[1], block.motion_to_be):
            remap = remaps.g.get(motion)
            if remap is not None:
                if self.remap_in_progress(remap):
                    self._recursion(remap)
                steps.add(STEP_MOTION)
        if steps:
            block.remappings = steps

    def remap_in_progress(self, remap: Remap | None) -> bool:
        if remap is None:
            return False
        blocks = self.remap_blocks
        return any(
            blocks[level].executing_remap is remap for level in range(1, self.remap_level + 1)
        )

    @staticmethod
    def _recursion(remap: Remap) -> None:
        raise InterpError(
            f"remapping recursion: {remap.name} is used in its own remap procedure "
            f"({remap.function})"
        )

    # ------------------------------------------------------------- execution
    def execute_remapped_block(self, block: Block, is_mdi: bool) -> int:
        """Execute a block with remapped steps: up to the first remap, then its call."""
        self.enter_remap(block)
        block.is_mdi_remap = is_mdi
        status = self.execute_block_steps(block)
        if status >= 0:
            return status  # (no remapped step ran: in inverse time a remapped F does not)
        if is_mdi:
            # MDI runs the remap procedure to its end now, as an MDI O-word call does
            status = self.convert_control_functions(self.block)
            if status != INTERP_OK:
                return status
            self.mdi_interrupt = False
            return self.run_mdi_call(is_finishing=False)
        return self.execute()  # the call read by convert_remapped_code

    def enter_remap(self, block: Block) -> None:
        level = self.remap_level + 1
        if level >= MAX_NESTED_REMAPS:
            self.remap_level = 0
            raise InterpError("maximum nesting of remapped blocks exceeded")
        self.remap_level = level
        block.breadcrumbs = set()
        block.executing_remap = None
        block.saved_line_number = self.sequence_number
        self.remap_blocks[level] = block
        self.sequence_number = 0

    def leave_remap(self) -> None:
        block = self.remap_blocks[self.remap_level]
        self.sequence_number = block.saved_line_number
        block.executing_remap = None
        self.remap_level -= 1

    def convert_remapped_code(self, block: Block, step: int, remap: Remap) -> int:
        """Start the remap of ``step``: read its call as the next block to execute.
        Returns ``-step``, which tells the callers a remap has started."""
        block.executing_remap = remap
        block.phase = step
        block.param_cnt = 0
        if self.traces & EMC_DEBUG_REMAP:
            self.trace(f"remap: {remap.name} (level {self.remap_level}) calls {remap.function}")
        command = f"O <{remap.function}> call "
        if remap.argspec and "@" in remap.argspec:
            command += self.add_parameters(block, remap, None, is_positional=True)
        self.read(command)
        self.block.call_type = CT_REMAP
        return -step

    def add_parameters(
        self, cblock: Block, remap: Remap, kwargs: dict | None, *, is_positional: bool
    ) -> str:
        """The argspec's words of the block (REMAP-012..018): local named parameters of the
        new call frame, keyword arguments of the Python handlers (``kwargs``), or (with
        ``@``) positional arguments, returned as ``[value]`` text."""
        argspec = remap.argspec or ""
        required: list[str] = []
        optional: list[str] = []
        for ch in argspec:
            if ch.isupper() and ch.lower() not in required:
                required.append(ch.lower())
            if ch.islower() and ch not in optional:
                optional.append(ch)
            if ch in ">^Nn" and ch not in required:
                required.append(ch)
        positional: list[str] = []

        def store(name: str, value: float) -> None:
            if kwargs is not None:
                kwargs[name] = value
            if is_positional:
                positional.append(f"[{value:.4f}]")
                cblock.param_cnt += 1
            else:
                self.add_named_param(name, 0)
                self.store_named_param(name, value)

        missing = []
        for ch in argspec:
            letter = ch.lower()
            if letter not in _WORD_LETTERS:
                continue
            if getattr(cblock, letter + "_flag"):
                if letter in required or letter in optional:
                    store(letter, _word_value(cblock, letter))
            elif letter in required:
                missing.append(letter.upper())
        tail = f" missing: {','.join(missing)}" if missing else ""
        if "n" in required or "N" in required:
            store("n", float(cblock.saved_line_number))
        if ">" in required:
            if self.feed_rate > 0.0:
                store("f", self.feed_rate)
            else:
                tail += "F>0,"
        if "^" in required:
            if self.speed[0] > 0.0:
                store("s", self.speed[0])
            else:
                tail += "S>0,"
        if tail:
            raise InterpError(f"user-defined {remap.name}:{tail}")
        return " ".join(positional)

    def remap_finished(self, step: int) -> int:
        """The remap of ``step`` has finished: start the block's next remap, or execute its
        remaining steps and pop the remap stack."""
        cblock = self.remap_blocks[self.remap_level]
        cblock.remappings.discard(step)
        if self.traces & EMC_DEBUG_REMAP:
            self.trace(f"remap: {cblock.executing_remap.name} finished")
        status = self.execute_block_steps(cblock)
        if status < 0:
            return self.execute()  # the block's next remap
        if status != INTERP_EXIT:  # (a program end leaves the stack to reset)
            self.leave_remap()
        return status

    # --------------------------------------------------------- call frames
    def call_type_of(self, name: str) -> int:
        """An ``O<name> call``: a Python O-word procedure shadows an NGC one (PY-007)."""
        python = self.python
        if python is not None and python.find("oword", name) is not None:
            return CT_PYTHON_OWORD_SUB
        return CT_NGC_OWORD_SUB

    def execute_remap_call(self, frame) -> int:
        """The call of a remap: arguments, prolog, then the Python body or the NGC
        procedure (whose return runs the epilog, see run_epilog)."""
        cblock = self.remap_blocks[self.remap_level]
        remap = cblock.executing_remap
        state = self.call_state
        if state == CS_NORMAL:
            # the caller's return point and #1..#30 first, so that an error in a handler
            # returns there; an NGC procedure's #1..#30 exist before its prolog runs, so
            # that what the prolog sets is the procedure's (PY-019, PY-020)
            previous = self.sub_context[self.call_level - 1]
            self.save_return_point(previous)
            self.enter_call_parameters(previous, self.block.params if remap.remap_ngc else None)
            frame.py_kwargs = {}
            if remap.argspec and "@" not in remap.argspec:
                kwargs = frame.py_kwargs if remap.uses_python else None
                self.add_parameters(cblock, remap, kwargs, is_positional=False)
        if remap.prolog_func and state in (CS_NORMAL, CS_REEXEC_PROLOG):
            status = self.run_handler(frame, remap, remap.prolog_func, CS_REEXEC_PROLOG)
            if status != INTERP_OK:
                return status
            state = CS_NORMAL
        if remap.remap_py and state in (CS_NORMAL, CS_REEXEC_PYBODY):
            status = self.run_handler(frame, remap, remap.remap_py, CS_REEXEC_PYBODY)
            if status != INTERP_OK:
                return status
            self.sequence_number = self.sub_context[self.call_level - 1].sequence_number
            self.leave_context()
            return self.remap_finished(cblock.phase)
        self.execute_call(frame, CT_NGC_OWORD_SUB, has_parameters=True)
        return INTERP_OK

    def run_epilog(self, frame) -> int:
        """At the ``endsub``/``return`` of a remap's NGC procedure: the epilog."""
        remap = self.remap_blocks[self.remap_level].executing_remap
        if remap is None or not remap.epilog_func:
            return INTERP_OK
        if self.call_state not in (CS_NORMAL, CS_REEXEC_EPILOG):
            return INTERP_OK
        status = self.run_handler(frame, remap, remap.epilog_func, CS_REEXEC_EPILOG)
        if status == INTERP_EXECUTE_FINISH:
            self.block.call_type = CT_REMAP  # (reading keeps this block: see resume_read)
        return status

    def execute_python_call(self, frame) -> int:
        """``O<name> call`` of a Python O-word procedure (PY-012)."""
        block = self.block
        previous = self.sub_context[self.call_level - 1]
        self.return_value = 0.0
        self.value_returned = 0
        self.save_return_point(previous)
        self.enter_call_parameters(previous, None)  # (kept for an error's unwinding)
        name = frame.subName
        function = self.python.find("oword", name)
        if function is None:
            raise InterpError(f"O<{name}>: the Python O-word procedure is gone")
        args = (block.params or ())[: block.param_cnt]
        if self.traces & EMC_DEBUG_PYTHON:
            self.trace(f"python: oword.{name}{tuple(args)}")
        result = self._call_python(f"O<{name}>", function, self.python_view, *args)
        if _is_generator(result):
            result.close()
            raise InterpError(
                f"O<{name}>: yield is not possible in a Python O-word procedure "
                "(only in remap handlers)"
            )
        if isinstance(result, str):
            raise InterpError(result)
        if isinstance(result, bool | int | float):
            self.return_value = float(result)
            self.value_returned = 1
        elif result is not None:
            raise InterpError(
                f"O<{name}>: returned {type(result).__name__} '{result}' - expected "
                "a number or an error message"
            )
        self.call_state = CS_NORMAL
        self.sequence_number = previous.sequence_number
        self.leave_context()
        return INTERP_OK

    # ------------------------------------------------------ Python handlers
    def run_handler(self, frame, remap: Remap, name: str, resume_state: int) -> int:
        """Call (or resume after its yield) the prolog, body or epilog ``name``.

        Returns INTERP_OK, or INTERP_EXECUTE_FINISH when the handler yielded it (it resumes
        at the next execute()); an error string, INTERP_ERROR or an exception raises
        InterpError naming the code and the handler (PY-013..016, PY-030).
        """
        label = f"{remap.name}/{name}"
        if self.call_state == resume_state:
            self.read_inputs()
            generator = frame.py_generator
            if self.traces & EMC_DEBUG_PYTHON:
                self.trace(f"python: {label} resumes")
            result = self._resume(label, generator)
        else:
            function = self.python.find("remap", name)
            if function is None:
                raise InterpError(f"{label}: the remap function is gone")
            self.saved_error = ""
            if self.traces & EMC_DEBUG_PYTHON:
                self.trace(f"python: {label}{tuple(frame.py_kwargs.items())}")
            result = self._call_python(label, function, self.python_view, **frame.py_kwargs)
            if _is_generator(result):
                frame.py_generator = result
                result = self._resume(label, result)
        if isinstance(result, _Yielded):
            status = result.value
            if status == INTERP_EXECUTE_FINISH:
                if self.nested_executes:
                    frame.py_generator = None
                    raise InterpError(
                        f"{label}: cannot yield INTERP_EXECUTE_FINISH inside self.execute() "
                        "(a nested interpretation cannot be resumed)"
                    )
                self.call_state = resume_state
                return INTERP_EXECUTE_FINISH
            frame.py_generator = None  # yield INTERP_OK (or an error) ends the handler
        else:
            status = result
        self.call_state = CS_NORMAL
        return self._handler_status(label, status)

    def _resume(self, label: str, generator):
        try:
            value = self.python.call(generator.__next__)
        except StopIteration as stop:
            if stop.value is not None:
                raise InterpError(
                    f"{label}: a handler that yields cannot return a value "
                    f"(returned {stop.value!r})"
                ) from None
            return None
        except Exception as error:
            raise self._user_error(label, error) from None
        return _Yielded(value)

    def _handler_status(self, label: str, result) -> int:
        if result is None:
            return INTERP_OK
        if isinstance(result, str):
            raise InterpError(result)
        if isinstance(result, bool | int):
            status = int(result)
            if status in (INTERP_OK, INTERP_EXIT):
                return status
            if status == INTERP_EXECUTE_FINISH:
                raise InterpError(
                    f"{label}: returned INTERP_EXECUTE_FINISH; a handler must yield it"
                )
            if status > INTERP_MIN_ERROR:
                raise InterpError(self.saved_error or f"{label} returned INTERP_ERROR")
            raise InterpError(f"{label}: returned the unexpected status {status}")
        if isinstance(result, float):
            raise InterpError(f"{label}: returned the number {result:f} - invalid")
        raise InterpError(
            f"{label}: returned '{result}' - expected generator, int, or float value, "
            f"got {type(result).__name__}"
        )

    def _call_python(self, label: str, function, *args, **kwargs):
        try:
            return self.python.call(function, *args, **kwargs)
        except Exception as error:
            raise self._user_error(label, error) from None

    def _user_error(self, label: str, error: Exception) -> InterpError:
        cause = getattr(error, "cause", None) or f"{type(error).__name__}: {error}"
        if isinstance(error, InterpError):
            return error
        return InterpError(f"{label}: {cause}")

    # ------------------------------------------------- Python calling NGC
    def python_execute(self, command: str, line_number: int | None = None) -> int:
        """``self.execute(command[, line_number])`` of a handler (PY-018, PY-021, PY-022)."""
        from .python import interpreter

        saved_block, saved_state = self.block, self.call_state
        level, remap_level = self.call_level, self.remap_level
        saved_deadline, self.slice_deadline = self.slice_deadline, None  # (runs whole)
        self.call_state = CS_NORMAL
        self.nested_executes += 1
        message = None
        try:
            if line_number:
                self.enter_remap(copy.copy(saved_block))
                self.sequence_number = line_number
            try:
                status = self._execute(command)
            finally:
                if line_number and self.remap_level > remap_level:
                    self.leave_remap()
            if status == INTERP_EXECUTE_FINISH and self.call_level > level:
                raise InterpError(
                    f"self.execute({command!r}): a queue buster inside a procedure called "
                    "from Python; call its codes one by one and yield INTERP_EXECUTE_FINISH"
                )
        except InterpError as error:
            message = error.message
            self.unwind_call(level)
            self.remap_level = remap_level
            status = INTERP_ERROR
        finally:
            self.nested_executes -= 1
            self.call_state = saved_state
            self.block = saved_block
            self.slice_deadline = saved_deadline
        if message is not None:
            if interpreter.throw_exceptions:
                line = line_number if line_number else saved_block.line_number
                raise interpreter.InterpreterException(message, line, self.linetext)
            self.saved_error = message
        return status

    def python_read(self, command: str) -> int:
        from .python import interpreter

        saved_block = self.block
        try:
            return self.read(command)
        except InterpError as error:
            if interpreter.throw_exceptions:
                raise interpreter.InterpreterException(
                    error.message, saved_block.line_number, self.linetext
                ) from None
            self.saved_error = error.message
            return INTERP_ERROR
        finally:
            self.block = saved_block

    # -------------------------------------------------- resuming handlers
    def resume_read(self) -> int | None:
        """``read()`` while a Python handler waits to resume: keep the block (its execute
        resumes the handler). None: no handler waits, read normally."""
        block = self.block
        if block.call_type in (CT_PYTHON_OWORD_SUB, CT_REMAP) and block.o_type in (
            O_call,
            M_98,
            O_return,
            O_endsub,
            M_99,
        ):
            self._fast = self._planned = None
            self.line_length = 0
            self.linetext = ""
            return INTERP_OK
        self.call_state = CS_NORMAL
        return None

    # ------------------------------------------------ named parameters
    def define_python_named_params(self) -> None:
        """The ``_name`` functions of the namedparams module become read-only globals
        (PY-026); redefining an existing one is allowed, with a warning."""
        python = self.python
        if python is None:
            return
        globals_ = self.sub_context[0].named_params
        for name in python.names("namedparams"):
            if not name.startswith("_"):
                continue
            key = name if self.feature_no_downcase_oword else name.lower()
            if key in globals_:
                self.report(f"warning: redefining named parameter {name}\n")
            globals_[key] = [0.0, PA_READONLY | PA_GLOBAL | PA_PYTHON]

    def python_named_param(self, name: str) -> float:
        function = self.python.find("namedparams", name) if self.python else None
        if function is None:
            raise InterpError(f"#<{name}>: its namedparams function is gone")
        if self.traces & EMC_DEBUG_NAMEDPARAM:
            self.trace(f"namedparams: {name}")
        result = self._call_python(f"#<{name}>", function, self.python_view)
        if isinstance(result, str):
            raise InterpError(result)
        if result is None:
            raise InterpError(f"Python namedparams.{name} returns no value")
        if isinstance(result, bool | int | float):
            return float(result)
        raise InterpError(
            f"Python call namedparams.{name} returned '{result}' - expected double, int or "
            f"string, got {type(result).__name__}"
        )

    # ------------------------------------------------------ the plug-in
    def configure_python(self, ini) -> None:
        """The [PYTHON] plug-in (PY-001..PY-005)."""
        from .python.plugin import PluginError, PythonPlugin
        from .python.view import InterpView

        self.python_view = InterpView(self)
        try:
            self.python = PythonPlugin.from_ini(
                ini,
                self.python_view,
                extra_modules=self.python_modules,
                log=lambda text: self.report(text + "\n"),
            )
        except PluginError as error:
            raise InterpError(str(error)) from None

    def require_python(self):
        """The plug-in; without [PYTHON]TOPLEVEL a bare one, for ``;py,`` statements."""
        if self.python is None:
            from .python.plugin import PythonPlugin
            from .python.view import InterpView

            self.python_view = InterpView(self)
            self.python = PythonPlugin(
                self.python_view,
                extra_modules=self.python_modules,
                log=lambda text: self.report(text + "\n"),
            )
        return self.python

    def start_python(self) -> None:
        """Once the interpreter is set up: the namedparams, then TOPLEVEL's ``__init__``
        (PY-010, PY-026)."""
        self.is_python_started = True
        self.define_python_named_params()
        function = self.python.find(None, "__init__")
        if function is not None:
            self._call_python("__init__", function, self.python_view)

    def release_python(self) -> None:
        """Close the plug-in without ``__delete__`` (a preview, a failed start)."""
        if self.python is not None:
            self.python.close()
            self.python = None
            self.is_python_started = False

    def stop_python(self) -> None:
        """At exit: TOPLEVEL's ``__delete__`` (after the parameters were saved), then the
        plug-in closes."""
        python = self.python
        if python is None:
            return
        function = python.find(None, "__delete__") if self.is_python_started else None
        try:
            if function is not None:
                self._call_python("__delete__", function, self.python_view)
        except InterpError as error:
            self.report(f"{error.message}\n")
        finally:
            python.close()
            self.python = None
            self.is_python_started = False

    # ------------------------------------------------------------- ;py,
    def run_python(self, statement: str) -> None:
        """``;py,<statement>`` and ``(py,<statement>)`` (PY-027)."""
        python = self.require_python()
        if self.traces & EMC_DEBUG_PYTHON:
            self.trace(f"python: {statement}")
        try:
            python.run(statement)
        except Exception as error:
            cause = getattr(error, "cause", None) or f"{type(error).__name__}: {error}"
            raise InterpError(f"py_execute({statement}): {cause}") from None

    # --------------------------------------------------------------- traces
    @property
    def traces(self) -> int:
        """The [EMC]DEBUG flags (REMAP-056) whose traces print: all of them at
        [RS274NGC]LOG_LEVEL >= 2, none below."""
        return self.debugmask if self.log_level > 1 else 0

    def trace(self, text: str) -> None:
        self.report(text + "\n")


class _Yielded:
    """What a handler's generator yielded."""

    __slots__ = ("value",)

    def __init__(self, value) -> None:
        self.value = value


def _is_generator(value) -> bool:
    return hasattr(value, "__next__") and hasattr(value, "send") and hasattr(value, "throw")


def _word_value(block: Block, letter: str) -> float:
    if letter == "d":
        return block.d_number_float
    return float(getattr(block, letter + "_number"))
