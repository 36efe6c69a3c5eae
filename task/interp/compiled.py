"""Compiled values and line plans: what lines read again and again are read with.

Loops and subroutines read the same lines again and again. The second time a value such as
``[#<r> * COS[#1]]`` is read at the same place of the same line, it is compiled once into a
Python function (from Python source generated for it) that evaluates it with the parameters
of the moment; later reads just call it.

A compiled value does exactly what ``ReaderMixin.read_real_value`` does, in the same order,
with the same errors: operands are evaluated left to right and each operator as soon as its right
operand is complete, which is the order of LinuxCNC's operator-precedence reader. Only
syntax is decided at compile time; a value with a syntax error is never compiled (the
interpreting reader then reports it at the right moment).

A whole line read a second time gets a *plan* (see ``plan_line``): O-word lines, lines of
parameter settings and ``G0``/``G1`` lines with computed axis values (and an F word) are then
read without lexing them again, with their values compiled. LinuxCNC re-reads every line; so
does the interpreter when a plan declines.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

from . import ldmath
from .block import CT_NGC_OWORD_SUB, O_call, O_sub, OWordBlock
from .errors import InterpError
from .params import PA_PYTHON, PA_USE_LOOKUP
from .reader import (
    _NO_ARGUMENTS,
    _NUMBER_SPAN,
    _O_KEYWORD,
    _O_TYPES,
    _OWN_NAMES,
    _PLAIN_NUMBER,
    _PRECEDENCE,
    _SUB_ENDS,
    _TESTS,
    _VALID_NUMBER,
    GE,
    GT,
    INTERP_SUB_PARAMS,
    LE,
    LT,
    MINUS,
    PLUS,
    READONLY_PARAMETERS,
    RIGHT_BRACKET,
    RS274NGC_MAX_PARAMETERS,
    TIMES,
    ReaderMixin,
    _execute_binary,
    _execute_unary,
    _read_operation_unary,
    _to_c_int,
)

Thunk = Callable[[], float]
_COMPUTED = PA_USE_LOOKUP | PA_PYTHON  # named parameters whose value is computed when read


class _SyntaxError(Exception):
    """The text cannot be compiled; the interpreting reader will handle it."""


def _not_finite(result: float) -> InterpError:
    """The error of read_real_value's check for a NaN or an infinity."""
    if result != result:
        return InterpError("Calculation resulted in 'not a number'")
    return InterpError("Calculation resulted in 'infinity'")


def _fail(result: float) -> float:
    raise _not_finite(result)


# Python source for the common binary operations (the same arithmetic as _execute_binary;
# the left operand is evaluated first, as the reader reads it); the others call it.
_BINARY_CODE = {
    PLUS: "({} + {})",
    MINUS: "({} - {})",
    TIMES: "({} * {})",
    LT: "(1.0 if {} < {} else 0.0)",
    GT: "(1.0 if {} > {} else 0.0)",
    LE: "(1.0 if {} <= {} else 0.0)",
    GE: "(1.0 if {} >= {} else 0.0)",
}
# unary operations that cannot fail, called directly (as _execute_unary does)
_DIRECT_UNARY = {"sin": "_sin", "cos": "_cos", "tan": "_tan"}


