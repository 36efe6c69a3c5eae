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
