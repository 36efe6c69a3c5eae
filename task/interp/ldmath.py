"""x87 long double arithmetic where LinuxCNC mixes it into angle calculations.

LinuxCNC converts degrees with ``M_PIl`` (a long double), and in C++ ``sin(long double)``
is ``sinl``: ``SIN[180]`` is computed as ``sinl(180 * M_PIl / 180)``, slightly negative, where
``math.sin(math.pi)`` is slightly positive; that shows up as ``-0.0000`` against ``0.0000``.
numpy's ``longdouble`` is the same x87 type on x86-64 Linux, so these helpers repeat the
long double steps exactly.
"""

from __future__ import annotations

import numpy as np

_LD = np.longdouble
PI_LD = _LD(0xC90FDAA22168C235) * _LD(2.0) ** -62  # M_PIl
PI_2_LD = PI_LD / _LD(2.0)  # M_PI_2l
_180 = _LD(180.0)


def _radians(degrees: float):
    return _LD(degrees) * PI_LD / _180


def sin_deg(degrees: float) -> float:
    """``sin((x * M_PIl) / 180.0)`` with C++'s long double overload."""
    return float(np.sin(_radians(degrees)))


def cos_deg(degrees: float) -> float:
    return float(np.cos(_radians(degrees)))


def tan_deg(degrees: float) -> float:
    return float(np.tan(_radians(degrees)))


def rad_to_deg(radians: float) -> float:
    """``(double)((radians * 180.0) / M_PIl)``"""
    return float(_LD(radians) * _180 / PI_LD)


def minus_pi_2(value: float) -> float:
    """``(double)(value - M_PI_2l)``"""
    return float(_LD(value) - PI_2_LD)


def plus_pi_2(value: float) -> float:
    """``(double)(value + M_PI_2l)``"""
    return float(_LD(value) + PI_2_LD)
