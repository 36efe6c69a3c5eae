"""Reading a line into a Block: lexing, words, expressions and parameters (INTERP-003).

The reader follows LinuxCNC's ``interp_read.cc`` character by character, because the exact
error for every malformed line is part of the interface. The line has already been through
``close_and_downcase``: no blanks, lower case outside comments.
"""

from __future__ import annotations

import math
import re

from nml.axes import AXIS_LETTERS

from . import ldmath
from .block import (
    CT_NGC_M98_SUB,
    EMS,
    G_80,
    GEES,
    M_98,
    M_99,
    O_,
    Block,
    O_break,
    O_call,
    O_continue,
    O_do,
    O_else,
    O_elseif,
    O_endif,
    O_endrepeat,
    O_endsub,
    O_endwhile,
    O_if,
    O_none,
    O_repeat,
    O_return,
    O_sub,
    O_while,
)
from .errors import InterpError

RS274NGC_MAX_PARAMETERS = 5602
INTERP_SUB_PARAMS = 30
LINELEN = 255
TOLERANCE_EQUAL = 0.0001
READONLY_PARAMETERS = frozenset([*range(5021, 5030), *range(5400, 5414), *range(5420, 5429)])

# binary operations, LinuxCNC's numbering
(
    NO_OPERATION,
    DIVIDED_BY,
    MODULO,
    POWER,
    TIMES,
    AND2,
    EXCLUSIVE_OR,
    MINUS,
    NON_EXCLUSIVE_OR,
    PLUS,
    RIGHT_BRACKET,
    LT,
    EQ,
    NE,
    LE,
    GE,
    GT,
) = range(17)
_PRECEDENCE = {
    RIGHT_BRACKET: 1,
    AND2: 2,
    EXCLUSIVE_OR: 2,
    NON_EXCLUSIVE_OR: 2,
    LT: 3,
    EQ: 3,
    NE: 3,
    LE: 3,
    GE: 3,
    GT: 3,
    MINUS: 4,
    PLUS: 4,
    NO_OPERATION: 5,
    DIVIDED_BY: 5,
    MODULO: 5,
    TIMES: 5,
    POWER: 6,
}

_DOWNCASE = str.maketrans(
    {chr(c): chr(c + 32) for c in range(65, 91)} | {" ": None, "\t": None, "\r": None}
)
_NUMBER_SPAN = re.compile(r"[+-]*[0-9.]*")
_VALID_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)")
_PLAIN_NUMBER = re.compile(r"-?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?![0-9.])")


def downcase(text: str) -> str:
    """A line without comments as close_and_downcase makes it: ASCII letters lower-cased
    (C's tolower), blanks removed. (The translation table is the general way; for the
    common ASCII line, lower() and replace() are twice as fast.)"""
    if text.isascii():
        line = text.lower().replace(" ", "")
        if "\t" not in line and "\r" not in line:
            return line
    return text.translate(_DOWNCASE)


def close_and_downcase(line: str) -> str:
    """Remove blanks, lower-case outside comments; LinuxCNC's comment errors."""
    if "(" not in line and ";" not in line:
        if "\n" in line:
            _check_newline(line)
        return downcase(line)
    out = []
    comment = semicomment = False
    n = len(line)
    for m in range(n):
        item = line[m]
        if item == ";" and not comment:
            semicomment = True
        if semicomment:
            out.append(item)
            continue
        if comment:
            out.append(item)
            if item == ")":
                comment = False
            elif item == "(":
                raise InterpError("Nested comment found")
        elif item in " \t\r":
            pass
        elif item == "\n":
            if m + 1 < n:
                raise InterpError("Null missing after newline")
        elif "A" <= item <= "Z":
            out.append(chr(ord(item) + 32))
        elif item == "(":
            comment = True
            out.append(item)
        else:
            out.append(item)
    if comment:
        raise InterpError("Unclosed comment found")
    return "".join(out)


def _check_newline(line: str) -> None:
    index = line.index("\n")
    if index + 1 < len(line):
        raise InterpError("Null missing after newline")


def _c_octal(ch: str) -> str:
    return "\\%03o" % (ord(ch) & 0xFF)