class Compiler:
    """Compiles the values of one interpreter's lines into Python functions.

    Each value becomes the source of one Python expression, in the reader's order of
    evaluation, compiled once into a function of no arguments. The NaN/infinity check
    read_real_value makes after every value is inline (``_checked``); parameters are read
    from the interpreter's table, named ones through small closures.
    """

    def __init__(self, interp) -> None:
        self.interp = interp
        self._namespace: dict = {
            "_fail": _fail,
            "_eb": _execute_binary,
            "_eu": _execute_unary,
            "_sin": ldmath.sin_deg,
            "_cos": ldmath.cos_deg,
            "_tan": ldmath.tan_deg,
            "_r2d": ldmath.rad_to_deg,
            "_atan2": math.atan2,
            "P": interp.parameters,
        }
        self._temporaries = 0
        # Python's compile is slow, so nothing is compiled twice: what value() and
        # expression() gave, by (line, counter, is_value) (a line's plan and the reader's
        # own cache ask for the same values); the functions by their source (values such as
        # ``#1`` or ``[2]`` come again and again, and temporaries are numbered per function);
        # the names of the named parameters' readers in the namespace
        self._done: dict[tuple[str, int, bool], tuple[Thunk, int] | None] = {}
        self._functions: dict[str, Thunk] = {}
        self._named: dict[str, str] = {}

    def value(self, line: str, counter: int) -> tuple[Thunk, int] | None:
        """A value as read_real_value reads it, compiled; None if it cannot be."""
        key = (line, counter, True)
        if key not in self._done:
            self._done[key] = self._compiled(self._value, line, counter)
        return self._done[key]

    def expression(self, line: str, counter: int) -> tuple[Thunk, int] | None:
        """A bracketed expression as read_real_expression reads it (no NaN check)."""
        key = (line, counter, False)
        if key not in self._done:
            self._done[key] = self._compiled(self._expression, line, counter)
        return self._done[key]

    def _compiled(self, grammar, line: str, counter: int) -> tuple[Thunk, int] | None:
        self._temporaries = 0  # (the temporaries are the compiled function's locals)
        try:
            code, counter = grammar(line, counter)
            return self._function(code), counter
        except (_SyntaxError, InterpError, IndexError, ValueError, SyntaxError, RecursionError):
            return None

    def _function(self, code: str) -> Thunk:
        function = self._functions.get(code)
        if function is None:
            function = self._functions[code] = eval("lambda: " + code, self._namespace)
        return function

    def _bind(self, obj) -> str:
        """A name in the compiled code's namespace for ``obj``."""
        name = f"_f{len(self._namespace)}"
        self._namespace[name] = obj
        return name

    def _checked(self, code: str) -> str:
        """``code`` with read_real_value's NaN/infinity check (x - x is 0.0 unless x is a
        NaN or an infinity)."""
        self._temporaries += 1
        t = f"_t{self._temporaries}"
        return f"({t} if not (({t} := {code}) - {t}) else _fail({t}))"

    # ------------------------------------------------------------- grammar
    def _value(self, line: str, counter: int) -> tuple[str, int]:
        match = _PLAIN_NUMBER.match(line, counter)
        if match is not None:  # read_real_value returns these unchecked
            return _number(float(match.group())), match.end()
        if counter >= len(line):
            raise _SyntaxError
        c = line[counter]
        c1 = line[counter + 1] if counter + 1 < len(line) else ""
        if c == "[":
            code, counter = self._expression(line, counter)
        elif c == "#":
            code, counter = self._parameter(line, counter, False)
        elif c in "+-" and c1 and not c1.isdigit() and c1 != ".":
            inner, counter = self._value(line, counter + 1)
            code = inner if c == "+" else f"(-{inner})"
        elif "a" <= c <= "z":
            code, counter = self._unary(line, counter)
        else:
            span = _NUMBER_SPAN.match(line, counter)
            text = span.group()
            valid = _VALID_NUMBER.match(text)
            if valid is None or valid.end() != len(text):
                raise _SyntaxError
            code, counter = _number(float(text)), span.end()
        return self._checked(code), counter

    def _expression(self, line: str, counter: int) -> tuple[str, int]:
        counter += 1
        values = []
        operators = []
        first, counter = self._value(line, counter)
        values.append(first)
        op, counter = ReaderMixin.read_operation(line, counter)
        operators.append(op)
        prec = _PRECEDENCE
        while operators[0] != RIGHT_BRACKET:
            value, counter = self._value(line, counter)
            op, counter = ReaderMixin.read_operation(line, counter)
            values.append(value)
            operators.append(op)
            top = len(values) - 1
            if prec[operators[top]] > prec[operators[top - 1]]:
                continue
            while prec[operators[top]] <= prec[operators[top - 1]]:
                values[top - 1] = _binary(values[top - 1], operators[top - 1], values[top])
                operators[top - 1] = operators[top]
                del values[top]
                del operators[top]
                top -= 1
                if top > 0 and prec[operators[top]] <= prec[operators[top - 1]]:
                    continue
                break
        return values[0], counter

    def _parameter(self, line: str, counter: int, check_exists: bool) -> tuple[str, int]:
        interp = self.interp
        counter += 1
        if counter < len(line) and line[counter] == "<":
            name, counter = ReaderMixin.read_name(line, counter)
            find = interp.find_named_param
            if check_exists:
                return f"{self._bind(lambda: 1.0 if find(name)[0] else 0.0)}()", counter

            reader = self._named.get(name)
            if reader is None:
                reader = self._named[name] = self._bind(self._named_reader(name))
            return f"{reader}()", counter
        index = _constant_index(line, counter)
        index_code, counter = self._value(line, counter)
        if index is not None and not check_exists and not 5420 <= index <= 5428:
            return f"P[{index}]", counter  # the number's checks are done: it is valid
        index_fn = self._function(index_code)
        pars = interp.parameters
        if check_exists:

            def exists_numbered() -> float:
                index = _integer(index_fn())
                return float(1 <= index < RS274NGC_MAX_PARAMETERS)

            return f"{self._bind(exists_numbered)}()", counter

        def numbered() -> float:
            index = _integer(index_fn())
            if index < 1 or index >= RS274NGC_MAX_PARAMETERS:
                raise InterpError("Parameter number out of range")
            if 5420 <= index <= 5428 and interp.cutter_comp_side:
                raise InterpError("Cannot read current position with cutter radius compensation on")
            return pars[index]

        return f"{self._bind(numbered)}()", counter

    def _named_reader(self, name: str) -> Thunk:
        """The value of ``#<name>``, as read_named_parameter reads it."""
        interp = self.interp
        find = interp.find_named_param
        contexts = interp.sub_context
        is_global = name.startswith("_")

        def named() -> float:
            # a plain stored parameter straight from its frame (find_named_param's common
            # case); predefined, INI and HAL ones through find_named_param
            level = 0 if is_global else interp.call_level
            entry = contexts[level].named_params.get(name)
            if entry is not None and not entry[1] & _COMPUTED:
                return entry[0]
            exists, value = find(name)
            if exists:
                return value
            if interp.defining_sub:
                return 0.0
            raise InterpError(f"Named parameter #<{name}> not defined")

        return named

    def _unary(self, line: str, counter: int) -> tuple[str, int]:
        operation, counter = _read_operation_unary(line, counter)
        if counter >= len(line) or line[counter] != "[":
            raise _SyntaxError
        if operation == "exists":
            counter += 1
            if counter >= len(line) or line[counter] != "#":
                raise _SyntaxError
            code, counter = self._parameter(line, counter, True)
            if counter >= len(line) or line[counter] != "]":
                raise _SyntaxError
            return code, counter + 1
        arg, counter = self._expression(line, counter)
        if operation == "atan":
            if counter >= len(line) or line[counter] != "/":
                raise _SyntaxError
            counter += 1
            if counter >= len(line) or line[counter] != "[":
                raise _SyntaxError
            arg2, counter = self._expression(line, counter)
            return f"_r2d(_atan2({arg}, {arg2}))", counter
        direct = _DIRECT_UNARY.get(operation)
        if direct is not None:
            return f"{direct}({arg})", counter
        return f"_eu({arg}, {operation!r})", counter


