"""Compiled values: expressions and parameter references turned into closures.

Loops and subroutines read the same lines again and again. The second time a value such as
``[#<r> * COS[#1]]`` is read at the same place of the same line, it is compiled once into a
closure that evaluates it with the parameters of the moment; later reads just call it.

A closure does exactly what ``ReaderMixin.read_real_value`` does, in the same order, with the
same errors: operands are evaluated left to right and each operator as soon as its right
operand is complete, which is the order of LinuxCNC's operator-precedence reader. Only
syntax is decided at compile time; a value with a syntax error is never compiled (the
interpreting reader then reports it at the right moment).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from . import ldmath
from .errors import InterpError
from .reader import (
    _NUMBER_SPAN,
    _PLAIN_NUMBER,
    _PRECEDENCE,
    _VALID_NUMBER,
    RIGHT_BRACKET,
    RS274NGC_MAX_PARAMETERS,
    ReaderMixin,
    _execute_binary,
    _execute_unary,
    _read_operation_unary,
    _to_c_int,
)

Thunk = Callable[[], float]


class _SyntaxError(Exception):
    """The text cannot be compiled; the interpreting reader will handle it."""


def _checked(fn: Thunk) -> Thunk:
    """The NaN/infinity check read_real_value makes after every value."""

    def value() -> float:
        result = fn()
        if result != result:
            raise InterpError("Calculation resulted in 'not a number'")
        if result in (math.inf, -math.inf):
            raise InterpError("Calculation resulted in 'infinity'")
        return result

    return value


class Compiler:
    """Compiles the values of one interpreter's lines (closures call back into it)."""

    def __init__(self, interp) -> None:
        self.interp = interp

    def value(self, line: str, counter: int) -> tuple[Thunk, int] | None:
        try:
            return self._value(line, counter)
        except (_SyntaxError, InterpError, IndexError, ValueError):
            return None

    def expression(self, line: str, counter: int) -> tuple[Thunk, int] | None:
        """A bracketed expression as read_real_expression reads it (no NaN check)."""
        try:
            return self._expression(line, counter)
        except (_SyntaxError, InterpError, IndexError, ValueError):
            return None

    # ------------------------------------------------------------- grammar
    def _value(self, line: str, counter: int) -> tuple[Thunk, int]:
        match = _PLAIN_NUMBER.match(line, counter)
        if match is not None:
            number = float(match.group())
            return (lambda: number), match.end()
        if counter >= len(line):
            raise _SyntaxError
        c = line[counter]
        c1 = line[counter + 1] if counter + 1 < len(line) else ""
        if c == "[":
            fn, counter = self._expression(line, counter)
        elif c == "#":
            fn, counter = self._parameter(line, counter, False)
        elif c in "+-" and c1 and not c1.isdigit() and c1 != ".":
            inner, counter = self._value(line, counter + 1)
            fn = inner if c == "+" else (lambda: -inner())
        elif "a" <= c <= "z":
            fn, counter = self._unary(line, counter)
        else:
            span = _NUMBER_SPAN.match(line, counter)
            text = span.group()
            valid = _VALID_NUMBER.match(text)
            if valid is None or valid.end() != len(text):
                raise _SyntaxError
            number = float(text)
            return (lambda: number), span.end()
        return _checked(fn), counter

    def _expression(self, line: str, counter: int) -> tuple[Thunk, int]:
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

    def _parameter(self, line: str, counter: int, check_exists: bool) -> tuple[Thunk, int]:
        interp = self.interp
        counter += 1
        if counter < len(line) and line[counter] == "<":
            name, counter = ReaderMixin.read_name(line, counter)
            find = interp.find_named_param
            if check_exists:
                return (lambda: 1.0 if find(name)[0] else 0.0), counter

            def named() -> float:
                exists, value = find(name)
                if exists:
                    return value
                if interp.defining_sub:
                    return 0.0
                raise InterpError(f"Named parameter #<{name}> not defined")

            return named, counter
        index_fn, counter = self._value(line, counter)
        pars = interp.parameters
        if check_exists:

            def exists_numbered() -> float:
                index = _integer(index_fn())
                return float(1 <= index < RS274NGC_MAX_PARAMETERS)

            return exists_numbered, counter

        def numbered() -> float:
            index = _integer(index_fn())
            if index < 1 or index >= RS274NGC_MAX_PARAMETERS:
                raise InterpError("Parameter number out of range")
            if 5420 <= index <= 5428 and interp.cutter_comp_side:
                raise InterpError("Cannot read current position with cutter radius compensation on")
            return pars[index]

        return numbered, counter

    def _unary(self, line: str, counter: int) -> tuple[Thunk, int]:
        operation, counter = _read_operation_unary(line, counter)
        if counter >= len(line) or line[counter] != "[":
            raise _SyntaxError
        if operation == "exists":
            counter += 1
            if counter >= len(line) or line[counter] != "#":
                raise _SyntaxError
            fn, counter = self._parameter(line, counter, True)
            if counter >= len(line) or line[counter] != "]":
                raise _SyntaxError
            return fn, counter + 1
        arg, counter = self._expression(line, counter)
        if operation == "atan":
            if counter >= len(line) or line[counter] != "/":
                raise _SyntaxError
            counter += 1
            if counter >= len(line) or line[counter] != "[":
                raise _SyntaxError
            arg2, counter = self._expression(line, counter)
            return (lambda: ldmath.rad_to_deg(math.atan2(arg(), arg2()))), counter
        return (lambda: _execute_unary(arg(), operation)), counter


def _binary(left: Thunk, op: int, right: Thunk) -> Thunk:
    return lambda: _execute_binary(left(), op, right())


def _integer(value: float) -> int:
    """read_integer_value's rounding and its error."""
    ivalue = math.floor(value)
    if value - ivalue > 0.9999:
        ivalue = math.ceil(value)
    elif value - ivalue > 0.0001:
        raise InterpError("Non integer value for integer")
    return _to_c_int(ivalue)