class ReaderMixin:
    """Parsing of one line into ``self.block``; mixed into the Interpreter."""

    # ------------------------------------------------------------------ items
    def read_items(self, block: Block, line: str) -> None:
        length = len(line)
        counter = 0
        if line.startswith("/"):
            counter = 1
        if counter < length and line[counter] == "n":
            counter = self.read_n_number(line, counter, block)
        m_number = -1
        if counter < length and line[counter] == "m":
            self._o_slots[0] = 0.0  # this number read overwrites LinuxCNC's stale slot
            try:
                m_number, _ = self.read_integer_value(line, counter + 1)
            except InterpError:
                m_number = -1
        if (
            (counter < length and line[counter] == "o")
            or m_number == 98
            or (m_number == 99 and self.call_level > 0)
        ):
            counter = self.read_o(line, counter, block)
            if self.skipping_o:
                return
            while counter < length:
                ch = line[counter]
                if ch == ";":
                    counter = length
                elif ch == "(":
                    counter = self.read_comment(line, counter, block)
                else:
                    raise InterpError("Unexpected character after O-word")
            return
        if self.skipping_o:
            return
        readers = self._readers
        while counter < length:
            letter = line[counter]
            reader = readers.get(letter)
            if reader is None:
                if letter < " " or letter > "z":
                    raise InterpError(f"Bad character '{_c_octal(letter)}' used")
                if not letter.isprintable() or letter.isspace():
                    raise InterpError(f"Bad character '{_c_octal(letter)}' used")
                raise InterpError(f"Bad character '{letter}' used")
            counter = reader(line, counter, block)

    def read_n_number(self, line: str, counter: int, block: Block) -> int:
        counter += 1
        value, counter = self.read_integer_unsigned(line, counter)
        block.n_number = value
        if counter < len(line) and line[counter] == ".":
            _, counter = self.read_integer_unsigned(line, counter + 1)
        return counter

    @staticmethod
    def read_integer_unsigned(line: str, counter: int) -> tuple[int, int]:
        n = counter
        length = len(line)
        while n < length and "0" <= line[n] <= "9":
            n += 1
        if n == counter:
            raise InterpError("Bad format unsigned integer")
        value = int(line[counter:n])
        if value > 2147483647:
            value = 2147483647  # sscanf("%d") saturates on glibc
        return value, n

    def read_integer_value(self, line: str, counter: int) -> tuple[int, int]:
        value, counter = self.read_real_value(line, counter)
        if value is STALE:
            value = 0.0  # an uninitialised local in LinuxCNC
        ivalue = math.floor(value)
        if value - ivalue > 0.9999:
            ivalue = math.ceil(value)
        elif value - ivalue > 0.0001:
            raise InterpError("Non integer value for integer")
        return _to_c_int(ivalue), counter

    # ------------------------------------------------------------ word readers
    def _make_readers(self, axis_mask: int) -> dict:
        readers = {
            "#": self.read_parameter_setting,
            "$": self.read_dollar,
            "(": self.read_comment,
            ";": self.read_semicolon,
            "@": self.read_atsign,
            "^": self.read_carat,
            "d": self.read_d,
            "e": self.read_e,
            "f": self.read_f,
            "g": self.read_g,
            "h": self.read_h,
            "l": self.read_l,
            "m": self.read_m,
            "p": self.read_p,
            "q": self.read_q,
            "s": self.read_s,
            "t": self.read_t,
        }
        for letter, message in (
            ("i", "Multiple i words on one line"),
            ("j", "Multiple j words on one line"),
            ("k", "Multiple k words on one line"),
            ("r", "Multiple r words on one line"),
        ):
            readers[letter] = self._word_reader(letter, message)
        for bit, letter in enumerate(AXIS_LETTERS.lower()):
            if axis_mask & (1 << bit):
                if letter in "uvw":
                    message = f"Multiple {letter.upper()} words on one line"
                else:
                    message = f"Multiple {letter} words on one line"
                readers[letter] = self._word_reader(letter, message)
        return readers

    def _word_reader(self, letter: str, message: str):
        flag = letter + "_flag"
        number = letter + "_number"
        read_real_value = self.read_real_value
        is_x = letter == "x"

        def reader(line: str, counter: int, block: Block) -> int:
            if getattr(block, flag):
                raise InterpError(message)
            value, counter = read_real_value(line, counter + 1)
            setattr(block, flag, True)
            if is_x and self.lathe_diameter_mode:
                value = value / 2
            setattr(block, number, value)
            return counter

        return reader

    def read_comment(self, line: str, counter: int, block: Block) -> int:
        end = line.find(")", counter + 1)
        if end < 0:  # cannot happen after close_and_downcase
            end = len(line)
        block.comment = line[counter + 1 : end]
        return end + 1

    def read_semicolon(self, line: str, counter: int, block: Block) -> int:
        if self.linetext.startswith(";py,"):  # Python, run as the line is read (PY-027)
            self.run_python(self.linetext[4:])
        return len(line)

    def read_d(self, line: str, counter: int, block: Block) -> int:
        if block.d_flag:
            raise InterpError("Multiple d words on one line")
        value, counter = self.read_real_value(line, counter + 1)
        block.d_number_float = value
        block.d_flag = True
        return counter

    def read_dollar(self, line: str, counter: int, block: Block) -> int:
        if block.dollar_flag:
            raise InterpError("Multiple spindle choice ($) words on one line")
        value, counter = self.read_real_value(line, counter + 1)
        block.dollar_number = value
        block.dollar_flag = True
        return counter

    def read_e(self, line: str, counter: int, block: Block) -> int:
        if block.e_flag:
            raise InterpError("Multiple e words on one line")
        value, counter = self.read_real_value(line, counter + 1)
        block.e_flag = True
        block.e_number = value
        return counter

    def read_f(self, line: str, counter: int, block: Block) -> int:
        if block.f_flag:
            raise InterpError("Multiple f words on one line")
        value, counter = self.read_real_value(line, counter + 1)
        if value < 0.0:
            raise InterpError("Negative f word used")
        block.f_number = value
        block.f_flag = True
        return counter

    def read_g(self, line: str, counter: int, block: Block) -> int:
        value_read, counter = self.read_real_value(line, counter + 1)
        value_read = 10.0 * value_read
        value = math.floor(value_read)
        if value_read - value > 0.999:
            value = math.ceil(value_read)
        elif value_read - value > 0.001:
            raise InterpError("G-code out of range")
        if value > 999:
            raise InterpError("G-code out of range")
        if value < 0:
            raise InterpError("Negative g code used")
        g_modes = block.g_modes
        remap = self.g_remapped.get(value)  # (empty without REMAP= lines)
        if remap is not None:
            if g_modes[remap.modal_group] != -1:
                raise InterpError("Two g codes used from same modal group")
            g_modes[remap.modal_group] = value
            return counter
        mode = GEES.get(value, -1)
        if mode == -1:
            raise InterpError("Unknown g code used")
        if value == G_80 and g_modes[mode] != -1:
            return counter
        if g_modes[mode] != G_80 and g_modes[mode] != -1:
            raise InterpError("Two g codes used from same modal group")
        g_modes[mode] = value
        return counter

    def read_h(self, line: str, counter: int, block: Block) -> int:
        if block.h_flag:
            raise InterpError("Multiple h words on one line")
        value, counter = self.read_integer_value(line, counter + 1)
        if value < -1:
            raise InterpError("Negative h word used")
        block.h_flag = True
        block.h_number = value
        return counter

    def read_l(self, line: str, counter: int, block: Block) -> int:
        if block.l_number > -1:
            raise InterpError("Multiple l words on one line")
        value, counter = self.read_integer_value(line, counter + 1)
        if value < 0:
            raise InterpError("Negative l word used")
        block.l_number = value
        block.l_flag = True
        return counter

    def read_m(self, line: str, counter: int, block: Block) -> int:
        value, counter = self.read_integer_value(line, counter + 1)
        if value < 0:
            raise InterpError("Negative m code used")
        remap = self.m_remapped.get(value)  # (empty without REMAP= lines)
        if remap is not None:
            if block.m_modes[remap.modal_group] != -1:
                raise InterpError("Two m codes used from same modal group")
            block.m_modes[remap.modal_group] = value
            block.m_count += 1
            return counter
        if value > 199:
            raise InterpError(f"M-code greater than 199: M{value}")
        mode = EMS.get(value, -1)
        if mode == -1:
            raise InterpError(f"Unknown m code used: M{value}")
        if block.m_modes[mode] != -1:
            raise InterpError("Two m codes used from same modal group")
        block.m_modes[mode] = value
        block.m_count += 1
        if 100 <= value < 200:
            block.user_m = 1
        return counter

    def read_p(self, line: str, counter: int, block: Block) -> int:
        if block.p_number > -1.0:
            raise InterpError("Multiple p words on one line")
        value, counter = self.read_real_value(line, counter + 1)
        block.p_number = value
        block.p_flag = True
        return counter

    def read_q(self, line: str, counter: int, block: Block) -> int:
        if block.q_number > -1.0:
            raise InterpError("Multiple q words on one line")
        value, counter = self.read_real_value(line, counter + 1)
        block.q_number = value
        block.q_flag = True
        return counter

    def read_s(self, line: str, counter: int, block: Block) -> int:
        if block.s_flag:
            raise InterpError("Multiple s words on one line")
        value, counter = self.read_real_value(line, counter + 1)
        if value < 0.0:
            raise InterpError("Negative spindle speed used")
        block.s_number = value
        block.s_flag = True
        return counter

    def read_t(self, line: str, counter: int, block: Block) -> int:
        if block.t_flag:
            raise InterpError("Multiple t words on one line")
        value, counter = self.read_integer_value(line, counter + 1)
        if value < 0:
            raise InterpError("Negative tool id (tool not found)")
        block.t_number = value
        block.t_flag = True
        return counter

    def read_atsign(self, line: str, counter: int, block: Block) -> int:
        block.radius, counter = self.read_real_value(line, counter + 1)
        block.radius_flag = True
        return counter

    def read_carat(self, line: str, counter: int, block: Block) -> int:
        block.theta, counter = self.read_real_value(line, counter + 1)
        block.theta_flag = True
        return counter

    # -------------------------------------------------------------- o-words
    def read_o(self, line: str, counter: int, block: Block) -> int:
        length = len(line)
        is_m = False
        if line[counter] == "m":
            try:
                onumber, _ = self.read_integer_value(line, counter + 1)
                is_m = True
            except InterpError:
                is_m = False
        if is_m:
            if onumber == 98:
                if self.disable_fanuc_style_sub:
                    raise InterpError("DISABLE_FANUC_STYLE_SUB set in INI file, but found m98")
                block.o_type = M_98
                counter += 3
                while counter < length:
                    counter = self._read_one_item(line, counter, block)
                if not block.p_flag:
                    raise InterpError("Found 'm98' code with no P-word")
                n = math.floor(block.p_number)
                if block.p_number - n > 0.9999:
                    n = math.ceil(block.p_number)
                elif block.p_number - n > 0.0001:
                    raise InterpError("Non integer value for integer")
                oname = str(int(n))
            elif onumber == 99:
                if self.disable_fanuc_style_sub:
                    raise InterpError("DISABLE_FANUC_STYLE_SUB set in INI file, but found m99")
                if self.defining_sub:
                    raise InterpError("Found 'M99' instead of 'O endsub' after 'O sub'")
                block.o_type = M_99
                counter += 3
                oname = self.sub_context[self.call_level].subName or ""
            else:
                raise InterpError(
                    f"{self.sequence_number}: Bug:  Non-m98/m99 M-code passed to read_o(): "
                    f"'{self.linetext}'"
                )
        else:
            counter += 1
            if counter < length and line[counter] == "<":
                oname, counter = self.read_name(line, counter)
            else:
                onumber, counter = self.read_integer_value(line, counter)
                oname = str(onumber)
                # reading a number overwrites the stack LinuxCNC's stale value came from
                self._o_slots[0] = 0.0
            keyword = _O_KEYWORD.match(line, counter)
            if keyword is not None:
                block.o_type = _O_TYPES[keyword.group()]
                counter = keyword.end()
            else:
                rest = line[counter:]
                if rest == "" or rest[0] in "(;":
                    if self.disable_fanuc_style_sub:
                        raise InterpError(
                            "DISABLE_FANUC_STYLE_SUB disabled in INI file, but found bare O-word"
                        )
                    block.o_type = O_
                else:
                    block.o_type = O_none
        return self.read_o_body(line, counter, block, oname)

    def read_o_body(self, line: str, counter: int, block: Block, oname: str) -> int:
        """What follows the O-word and its keyword: the part of reading that depends on
        the state (skipping, defining, call level), and the expressions."""
        length = len(line)
        otype = block.o_type
        if otype in _OWN_NAMES:
            block.o_name = oname
        else:
            if self.call_level:
                sub_name = self.sub_context[self.call_level].subName or ""
            elif self.defining_sub:
                sub_name = self.sub_name or ""
            else:
                sub_name = ""
            block.o_name = f"{sub_name}#{oname}"
        if otype in _SUB_STARTS:
            if self.defining_sub == 1:
                raise InterpError("Nested subroutine definition")
        elif otype in _SUB_ENDS:
            if self.skipping_o and self.skipping_o != block.o_name:
                return counter
            if otype != M_99 and counter < length and line[counter] == "[":
                value, counter = self.read_expression_cached(line, counter)
                self.return_value = value
                self.value_returned = 1
            else:
                self.return_value = 0.0
                self.value_returned = 0
        elif self.defining_sub == 1:
            block.o_type = O_none
        elif otype == O_call:
            if self.skipping_o:
                block.o_type = O_none
                return counter
            block.call_type = self.call_type_of(block.o_name)  # NGC or Python (PY-007)
            params = []
            while counter < length and line[counter] in "[(":
                if line[counter] == "(":
                    counter = self.read_comment(line, counter, block)
                    continue
                if len(params) >= INTERP_SUB_PARAMS:
                    raise InterpError("Too many subroutine parameters")
                value, counter = self.read_expression_cached(line, counter)
                params.append(value)
            block.param_cnt = len(params)
            block.params = params + [0.0] * (INTERP_SUB_PARAMS - len(params))
        elif otype == M_98:
            block.param_cnt = 0
            block.call_type = CT_NGC_M98_SUB
        elif otype in _TESTS:
            if self.skipping_o and self.skipping_o != block.o_name:
                return counter
            if counter >= length or line[counter] != "[":
                raise InterpError(f"Left bracket missing after '{_O_NAMES[otype]}'")
            value, counter = self.read_expression_cached(line, counter)
            self.test_value = value
        elif otype in _NO_ARGUMENTS:
            pass
        else:
            block.o_type = O_none
            raise InterpError("Unknown control command in o word")
        return counter

    def _read_one_item(self, line: str, counter: int, block: Block) -> int:
        letter = line[counter]
        reader = self._readers.get(letter)
        if reader is None:
            if letter < " " or letter > "z" or not letter.isprintable() or letter.isspace():
                raise InterpError(f"Bad character '{_c_octal(letter)}' used")
            raise InterpError(f"Bad character '{letter}' used")
        return reader(line, counter, block)

    @staticmethod
    def read_name(line: str, counter: int) -> tuple[str, int]:
        counter += 1
        end = line.find(">", counter)
        if end < 0 or end - counter >= LINELEN:
            raise InterpError("Named parameter not terminated")
        return line[counter:end], end + 1

    # ------------------------------------------------------------- parameters
    def read_parameter_setting(self, line: str, counter: int, block: Block) -> int:
        counter += 1
        if counter < len(line) and line[counter] == "<":
            name, counter = self.read_name(line, counter)
            self.add_named_param(name)
            if counter >= len(line) or line[counter] != "=":
                raise InterpError("Equal sign missing in parameter setting")
            value, counter = self.read_real_value(line, counter + 1)
            self.named_parameter_assignments.append((name, value))
        else:
            index, counter = self.read_integer_value(line, counter)
            if index < 1 or index >= RS274NGC_MAX_PARAMETERS:
                raise InterpError("Parameter number out of range")
            if index in READONLY_PARAMETERS:
                raise InterpError("Parameter is readonly")
            if counter >= len(line) or line[counter] != "=":
                raise InterpError("Equal sign missing in parameter setting")
            value, counter = self.read_real_value(line, counter + 1)
            self.parameter_assignments.append((index, value))
        return counter

    def read_parameter(self, line: str, counter: int, check_exists: bool) -> tuple[float, int]:
        counter += 1
        if counter < len(line) and line[counter] == "<":
            name, counter = self.read_name(line, counter)
            exists, value = self.find_named_param(name)
            if check_exists:
                return (1.0 if exists else 0.0), counter
            if exists:
                return value, counter
            if self.defining_sub:
                # LinuxCNC leaves the value it was to be read into as it was (see STALE)
                return STALE, counter
            raise InterpError(f"Named parameter #<{name}> not defined")
        index, counter = self.read_integer_value(line, counter)
        if check_exists:
            return float(1 <= index < RS274NGC_MAX_PARAMETERS), counter
        if index < 1 or index >= RS274NGC_MAX_PARAMETERS:
            raise InterpError("Parameter number out of range")
        if 5420 <= index <= 5428 and self.cutter_comp_side:
            raise InterpError("Cannot read current position with cutter radius compensation on")
        return self.parameters[index], counter

    # ------------------------------------------------------------ expressions
    def read_real_value(self, line: str, counter: int) -> tuple[float, int]:
        match = _PLAIN_NUMBER.match(line, counter)
        if match is not None:
            return float(match.group()), match.end()
        # a value read a second time at the same place is compiled (see compiled.py)
        key = (line, counter)
        entry = self._compiled.get(key) if not self.defining_sub else _NEVER
        if entry is None:
            self._compiled[key] = _SEEN
        elif entry is _SEEN:
            entry = self._compiler.value(line, counter)
            self._compiled[key] = entry if entry is not None else _NEVER
            if entry is not None:
                return entry[0](), entry[1]
        elif entry is not _NEVER:
            return entry[0](), entry[1]
        if counter >= len(line):
            raise InterpError("No characters found in reading real value")
        c = line[counter]
        c1 = line[counter + 1] if counter + 1 < len(line) else ""
        if c == "[":
            value, counter = self.read_real_expression(line, counter)
        elif c == "#":
            value, counter = self.read_parameter(line, counter, False)
        elif c == "+" and c1 and not c1.isdigit() and c1 != ".":
            value, counter = self.read_real_value(line, counter + 1)
        elif c == "-" and c1 and not c1.isdigit() and c1 != ".":
            value, counter = self.read_real_value(line, counter + 1)
            if value is not STALE:
                value = -value
        elif "a" <= c <= "z":
            value, counter = self.read_unary(line, counter)
        else:
            value, counter = self.read_real_number(line, counter)
        if value != value:
            raise InterpError("Calculation resulted in 'not a number'")
        if value in (math.inf, -math.inf):
            raise InterpError("Calculation resulted in 'infinity'")
        return value, counter

    @staticmethod
    def read_real_number(line: str, counter: int) -> tuple[float, int]:
        span = _NUMBER_SPAN.match(line, counter)
        text = span.group()
        valid = _VALID_NUMBER.match(text)
        if valid is None:
            raise InterpError(f"bad number format (conversion failed) parsing '{text}'")
        if valid.end() != len(text):
            raise InterpError(f"bad number format (trailing characters) parsing '{text}'")
        return float(text), span.end()

    def read_expression_cached(self, line: str, counter: int) -> tuple[float, int]:
        """read_real_expression for O-word lines, compiled the second time it is read.

        O-word expressions share one value stack (``_o_slots``), as they share one stack
        frame in LinuxCNC: an undefined parameter read while a definition is skipped leaves
        the slot holding what the previous O-word expression left there.
        """
        slots = self._o_slots
        if not self.defining_sub:
            key = (line, -counter - 1)  # apart from read_real_value's keys: no NaN check
            entry = self._compiled.get(key)
            if entry is None:
                self._compiled[key] = _SEEN
            elif entry is _SEEN:
                entry = self._compiler.expression(line, counter)
                self._compiled[key] = entry if entry is not None else _NEVER
            if entry is not None and entry is not _SEEN and entry is not _NEVER:
                value = entry[0]()
                slots[0] = value
                return value, entry[1]
        return self.read_real_expression(line, counter, slots)

    def read_real_expression(
        self, line: str, counter: int, values: list | None = None
    ) -> tuple[float, int]:
        counter += 1
        if values is None:
            values = [0.0] * 8
        operators = [0] * 8
        value, counter = self.read_real_value(line, counter)
        if value is not STALE:
            values[0] = value
        operators[0], counter = self.read_operation(line, counter)
        stack_index = 1
        prec = _PRECEDENCE
        while operators[0] != RIGHT_BRACKET:
            value, counter = self.read_real_value(line, counter)
            if value is not STALE:
                values[stack_index] = value
            operators[stack_index], counter = self.read_operation(line, counter)
            if prec[operators[stack_index]] > prec[operators[stack_index - 1]]:
                stack_index += 1
            else:
                while prec[operators[stack_index]] <= prec[operators[stack_index - 1]]:
                    values[stack_index - 1] = _execute_binary(
                        values[stack_index - 1], operators[stack_index - 1], values[stack_index]
                    )
                    operators[stack_index - 1] = operators[stack_index]
                    if stack_index > 1 and (
                        prec[operators[stack_index - 1]] <= prec[operators[stack_index - 2]]
                    ):
                        stack_index -= 1
                    else:
                        break
        return values[0], counter

    @staticmethod
    def read_operation(line: str, counter: int) -> tuple[int, int]:
        c = line[counter] if counter < len(line) else ""
        counter += 1
        nxt = line[counter : counter + 2]
        if c == "+":
            return PLUS, counter
        if c == "-":
            return MINUS, counter
        if c == "/":
            return DIVIDED_BY, counter
        if c == "*":
            if nxt[:1] == "*":
                return POWER, counter + 1
            return TIMES, counter
        if c == "]":
            return RIGHT_BRACKET, counter
        if c == "a":
            if nxt == "nd":
                return AND2, counter + 2
            raise InterpError("Unknown operation name starting with a")
        if c == "m":
            if nxt == "od":
                return MODULO, counter + 2
            raise InterpError("Unknown operation name starting with m")
        if c == "o":
            if nxt[:1] == "r":
                return NON_EXCLUSIVE_OR, counter + 1
            raise InterpError("Unknown operation name starting with o")
        if c == "x":
            if nxt == "or":
                return EXCLUSIVE_OR, counter + 2
            raise InterpError("Unknown operation name starting with x")
        if c == "e":
            if nxt[:1] == "q":
                return EQ, counter + 1
            raise InterpError("Unknown operation name starting with e")
        if c == "n":
            if nxt[:1] == "e":
                return NE, counter + 1
            raise InterpError("Unknown operation name starting with n")
        if c == "g":
            if nxt[:1] == "e":
                return GE, counter + 1
            if nxt[:1] == "t":
                return GT, counter + 1
            raise InterpError("Unknown operation name starting with g")
        if c == "l":
            if nxt[:1] == "e":
                return LE, counter + 1
            if nxt[:1] == "t":
                return LT, counter + 1
            raise InterpError("Unknown operation name starting with l")
        if c == "":
            raise InterpError("Unclosed expression")
        raise InterpError("Unknown operation")

    def read_unary(self, line: str, counter: int) -> tuple[float, int]:
        operation, counter = _read_operation_unary(line, counter)
        if counter >= len(line) or line[counter] != "[":
            raise InterpError("Left bracket missing after unary operation name")
        if operation == "exists":
            counter += 1
            if counter >= len(line) or line[counter] != "#":
                raise InterpError("Expected # reading parameter")
            value, counter = self.read_parameter(line, counter, True)
            if counter >= len(line) or line[counter] != "]":
                raise InterpError("Expected ] reading bracketed parameter")
            return value, counter + 1
        value, counter = self.read_real_expression(line, counter)
        if operation == "atan":
            if counter >= len(line) or line[counter] != "/":
                raise InterpError("Slash missing after first atan argument")
            counter += 1
            if counter >= len(line) or line[counter] != "[":
                raise InterpError("Left bracket missing after slash with atan")
            argument2, counter = self.read_real_expression(line, counter)
            return ldmath.rad_to_deg(math.atan2(value, argument2)), counter
        return _execute_unary(value, operation), counter


