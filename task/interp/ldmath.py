"""x87 long double arithmetic where LinuxCNC mixes it into angle calculations.

LinuxCNC converts degrees with ``M_PIl`` (a long double), and in C++ ``sin(long double)``
is ``sinl``: ``SIN[180]`` is computed as ``sinl(180 * M_PIl / 180)``, slightly negative, where
``math.sin(math.pi)`` is slightly positive; that shows up as ``-0.0000`` against ``0.0000``.

``LongDouble`` repeats the x87 steps exactly: every operation is done on exact integers and
rounded to a 64-bit significand, to nearest, ties to even, as the FPU does; ``float()`` rounds
to double as C's cast does. The transcendental functions are glibc's own (``sinl``, ``cosl``,
``tanl``, ``hypot``) through ctypes, loaded on first use. (numpy's ``longdouble`` is the same
type, but importing numpy costs more than interpreting a whole small program.)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import cache

_BITS = 64  # the x87 extended significand
_M_PIL = 0xC90FDAA22168C235  # M_PIl = _M_PIL * 2**-62


class LongDouble:
    """An x87 extended precision value: ``(-1)**sign * mant * 2**exp``, ``mant`` < 2**64.

    Arithmetic with ``LongDouble``, ``float`` and ``int`` operands (converted exactly, as C
    promotes them) gives a ``LongDouble``; comparisons are exact.
    """

    __slots__ = ("exp", "mant", "sign")

    def __init__(self, sign: int, mant: int, exp: int) -> None:
        self.sign = sign
        self.mant = mant
        self.exp = exp

    # ------------------------------------------------------------ conversion
    def __float__(self) -> float:
        if not self.mant:
            return -0.0 if self.sign else 0.0
        value = math.ldexp(float(self.mant), self.exp)  # int -> float rounds to nearest even
        if value and abs(value) >= 2.2250738585072014e-308:
            return -value if self.sign else value
        from fractions import Fraction  # subnormal: round once, exactly

        value = float(Fraction(self.mant) * Fraction(2) ** self.exp)
        return -value if self.sign else value

    def __repr__(self) -> str:
        return f"LongDouble({float(self)!r})"

    # ------------------------------------------------------------ arithmetic
    def __neg__(self) -> LongDouble:
        return LongDouble(self.sign ^ 1, self.mant, self.exp)

    def __abs__(self) -> LongDouble:
        return LongDouble(0, self.mant, self.exp)

    def __add__(self, other) -> LongDouble:
        other = _coerce(other)
        if not self.mant and not other.mant:
            return LongDouble(self.sign & other.sign, 0, 0)  # -0 + -0 is the only -0
        exp = min(self.exp, other.exp)
        total = _signed(self, exp) + _signed(other, exp)
        if not total:
            return LongDouble(0, 0, 0)
        return _rounded(int(total < 0), abs(total), exp)

    __radd__ = __add__

    def __sub__(self, other) -> LongDouble:
        return self + -_coerce(other)

    def __rsub__(self, other) -> LongDouble:
        return _coerce(other) + -self

    def __mul__(self, other) -> LongDouble:
        other = _coerce(other)
        return _rounded(self.sign ^ other.sign, self.mant * other.mant, self.exp + other.exp)

    __rmul__ = __mul__

    def __truediv__(self, other) -> LongDouble:
        other = _coerce(other)
        if not other.mant:
            raise ZeroDivisionError("long double division by zero")
        return _quotient(self.sign ^ other.sign, self.mant, other.mant, self.exp - other.exp)

    def __rtruediv__(self, other) -> LongDouble:
        return _coerce(other) / self

    # ------------------------------------------------------------ comparison
    def _cmp(self, other) -> int:
        other = _coerce(other)
        exp = min(self.exp, other.exp)
        difference = _signed(self, exp) - _signed(other, exp)
        return (difference > 0) - (difference < 0)

    def __eq__(self, other) -> bool:
        return self._cmp(other) == 0

    def __lt__(self, other) -> bool:
        return self._cmp(other) < 0

    def __le__(self, other) -> bool:
        return self._cmp(other) <= 0

    def __gt__(self, other) -> bool:
        return self._cmp(other) > 0

    def __ge__(self, other) -> bool:
        return self._cmp(other) >= 0

    __hash__ = None  # mutable-looking numeric: not used as a key

    # ------------------------------------------------------------ C interface
    def to_bytes(self) -> bytes:
        """The 80-bit memory image (little endian, padded to 16 bytes) for ctypes."""
        if not self.mant:
            return bytes(9) + bytes([0x80 if self.sign else 0]) + bytes(6)
        shift = _BITS - self.mant.bit_length()
        biased = self.exp - shift + (_BITS - 1) + 16383
        return (
            (self.mant << shift).to_bytes(8, "little")
            + (biased | (self.sign << 15)).to_bytes(2, "little")
            + bytes(6)
        )


def _signed(value: LongDouble, exp: int) -> int:
    magnitude = value.mant << (value.exp - exp)
    return -magnitude if value.sign else magnitude


def _rounded(sign: int, mant: int, exp: int, sticky: bool = False) -> LongDouble:
    """``mant * 2**exp`` (plus a sticky remainder) rounded to 64 bits, ties to even."""
    extra = mant.bit_length() - _BITS
    if extra > 0:
        low = mant & ((1 << extra) - 1)
        mant >>= extra
        exp += extra
        half = 1 << (extra - 1)
        if low > half or (low == half and (sticky or mant & 1)):
            mant += 1
            if mant >> _BITS:
                mant >>= 1
                exp += 1
    return LongDouble(sign, mant, exp)


def _quotient(sign: int, num: int, den: int, exp: int) -> LongDouble:
    """``num / den * 2**exp`` rounded to 64 bits."""
    if not num:
        return LongDouble(sign, 0, 0)
    shift = _BITS + 2 - (num.bit_length() - den.bit_length())
    if shift > 0:
        num <<= shift
        exp -= shift
    q, r = divmod(num, den)
    return _rounded(sign, q, exp, r != 0)


def _coerce(value) -> LongDouble:
    if isinstance(value, LongDouble):
        return value
    return ld(value)


def ld(value: float) -> LongDouble:
    """A double or an int as a long double (exactly, as C promotes it)."""
    if isinstance(value, int):
        return _rounded(int(value < 0), abs(value), 0)
    if value != value or value in (math.inf, -math.inf):
        raise ValueError("long double emulation has no NaN or infinity")
    if not value:
        return LongDouble(int(math.copysign(1.0, value) < 0), 0, 0)
    num, den = value.as_integer_ratio()
    return LongDouble(int(num < 0), abs(num), 1 - den.bit_length())


PI = LongDouble(0, _M_PIL, -62)  # M_PIl
PI_2 = LongDouble(0, _M_PIL, -63)  # M_PI_2l
_LD180 = ld(180.0)


def pi_ld() -> LongDouble:
    return PI


def pi_2_ld() -> LongDouble:
    return PI_2


# ---------------------------------------------------------------- glibc calls
@cache
def _libm():
    """glibc's libm through ctypes (find_library() would run ldconfig: slow)."""
    import ctypes

    libm = ctypes.CDLL("libm.so.6")
    for name in ("sinl", "cosl", "tanl"):
        func = getattr(libm, name)
        func.restype = ctypes.c_longdouble
        func.argtypes = [ctypes.c_longdouble]
    return libm, ctypes.c_longdouble.from_buffer_copy