def _number(value: float) -> str:
    """A number as Python source (repr() gives the same double back)."""
    if value - value:  # an infinity (a number too long for a double)
        return "1e999" if value > 0 else "-1e999"
    return repr(value)


def _binary(left: str, op: int, right: str) -> str:
    code = _BINARY_CODE.get(op)
    if code is not None:
        return code.format(left, right)
    return f"_eb({left}, {op}, {right})"


def _constant_index(line: str, counter: int) -> int | None:
    """The parameter number of ``#n`` when ``n`` is a plain valid number, else None."""
    match = _PLAIN_NUMBER.match(line, counter)
    if match is None:
        return None
    try:
        index = _integer(float(match.group()))
    except InterpError:
        return None
    if 1 <= index < RS274NGC_MAX_PARAMETERS:
        return index
    return None


def _integer(value: float) -> int:
    """read_integer_value's rounding and its error."""
    ivalue = math.floor(value)
    if value - ivalue > 0.9999:
        ivalue = math.ceil(value)
    elif value - ivalue > 0.0001:
        raise InterpError("Non integer value for integer")
    return _to_c_int(ivalue)


# ===================================================================== line plans
# A line read a second time (a loop body, a subroutine) is planned: what reading it takes
# is worked out once, from its text, and replayed on later reads. Only lines whose reading
# can be replayed exactly get a plan; a plan's read() declines (returns False) whenever the
# state makes the general reader do anything else, and the line then takes the general path.