STALE = object()  # "left as it was": see read_parameter and read_real_expression
_SEEN = object()  # compiled-value cache: read once so far
_NEVER = object()  # compiled-value cache: cannot be compiled

_O_KEYWORDS = [
    ("sub", O_sub),
    ("endsub", O_endsub),
    ("call", O_call),
    ("do", O_do),
    ("while", O_while),
    ("repeat", O_repeat),
    ("if", O_if),
    ("elseif", O_elseif),
    ("else", O_else),
    ("endif", O_endif),
    ("break", O_break),
    ("continue", O_continue),
    ("endwhile", O_endwhile),
    ("endrepeat", O_endrepeat),
    ("return", O_return),
]
# LinuxCNC tries the keywords in this order, as prefixes; so does the alternation
_O_KEYWORD = re.compile("|".join(word for word, _ in _O_KEYWORDS))
_O_TYPES = dict(_O_KEYWORDS)
_O_NAMES = {O_while: "while", O_repeat: "repeat", O_if: "if", O_elseif: "elseif"}
# O-word types by what read_o_body does with them (sets, not tuples: read on every O line)
_OWN_NAMES = frozenset((O_sub, O_, O_endsub, O_call, M_98, O_return, M_99))  # not sub-qualified
_SUB_STARTS = frozenset((O_sub, O_))
_SUB_ENDS = frozenset((O_endsub, O_return, M_99))
_TESTS = frozenset((O_while, O_repeat, O_if, O_elseif))  # followed by [test]
_NO_ARGUMENTS = frozenset((O_do, O_else, O_endif, O_break, O_continue, O_endwhile, O_endrepeat))


