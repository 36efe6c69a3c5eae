"""Any command motion handles, with any field values (what a buggy client or corrupt shared
memory could put in the motion command buffer), is carried out or refused with a reason:
it never raises, and the joints' commands stay finite (MOT-019..065 and the fault rules).

An exception here would, in the realtime host, disable the HAL function that raised it:
motion would stop listening or stop running. motmod reports such a bug and turns motion off
(tests/motion/test_motmod.py); this test is about not having those bugs.
"""

from __future__ import annotations

import math
import struct

import hypothesis.strategies as st
from hypothesis import HealthCheck, given, settings

from motion.controller import COORD, FREE, TELEOP, MotionController
from nml import emc
from nml.commands import handled_by
from tests.motion.test_controller import enabled_homed, make, run

COMMANDS = sorted(handled_by(MotionController), key=lambda cls: cls.NAME)
SPECIAL_FLOATS = [0.0, -0.0, 1.0, -1.0, 0.5, 100.0, -100.0, 1e9, 1e300, -1e300, 5e-324]
SPECIAL_FLOATS += [math.nan, math.inf, -math.inf]
SPECIAL_INTS = [0, 1, -1, 2, 3, 8, 9, 64, 1000, 2**31 - 1, -(2**31)]


def _leaf_value(code: str) -> st.SearchStrategy:
    if code == "d":
        return st.sampled_from(SPECIAL_FLOATS) | st.floats(-1e3, 1e3)
    if code == "f":  # (single precision: what fits)
        fitting = [v for v in SPECIAL_FLOATS if not abs(v) < math.inf or abs(v) < 3e38]
        return st.sampled_from(fitting) | st.floats(-1e3, 1e3, width=32)
    if code == "i":
        return st.sampled_from(SPECIAL_INTS) | st.integers(-10, 10)
    if code == "B":
        return st.integers(0, 255)
    if code == "?":
        return st.booleans()
    if code == "Q":
        return st.integers(0, 2**64 - 1)
    return st.binary(max_size=int(code[:-1]))  # a text field: "<n>s"


@st.composite
def commands(draw: st.DrawFn) -> emc.NMLmsg:
    """A command with raw bytes for its fields, or with odd but well-formed values."""
    cls = draw(st.sampled_from(COMMANDS))
    if draw(st.booleans()):
        size = cls.fixed_size()
        return cls.from_bytes(draw(st.binary(min_size=size, max_size=size)))
    values = [draw(_leaf_value(code)) for code in cls.flat_codes]
    return cls.from_flat(values)


def machine_in(mode: int | None) -> MotionController:
    """Motion off (None), or on and homed in free, coordinated or teleop mode."""
    if mode is None:
        return make()
    motion = enabled_homed(FREE if mode == TELEOP else mode)
    if mode == TELEOP:
        assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=TELEOP)) is None
    return motion


def test_every_field_of_every_command_can_be_drawn() -> None:
    for cls in COMMANDS:
        assert struct.calcsize(cls.flat_format.format) == cls.fixed_size(), cls.NAME


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mode=st.sampled_from([None, FREE, COORD, TELEOP]), sent=st.lists(commands(), max_size=6))
def test_any_command_is_done_or_refused_and_the_joints_stay_finite(mode, sent) -> None:
    motion = machine_in(mode)
    for cmd in sent:
        answer = motion.handle(cmd)
        assert answer is None or isinstance(answer, str), cmd.NAME
        run(motion, 3)
        values = [v for j in motion.joints for v in (j.pos_cmd, j.motor_pos_cmd, j.vel_cmd)]
        assert all(map(math.isfinite, values)), (cmd.NAME, cmd.to_python(), values)