_MOTION_HEAD = re.compile(r"(?:n\d+)?(?:g0*([01])(?![0-9.]))?(?=[xyzabc])")
_PARAMETER_INDEX = re.compile(r"[0-9]+(?![0-9.])")
_O_NUMBER = re.compile(r"o([0-9]+)(?![0-9.])")
_AXES = "xyzabc"


class LinePlan:
    """The reading of one line of a file: its text, its downcased block text.

    ``read(interp)`` either reads the line as the general reader would and returns True
    (or raises its error), or declines (returns False) with the read position as it was,
    for the general reader to read the line.
    """

    __slots__ = ("line", "text")

    def __init__(self, text: str, line: str) -> None:
        self.text = text
        self.line = line

    def read(self, interp) -> bool:
        raise NotImplementedError


class MotionPlan(LinePlan):
    """``[N..] [G0|G1] X.. Y.. [F..]`` with expressions: the fast path of plain motion lines
    (``Interpreter._fast_read``) for values computed at each read."""

    __slots__ = ("feed", "g", "values")

    def __init__(
        self, text: str, line: str, g: str | None, values: list, feed: Thunk | None
    ) -> None:
        super().__init__(text, line)
        self.g = g
        self.values = values  # (axis index, thunk) in the order of the line
        self.feed = feed  # the F word's value, last on the line, if it has one

    def read(self, interp) -> bool:
        if interp._no_fast or interp.defining_sub or interp.skipping_o:
            return False  # (skipped lines are not evaluated)
        offset = interp.begin_planned_line(self)
        # the values first, as the general reader reads them (their errors come first)
        words = [None] * 6
        for k, thunk in self.values:
            words[k] = thunk()
        feed = None if self.feed is None else self.feed()
        # (a negative F is an error of the general reader's)
        if (feed is None or feed >= 0.0) and interp._fast_read(self.g, words, feed):
            return True
        # the state wants the general path: it reads the line again (values have no
        # side effects) from where this read started
        interp.file_pos = offset
        interp.sequence_number -= 1
        return False


class ParameterPlan(LinePlan):
    """A line of nothing but parameter settings: ``#1 = [..]``, ``#<name> = [..]``."""

    __slots__ = ("settings",)

    def __init__(self, text: str, line: str, settings: list) -> None:
        super().__init__(text, line)
        self.settings = settings  # (name or None, index, thunk) in the order of the line

    def read(self, interp) -> bool:
        if interp._no_fast or interp.skipping_o or interp.defining_sub or interp.mdi_interrupt:
            return False
        interp.begin_planned_line(self)
        numbered = interp.parameter_assignments
        named = interp.named_parameter_assignments
        for name, index, thunk in self.settings:
            if name is None:
                numbered.append((index, thunk()))
            else:
                interp.add_named_param(name)
                named.append((name, thunk()))
        interp._planned = (interp._fast_assign, None)
        return True


