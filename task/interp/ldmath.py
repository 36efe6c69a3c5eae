"""x87 long double arithmetic where LinuxCNC mixes it into angle calculations.

LinuxCNC converts degrees with ``M_PIl`` (a long double), and in C++ ``sin(long double)``
is ``sinl``: ``SIN[180]`` is computed as ``sinl(180 * M_PIl / 180)``, slightly negative, where
``math.sin(math.pi)`` is slightly positive; that shows up as ``-0.0000`` against ``0.0000``.
numpy's ``longdouble`` is the same x87 type on x86-64 Linux, so these helpers repeat the
long double steps exactly.
"""

from __future__ import annotations

from functools import cache


@cache
def _np():
    """numpy and the long double constants, imported on first use (keeps start-up fast)."""
    import numpy as np

    ld = np.longdouble
    pi_ld = ld(0xC90FDAA22168C235) * ld(2.0) ** -62  # M_PIl
    return np, ld, pi_ld, pi_ld / ld(2.0), ld(180.0)


def _radians(degrees: float):
    _, ld, pi_ld, _, ld180 = _np()
    return ld(degrees) * pi_ld / ld180


def sin_deg(degrees: float) -> float:
    """``sin((x * M_PIl) / 180.0)`` with C++'s long double overload."""
    return float(_np()[0].sin(_radians(degrees)))


def cos_deg(degrees: float) -> float:
    return float(_np()[0].cos(_radians(degrees)))


def tan_deg(degrees: float) -> float:
    return float(_np()[0].tan(_radians(degrees)))


def rad_to_deg(radians: float) -> float:
    """``(double)((radians * 180.0) / M_PIl)``"""
    _, ld, pi_ld, _, ld180 = _np()
    return float(ld(radians) * ld180 / pi_ld)


def minus_pi_2(value: float) -> float:
    """``(double)(value - M_PI_2l)``"""
    _, ld, _, pi_2, _ = _np()
    return float(ld(value) - pi_2)


def plus_pi_2(value: float) -> float:
    """``(double)(value + M_PI_2l)``"""
    _, ld, _, pi_2, _ = _np()
    return float(ld(value) + pi_2)


def ld(value):
    """A value as an x87 long double (numpy), for expressions LinuxCNC evaluates that way."""
    return _np()[1](value)


def pi_ld():
    return _np()[2]


def pi_2_ld():
    return _np()[3]


def sinl(value) -> float:
    """``sin`` of a long double argument (C++ picks ``sinl``), rounded to double."""
    return float(_np()[0].sin(value))


def find_turn(
    x1: float, y1: float, center_x: float, center_y: float, turn: int, x2: float, y2: float
) -> float:
    """LinuxCNC's find_turn: the swept angle, with its long double 2*pi steps."""
    import math

    if turn == 0:
        return 0.0
    alpha = math.atan2(y1 - center_y, x1 - center_x)
    beta = math.atan2(y2 - center_y, x2 - center_x)
    two_pi = 2 * pi_ld()
    if turn > 0:
        if beta <= alpha:
            beta = float(ld(beta) + two_pi)
        return float((ld(beta) - ld(alpha)) + (turn - 1) * two_pi)
    if alpha <= beta:
        alpha = float(ld(alpha) + two_pi)
    return float((ld(beta) - ld(alpha)) + (turn + 1) * two_pi)


def degrees_to_radians(degrees: float) -> float:
    """``(double)(degrees * (M_PIl / 180.0))``"""
    return float(ld(degrees) * (pi_ld() / ld(180.0)))


def _libc_hypot():
    """glibc's hypot: CPython's math.hypot uses its own algorithm, which can differ from
    glibc in the last bit, and LinuxCNC's positions are built from glibc's."""
    import ctypes

    try:
        libm = ctypes.CDLL("libm.so.6")  # find_library() would run ldconfig: slow
        func = libm.hypot
    except (OSError, AttributeError):
        import math

        return math.hypot
    func.restype = ctypes.c_double
    func.argtypes = [ctypes.c_double, ctypes.c_double]
    return func


def hypot(x: float, y: float) -> float:
    """glibc's hypot, loaded on first use (ctypes costs start-up time)."""
    func = _libc_hypot()
    globals()["hypot"] = func
    return func(x, y)