def _to_c_int(value: float) -> int:
    """(int) of a double as x86-64 does it: out of range becomes INT_MIN."""
    if -2147483648 <= value <= 2147483647:
        return int(value)
    return -2147483648


def _read_operation_unary(line: str, counter: int) -> tuple[str, int]:
    c = line[counter] if counter < len(line) else ""
    counter += 1
    rest = line[counter : counter + 5]
    if c == "a":
        for name in ("bs", "cos", "sin", "tan"):
            if rest.startswith(name):
                return {"bs": "abs", "cos": "acos", "sin": "asin", "tan": "atan"}[name], (
                    counter + len(name)
                )
        raise InterpError("Unknown word starting with a")
    if c == "c":
        if rest.startswith("os"):
            return "cos", counter + 2
        raise InterpError("Unknown word starting with c")
    if c == "e":
        if rest.startswith("xp"):
            return "exp", counter + 2
        if rest.startswith("xists"):
            return "exists", counter + 5
        raise InterpError("Unknown word starting with e")
    if c == "f":
        if rest.startswith("ix"):
            return "fix", counter + 2
        if rest.startswith("up"):
            return "fup", counter + 2
        raise InterpError("Unknown word starting with f")
    if c == "l":
        if rest.startswith("n"):
            return "ln", counter + 1
        raise InterpError("Unknown word starting with l")
    if c == "r":
        if rest.startswith("ound"):
            return "round", counter + 4
        raise InterpError("Unknown word starting with r")
    if c == "s":
        if rest.startswith("in"):
            return "sin", counter + 2
        if rest.startswith("qrt"):
            return "sqrt", counter + 3
        raise InterpError("Unknown word starting with s")
    if c == "t":
        if rest.startswith("an"):
            return "tan", counter + 2
        raise InterpError("Unknown word starting with t")
    raise InterpError("Unknown word where unary operation could be")