class OWordPlan(LinePlan):
    """An O-word line: the O-word and its keyword are read once; the rest, which depends
    on the state, is read by ``read_o_body`` each time.

    When the rest is nothing but the line's bracketed expressions (``thunks``, compiled),
    the common state (no definition or skipping under way) takes a shorter path doing what
    ``read_o_body`` does in that state: name the block, evaluate the expressions, store them.
    """

    __slots__ = ("execute", "is_number", "name", "names", "o_type", "position", "thunks")

    def __init__(
        self,
        text: str,
        line: str,
        name: str,
        o_type: int,
        position: int,
        is_number: bool,
        thunks: tuple[Thunk, ...] | None,
        execute: Callable,
    ) -> None:
        super().__init__(text, line)
        self.name = name
        self.o_type = o_type
        self.position = position
        self.is_number = is_number
        self.thunks = thunks  # None: the line is always read by read_o_body
        self.execute = execute  # what executing the line does when no skipping is under way
        # sub name -> the name read_o_body gives the block (None: the O-word's own name)
        self.names: dict[str, str] | None = None if o_type in _OWN_NAMES else {}

    def read(self, interp) -> bool:
        if (
            self.thunks is None
            or interp.defining_sub
            or interp.skipping_o
            or interp.skipping_to_sub
            or interp.mdi_interrupt
        ):
            return self._read_generally(interp)
        offset = interp.begin_planned_line(self)
        block = OWordBlock()
        block.offset = offset
        interp.block = block
        slots = interp._o_slots
        if self.is_number:
            slots[0] = 0.0  # as reading the number does (see read_o)
        otype = block.o_type = self.o_type
        names = self.names
        if names is None:
            block.o_name = self.name
        else:
            level = interp.call_level
            sub_name = (interp.sub_context[level].subName or "") if level else ""
            o_name = names.get(sub_name)
            if o_name is None:
                o_name = names[sub_name] = f"{sub_name}#{self.name}"
            block.o_name = o_name
        values = []
        for thunk in self.thunks:  # (each leaves its value in the shared slot)
            value = slots[0] = thunk()
            values.append(value)
        if otype == O_call:
            block.call_type = (
                CT_NGC_OWORD_SUB if interp.python is None else interp.call_type_of(block.o_name)
            )
            block.param_cnt = len(values)
            block.params = values + [0.0] * (INTERP_SUB_PARAMS - len(values))
        elif otype in _TESTS:
            interp.test_value = values[0]
        elif otype in _SUB_ENDS:
            if values:
                interp.return_value = values[0]
                interp.value_returned = 1
            else:
                interp.return_value = 0.0
                interp.value_returned = 0
        interp._planned = (self.execute, block)  # (no skipping: see convert_control_functions)
        return True

    def _read_generally(self, interp) -> bool:
        offset = interp.begin_planned_line(self)
        block = OWordBlock()
        block.offset = offset
        interp.block = block
        if self.is_number:
            interp._o_slots[0] = 0.0  # as reading the number does (see read_o)
        block.o_type = self.o_type
        line = self.line
        counter = interp.read_o_body(line, self.position, block, self.name)
        if not interp.skipping_o:
            length = len(line)
            while counter < length:  # read_items' check of what follows an O-word
                ch = line[counter]
                if ch == ";":
                    counter = length
                elif ch == "(":
                    counter = interp.read_comment(line, counter, block)
                else:
                    raise InterpError("Unexpected character after O-word")
        if not interp.mdi_interrupt:  # (an MDI interruption needs _execute's handling)
            interp._planned = (interp.convert_control_functions, block)
        return True