def _call_l(name: str, value: LongDouble) -> float:
    """``(double) name##l(value)``: ctypes hands back the result cast to double."""
    libm, from_bytes = _libm()
    return getattr(libm, name)(from_bytes(value.to_bytes()))


def _radians(degrees: float) -> bytes:
    """``degrees * M_PIl / 180.0`` in long double, as its memory image.

    The same steps as ``ld(degrees) * PI / ld(180.0)``, unrolled on plain integers: this
    runs for every SIN, COS and TAN of a program.
    """
    num, den = degrees.as_integer_ratio()
    sign = 0x8000 if num < 0 else 0
    if not num:
        return LongDouble(int(math.copysign(1.0, degrees) < 0), 0, 0).to_bytes()
    # the product, exact, rounded to 64 bits
    mant = abs(num) * _M_PIL
    exp = 1 - den.bit_length() - 62
    extra = mant.bit_length() - _BITS
    if extra > 0:
        low = mant & ((1 << extra) - 1)
        mant >>= extra
        exp += extra
        half = 1 << (extra - 1)
        if low > half or (low == half and mant & 1):
            mant += 1
            if mant >> _BITS:
                mant >>= 1
                exp += 1
    # divided by 180, rounded to 64 bits (sticky remainder)
    shift = _BITS + 10 - mant.bit_length()
    q, r = divmod(mant << shift, 180)
    exp -= shift
    extra = q.bit_length() - _BITS
    low = q & ((1 << extra) - 1)
    q >>= extra
    exp += extra
    half = 1 << (extra - 1)
    if low > half or (low == half and (r or q & 1)):
        q += 1
        if q >> _BITS:
            q >>= 1
            exp += 1
    return ((((exp + 63 + 16383) | sign) << 64) | q).to_bytes(16, "little")