def _execute_unary(value: float, operation: str) -> float:
    if operation == "abs":
        return -value if value < 0.0 else value
    if operation == "acos":
        if value < -1.0 or value > 1.0:
            raise InterpError("Argument to acos out of range")
        return ldmath.rad_to_deg(math.acos(value))
    if operation == "asin":
        if value < -1.0 or value > 1.0:
            raise InterpError("Argument to asin out of range")
        return ldmath.rad_to_deg(math.asin(value))
    if operation == "cos":
        return ldmath.cos_deg(value)
    if operation == "exp":
        try:
            return math.exp(value)
        except OverflowError:
            return math.inf
    if operation == "fix":  # C's floor()/ceil() keep the sign of a zero result
        return math.copysign(float(math.floor(value)), value)
    if operation == "fup":
        return math.copysign(float(math.ceil(value)), value)
    if operation == "ln":
        if value <= 0.0:
            raise InterpError("Zero or negative argument to ln")
        return math.log(value)
    if operation == "round":
        return float(_to_c_int(value + (-0.5 if value < 0.0 else 0.5)))
    if operation == "sin":
        return ldmath.sin_deg(value)
    if operation == "sqrt":
        if value < 0.0:
            raise InterpError("Negative argument to sqrt")
        return math.sqrt(value)
    if operation == "tan":
        return ldmath.tan_deg(value)
    raise InterpError("Bug unknown operation")