def plan_line(compiler: Compiler, text: str, line: str) -> LinePlan | None:
    """The plan for a line (``text`` as read, ``line`` downcased), or None."""
    if not line or line[0] == "/":
        return None
    try:
        if line[0] == "o":
            return _plan_oword(compiler, text, line)
        if line[0] == "#":
            return _plan_parameters(compiler, text, line)
        return _plan_motion(compiler, text, line)
    except (_SyntaxError, InterpError, IndexError, ValueError):
        return None


def _plan_oword(compiler: Compiler, text: str, line: str) -> OWordPlan | None:
    if line.startswith("o<"):
        name, counter = ReaderMixin.read_name(line, 1)
        is_number = False
    else:
        match = _O_NUMBER.match(line)
        if match is None or len(match.group(1)) > 9:
            return None
        name, counter = str(int(match.group(1))), match.end()
        is_number = True
    keyword = _O_KEYWORD.match(line, counter)
    if keyword is None:
        return None  # O_ and O_none lines depend on the INI or are errors
    o_type = _O_TYPES[keyword.group()]
    position = keyword.end()
    thunks = _o_expressions(compiler, line, position, o_type)
    execute = compiler.interp.control_function(o_type)
    return OWordPlan(text, line, name, o_type, position, is_number, thunks, execute)


def _o_expressions(
    compiler: Compiler, line: str, counter: int, o_type: int
) -> tuple[Thunk, ...] | None:
    """The compiled expressions ending an O-word line of a type OWordPlan.read can read,
    when nothing else follows them (no comment) and there are as many as read_o_body reads
    without an error; else None."""
    thunks = []
    while counter < len(line) and line[counter] == "[":
        compiled = compiler.expression(line, counter)
        if compiled is None:
            return None
        thunk, counter = compiled
        thunks.append(thunk)
    if counter != len(line):
        return None
    if o_type == O_call:
        is_readable = len(thunks) <= INTERP_SUB_PARAMS
    elif o_type in _TESTS:
        is_readable = len(thunks) == 1
    elif o_type in _SUB_ENDS:
        is_readable = len(thunks) <= 1
    elif o_type == O_sub or o_type in _NO_ARGUMENTS:
        is_readable = not thunks
    else:
        is_readable = False
    return tuple(thunks) if is_readable else None


def _plan_parameters(compiler: Compiler, text: str, line: str) -> ParameterPlan | None:
    settings = []
    counter = 0
    while counter < len(line):
        if line[counter] != "#":
            return None
        counter += 1
        if line[counter] == "<":
            name, counter = ReaderMixin.read_name(line, counter)
            index = 0
        else:
            match = _PARAMETER_INDEX.match(line, counter)
            if match is None or len(match.group()) > 9:
                return None
            name, index, counter = None, int(match.group()), match.end()
            if index < 1 or index >= RS274NGC_MAX_PARAMETERS or index in READONLY_PARAMETERS:
                return None
        if line[counter] != "=":
            return None
        compiled = compiler.value(line, counter + 1)
        if compiled is None:
            return None
        thunk, counter = compiled
        settings.append((name, index, thunk))
    return ParameterPlan(text, line, settings)


def _plan_motion(compiler: Compiler, text: str, line: str) -> MotionPlan | None:
    head = _MOTION_HEAD.match(line)
    if head is None:
        return None
    readers = compiler.interp._readers
    values = []
    seen = set()
    counter = head.end()
    while counter < len(line):
        letter = line[counter]
        if letter == "f" and values:
            compiled = compiler.value(line, counter + 1)
            if compiled is None or compiled[1] != len(line):
                return None  # (F, when there is one, comes last)
            return MotionPlan(text, line, head.group(1), values, compiled[0])
        if letter not in _AXES or letter in seen or letter not in readers:
            return None
        seen.add(letter)
        compiled = compiler.value(line, counter + 1)
        if compiled is None:
            return None
        thunk, counter = compiled
        values.append((_AXES.index(letter), thunk))
    return MotionPlan(text, line, head.group(1), values, None)
