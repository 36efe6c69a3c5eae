"""ldmath's pure-Python x87 long double: the same bits as the FPU (and numpy's longdouble).

The interpreter's angle arithmetic must round exactly as LinuxCNC's long double code does
(``SIN[180]`` is ``-0.0000`` in rs274's output, not ``0.0000``); these tests pin the rounding
down without numpy, and compare with numpy's ``longdouble`` (the x87 type on x86-64) where
numpy is installed.
"""

from __future__ import annotations

import math
import random
import struct

import pytest

from task.interp import ldmath
from task.interp.ldmath import PI, LongDouble, ld


def _bits(value: float) -> bytes:
    return struct.pack("<d", value)


def test_a_double_converts_exactly_both_ways() -> None:
    for value in (0.1, -2.5, 1e-300, 1e300, 123456.789, 5e-324):
        assert float(ld(value)) == value


def test_rounding_is_to_nearest_with_ties_to_even() -> None:
    one = ld(1.0)
    assert float(one + ld(2.0**-64)) == 1.0  # a tie below an even significand: stays
    above = one + ld(2.0**-63)  # the next long double after 1
    assert above > one
    assert (above + ld(2.0**-64)) > above  # a tie above an odd significand: rounds up
    assert (one + ld(3 * 2.0**-65)) == above  # more than half: rounds up


def test_zero_keeps_its_sign() -> None:
    assert math.copysign(1.0, float(ld(-0.0))) == -1.0
    assert math.copysign(1.0, float(ld(-0.0) + ld(-0.0))) == -1.0
    assert math.copysign(1.0, float(ld(1.5) - ld(1.5))) == 1.0
    assert math.copysign(1.0, ldmath.sin_deg(-0.0)) == -1.0


def test_sin_of_180_degrees_is_slightly_negative_as_in_linuxcnc() -> None:
    assert -1e-15 < ldmath.sin_deg(180.0) < 0.0
    assert ldmath.cos_deg(90.0) != 0.0
    assert ldmath.cos_deg(0.0) == 1.0


def test_trig_results_taken_again_are_the_same_and_zeros_keep_their_sign() -> None:
    rng = random.Random(7)
    angles = [rng.uniform(-720.0, 720.0) for _ in range(50)] + [30.0, 45.0, 90.0, 180.0]
    functions = (ldmath.sin_deg, ldmath.cos_deg, ldmath.tan_deg)
    first = [_bits(f(a)) for a in angles for f in functions]
    again = [_bits(f(a)) for a in angles for f in functions]  # (from the cache)
    assert again == first
    assert ldmath.sin_deg(0.0) == 0.0
    assert math.copysign(1.0, ldmath.sin_deg(0.0)) == 1.0
    assert math.copysign(1.0, ldmath.sin_deg(-0.0)) == -1.0  # not 0.0's cached result


def test_trig_of_an_infinity_is_a_nan_for_the_reader_to_report() -> None:
    assert math.isnan(ldmath.sin_deg(math.inf))
    assert math.isnan(ldmath.cos_deg(-math.inf))
    assert math.isnan(ldmath.tan_deg(math.nan))


def test_the_memory_image_is_the_x87_format() -> None:
    image = ld(1.0).to_bytes()
    assert image[:8] == (1 << 63).to_bytes(8, "little")
    assert image[8:10] == (16383).to_bytes(2, "little")
    assert ld(-2.0).to_bytes()[8:10] == (0x8000 | 16384).to_bytes(2, "little")
    assert len(image) == 16


def test_pi_is_m_pil() -> None:
    assert float(PI) == math.pi
    assert ld(math.pi) < PI  # M_PIl is above the double nearest pi


def _values() -> list[float]:
    rng = random.Random(4)
    values = [0.72 * k for k in range(400)] + [15.0 * k for k in range(-30, 30)]
    values += [rng.uniform(-1e4, 1e4) for _ in range(2000)]
    values += [rng.uniform(-1, 1) * 10 ** rng.randint(-12, 12) for _ in range(2000)]
    return values


def test_the_same_bits_as_numpy_longdouble() -> None:
    np = pytest.importorskip("numpy")
    nld = np.longdouble
    npi = nld(0xC90FDAA22168C235) * nld(2.0) ** -62
    ours_theirs = [
        (ldmath.sin_deg, lambda x: float(np.sin(nld(x) * npi / nld(180.0)))),
        (ldmath.cos_deg, lambda x: float(np.cos(nld(x) * npi / nld(180.0)))),
        (ldmath.tan_deg, lambda x: float(np.tan(nld(x) * npi / nld(180.0)))),
        (ldmath.rad_to_deg, lambda x: float(nld(x) * nld(180.0) / npi)),
        (ldmath.minus_pi_2, lambda x: float(nld(x) - npi / nld(2.0))),
        (ldmath.plus_pi_2, lambda x: float(nld(x) + npi / nld(2.0))),
        (ldmath.degrees_to_radians, lambda x: float(nld(x) * (npi / nld(180.0)))),
    ]
    for value in _values():
        for ours, theirs in ours_theirs:
            assert _bits(ours(value)) == _bits(theirs(value)), (ours.__name__, value)


def test_arithmetic_matches_numpy_longdouble() -> None:
    np = pytest.importorskip("numpy")
    nld = np.longdouble
    rng = random.Random(5)
    for _ in range(3000):
        a, b = rng.uniform(-4, 4), rng.uniform(-4, 4) * 10 ** rng.randint(-8, 8)
        x, y = ld(a), ld(b)
        assert _bits(float(x + y)) == _bits(float(nld(a) + nld(b)))
        assert _bits(float(x - y)) == _bits(float(nld(a) - nld(b)))
        assert _bits(float(x * y)) == _bits(float(nld(a) * nld(b)))
        assert _bits(float(x / y)) == _bits(float(nld(a) / nld(b)))
        assert (x < y) == (nld(a) < nld(b))
        turns = rng.randint(-3, 3)
        assert _bits(float(x + turns * (2 * PI))) == _bits(
            float(nld(a) + turns * (2 * (nld(0xC90FDAA22168C235) * nld(2.0) ** -62)))
        )


def test_division_by_zero_is_refused() -> None:
    with pytest.raises(ZeroDivisionError):
        LongDouble(0, 1, 0) / ld(0.0)