def _libm_call(name: str):
    """A long double function of libm that takes the memory image of its argument."""
    libm, from_bytes = _libm()
    func = getattr(libm, name)

    def call(image: bytes) -> float:
        return func(from_bytes(image))

    return call


# Degree conversions and results already computed, by argument: loops and subroutines take
# the same angles again and again, and SIN[a] and COS[a] of the same ``a`` often go together.
# A cached value is the very result of the call it saves. Zeros, infinities and NaNs are never
# cached (0.0 and -0.0 are the same key). Each table is emptied when it grows too large.
_CACHE_SIZE = 4096
_images: dict[float, bytes] = {}
_calls: dict[str, Callable[[bytes], float]] = {}  # libm's functions, loaded on first use


def _trig_function(name: str) -> Callable[[float], float]:
    """``name((x * M_PIl) / 180.0)`` with C++'s long double overload, for degrees ``x``."""
    results: dict[float, float] = {}

    def trig_deg(degrees: float) -> float:
        result = results.get(degrees)
        if result is not None:
            return result
        call = _calls.get(name)
        if call is None:
            call = _calls[name] = _libm_call(name)
        if degrees - degrees or not degrees:
            # an infinity or a NaN (sinl gives a NaN; the caller reports it), or a zero,
            # whose sign _radians does not keep
            if degrees:
                return math.nan
            return call(ld(degrees).to_bytes())
        image = _images.get(degrees)
        if image is None:
            if len(_images) >= _CACHE_SIZE:
                _images.clear()
            image = _images[degrees] = _radians(degrees)
        result = call(image)
        if len(results) >= _CACHE_SIZE:
            results.clear()
        results[degrees] = result
        return result

    trig_deg.__name__ = name[:-1] + "_deg"
    return trig_deg


sin_deg = _trig_function("sinl")
cos_deg = _trig_function("cosl")
tan_deg = _trig_function("tanl")


def sinl(value: LongDouble) -> float:
    """``sin`` of a long double argument (C++ picks ``sinl``), rounded to double."""
    return _call_l("sinl", _coerce(value))


def rad_to_deg(radians: float) -> float:
    """``(double)((radians * 180.0) / M_PIl)``"""
    return float(ld(radians) * _LD180 / PI)


def minus_pi_2(value: float) -> float:
    """``(double)(value - M_PI_2l)``"""
    return float(ld(value) - PI_2)


def plus_pi_2(value: float) -> float:
    """``(double)(value + M_PI_2l)``"""
    return float(ld(value) + PI_2)


def degrees_to_radians(degrees: float) -> float:
    """``(double)(degrees * (M_PIl / 180.0))``"""
    return float(ld(degrees) * (PI / _LD180))


def find_turn(
    x1: float, y1: float, center_x: float, center_y: float, turn: int, x2: float, y2: float
) -> float:
    """LinuxCNC's find_turn: the swept angle, with its long double 2*pi steps."""
    if turn == 0:
        return 0.0
    alpha = math.atan2(y1 - center_y, x1 - center_x)
    beta = math.atan2(y2 - center_y, x2 - center_x)
    two_pi = 2 * PI
    if turn > 0:
        if beta <= alpha:
            beta = float(ld(beta) + two_pi)
        return float((ld(beta) - ld(alpha)) + (turn - 1) * two_pi)
    if alpha <= beta:
        alpha = float(ld(alpha) + two_pi)
    return float((ld(beta) - ld(alpha)) + (turn + 1) * two_pi)


def _libc_hypot():
    """glibc's hypot: CPython's math.hypot uses its own algorithm, which can differ from
    glibc in the last bit, and LinuxCNC's positions are built from glibc's."""
    import ctypes

    try:
        libm = ctypes.CDLL("libm.so.6")
        func = libm.hypot
    except (OSError, AttributeError):
        return math.hypot
    func.restype = ctypes.c_double
    func.argtypes = [ctypes.c_double, ctypes.c_double]
    return func


def hypot(x: float, y: float) -> float:
    """glibc's hypot, loaded on first use (ctypes costs start-up time)."""
    func = _libc_hypot()
    globals()["hypot"] = func
    return func(x, y)
