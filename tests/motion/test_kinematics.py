"""Kinematics modules (KIN-004..018) and the loader's interface check (ARCH-008 style)."""

import math
import sys
import types

import pytest
from hypothesis import given
from hypothesis import strategies as st

from motion.kinematics import (
    KinematicsError,
    KinematicsType,
    SingularityError,
    load_kinematics,
)
from motion.modules import ModuleInterfaceError
from nml.pose import Pose

coord = st.floats(-1000, 1000, allow_nan=False)


def test_trivkins_default_maps_nine_axes_in_order() -> None:
    kins = load_kinematics("trivkins")
    assert kins.num_joints == 9
    assert kins.forward(range(9)) == Pose(*map(float, range(9)))
    assert kins.kinematics_type() == KinematicsType.IDENTITY


def test_trivkins_lathe_coordinates() -> None:
    kins = load_kinematics("trivkins", coordinates="XZ")
    assert kins.num_joints == 2
    assert kins.axis_mask == 0x5  # MOT-068
    assert kins.inverse(Pose(x=1, y=7, z=3)) == [1, 3]
    assert kins.forward([1, 3]) == Pose(x=1, z=3)


def test_trivkins_gantry_repeats_a_letter() -> None:
    kins = load_kinematics("trivkins", coordinates="xyyz", kinstype="both")
    assert kins.inverse(Pose(x=1, y=2, z=3)) == [1, 2, 2, 3]
    # forward takes the axis from the first joint mapped to it (KIN-007)
    assert kins.forward([1, 2, 2.5, 3]) == Pose(x=1, y=2, z=3)
    assert kins.kinematics_type() == KinematicsType.BOTH
    assert kins.axis_mask == 0x7


def test_trivkins_axis_mask_xyzb() -> None:
    assert load_kinematics("trivkins", coordinates="xyzb").axis_mask == 0x17


@given(st.lists(coord, min_size=9, max_size=9), st.sampled_from(["xyz", "xyyz", "xz", "xyzabcuvw"]))
def test_trivkins_forward_inverse_round_trip(values: list[float], coordinates: str) -> None:
    kins = load_kinematics("trivkins", coordinates=coordinates)
    pose = kins.forward(kins.inverse(Pose(*values)))
    for letter in set(coordinates):
        assert pose[letter] == Pose(*values)[letter]


@given(coord, coord, coord)
def test_corexy_round_trip(x: float, y: float, z: float) -> None:
    kins = load_kinematics("corexykins")
    joints = kins.inverse(Pose(x=x, y=y, z=z))
    assert joints[0] == pytest.approx(x + y) and joints[1] == pytest.approx(x - y)
    back = kins.forward(joints)
    assert (back.x, back.y, back.z) == pytest.approx((x, y, z), abs=1e-9)


def test_bipod_test_vectors() -> None:  # KIN-013
    kins = load_kinematics("bipod", bx="10")
    joints = kins.inverse(Pose(x=5, y=5))
    assert joints == pytest.approx([math.sqrt(50), math.sqrt(50)])
    pose = kins.forward(joints)
    assert (pose.x, pose.y) == pytest.approx((5, 5))


def test_bipod_singularity_is_an_error() -> None:  # KIN-010/012
    kins = load_kinematics("bipod", bx=10)
    with pytest.raises(SingularityError, match="cannot meet"):
        kins.forward([1, 1])


@given(st.floats(0.1, 9.9), st.floats(0.1, 50))
def test_bipod_round_trip(x: float, y: float) -> None:
    kins = load_kinematics("bipod", bx=10)
    pose = kins.forward(kins.inverse(Pose(x=x, y=y)))
    assert (pose.x, pose.y) == pytest.approx((x, y), abs=1e-6)


def test_home_returns_the_pose_of_the_home_joints() -> None:  # KIN-015
    kins = load_kinematics("trivkins", coordinates="xyz")
    pose, joints = kins.home(Pose(), [1, 2, 3])
    assert joints == [1, 2, 3] and pose == Pose(1, 2, 3)


def test_bad_input_gives_clear_errors() -> None:
    kins = load_kinematics("trivkins", coordinates="xyz")
    with pytest.raises(KinematicsError, match="joint 1 position is not finite"):
        kins.forward([0, float("nan"), 0])
    with pytest.raises(KinematicsError, match="expected 3 joint values"):
        kins.forward([0])
    with pytest.raises(KinematicsError, match="unknown axis letters"):
        load_kinematics("trivkins", coordinates="xq")
    with pytest.raises(KinematicsError, match="kinstype"):
        load_kinematics("trivkins", kinstype="z")
    with pytest.raises(KinematicsError, match="positive"):
        load_kinematics("bipod", bx=-1)


def test_loader_refuses_unknown_and_incomplete_modules() -> None:
    with pytest.raises(ModuleInterfaceError, match="not found"):
        load_kinematics("no_such_kins")
    module = types.ModuleType("halfkins")

    class Half:
        num_joints = 1

        def forward(self, joints):
            return Pose()

    module.create = Half
    sys.modules["halfkins"] = module
    try:
        with pytest.raises(ModuleInterfaceError, match="missing inverse, kinematics_type, home"):
            load_kinematics("halfkins")
    finally:
        del sys.modules["halfkins"]


def test_kinematics_type_capabilities() -> None:
    assert KinematicsType.FORWARD_ONLY.has_forward and not KinematicsType.FORWARD_ONLY.has_inverse
    assert KinematicsType.INVERSE_ONLY.has_inverse and not KinematicsType.INVERSE_ONLY.has_forward
    assert KinematicsType.IDENTITY.has_forward and KinematicsType.BOTH.has_inverse