def _execute_binary(left: float, operation: int, right: float) -> float:
    if operation == DIVIDED_BY:
        if right == 0.0:
            raise InterpError("Attempt to divide by zero")
        return left / right
    if operation == MODULO:
        if right == 0.0:
            return math.nan
        result = math.fmod(left, right)
        if result < 0.0:
            result = result + abs(right)
        return result
    if operation == POWER:
        if left < 0.0 and math.floor(right) != right:
            raise InterpError("Attempt to raise negative to non integer power")
        try:
            return math.pow(left, right)
        except OverflowError:
            return math.inf
        except ValueError:  # 0 ** negative
            return math.inf
    if operation == TIMES:
        return left * right
    if operation == AND2:
        return 0.0 if (left == 0.0 or right == 0.0) else 1.0
    if operation == EXCLUSIVE_OR:
        return 1.0 if ((left == 0.0) != (right == 0.0)) else 0.0
    if operation == MINUS:
        return left - right
    if operation == NON_EXCLUSIVE_OR:
        return 1.0 if (left != 0.0 or right != 0.0) else 0.0
    if operation == PLUS:
        return left + right
    if operation == LT:
        return 1.0 if left < right else 0.0
    if operation == EQ:
        return 1.0 if abs(left - right) < TOLERANCE_EQUAL else 0.0
    if operation == NE:
        return 1.0 if abs(left - right) >= TOLERANCE_EQUAL else 0.0
    if operation == LE:
        return 1.0 if left <= right else 0.0
    if operation == GE:
        return 1.0 if left >= right else 0.0
    if operation == GT:
        return 1.0 if left > right else 0.0
    raise InterpError("Bug unknown operation")
