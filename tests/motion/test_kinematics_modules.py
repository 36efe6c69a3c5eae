"""The kinematics modules of LinuxCNC's sample configs (issue 17 "Kinematics"), loaded by
name without HAL: forward(inverse(p)) round trips, and known poses checked against the
machine's geometry computed here independently (rotation matrices, rod and strut lengths),
not against the module's own formulas. Switchable kinematics switch as LinuxCNC's do.
"""

from __future__ import annotations

import contextlib
import gc
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion.kinematics import KinematicsError, SwitchKins, fit_joints, load_kinematics
from motion.kinematics._rotation import rpy_matrix
from nml.pose import AXIS_NAMES, Pose

REPO = Path(__file__).resolve().parents[2]
SAMPLE_CONFIG_KINEMATICS = [
    "trivkins",
    "corexykins",
    "xyzac-trt-kins",
    "xyzbc-trt-kins",
    "lineardeltakins",
    "rotarydeltakins",
    "5axiskins",
    "maxkins",
    "pentakins",
    "genhexkins",
    "genserkins",
    "pumakins",
    "scarakins",
    "rosekins",
    "tripodkins",
    "scorbot-kins",
    "xyzab_tdr_kins",
    "millturn",
]


def own(kins):
    """The module's own kinematics behind a switchable module (type 0)."""
    return kins.types[0] if isinstance(kins, SwitchKins) else kins


def rx(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def assert_pose(pose: Pose, expected: Pose, letters: str, tol: float = 1e-6) -> None:
    for letter in letters:
        assert pose[letter] == pytest.approx(expected[letter], abs=tol), letter


# --------------------------------------------------------------- found by name
@pytest.mark.parametrize("name", SAMPLE_CONFIG_KINEMATICS)
def test_each_module_is_one_file_found_by_its_linuxcnc_name(name: str) -> None:
    path = REPO / "motion" / "kinematics" / f"{name.replace('-', '_')}.py"
    assert path.is_file()
    kins = load_kinematics(name)
    assert kins.num_joints >= 3
    assert kins.kinematics_type().has_forward and kins.kinematics_type().has_inverse


def test_hal_components_do_not_import_motion() -> None:
    """One-way imports (issue 15): kinematics are found in motion/kinematics, never
    through shims in hal/components."""
    for path in (REPO / "hal" / "components").glob("*.py"):
        text = path.read_text()
        assert "from motion" not in text and "import motion" not in text, path.name


# --------------------------------------------------------------- round trips
# name -> (module parameters, pins to set on its own kinematics, poses to round-trip,
#          the axes that must come back)
ROUND_TRIPS = {
    "corexykins": ({}, {}, [Pose(10, -3, 2, 1, 2, 3, 4, 5, 6)], AXIS_NAMES),
    "xyzac-trt-kins": (
        {},
        {"x_rot_point": 3, "y_rot_point": -2, "z_rot_point": 5, "y_offset": 20, "z_offset": 10},
        [Pose(10, 5, -20, a=-30, c=90), Pose(-50, 40, 7, a=20, c=-200)],
        "xyzac",
    ),
    "xyzbc-trt-kins": (
        {},
        {"x_rot_point": 3, "y_rot_point": -2, "z_rot_point": 5, "x_offset": 20, "tool_offset": 35},
        [Pose(10, 5, -20, b=-30, c=90), Pose(-50, 40, 7, b=45, c=300)],
        "xyzbc",
    ),
    "lineardeltakins": ({}, {}, [Pose(10, -20, 30), Pose(-60, 40, -100)], "xyz"),
    "rotarydeltakins": ({}, {}, [Pose(1, -2, -15), Pose(-3, 2.5, -18)], "xyz"),
    "5axiskins": ({}, {}, [Pose(10, 20, 30, b=30, c=60, w=5)], "xyzbcw"),
    # (LinuxCNC's maxkins does not invert with U or V and a turned C)
    "maxkins": (
        {},
        {},
        [Pose(1, 2, 3, b=30, w=0.5, v=0.1), Pose(1, 2, 3, c=40, w=0.5)],
        "xyzbcw",
    ),
    "pentakins": ({}, {}, [Pose(10, -20, 5, a=3, b=-4)], "xyzab"),
    "genhexkins": ({}, {}, [Pose(1, -2, 20, a=3, b=-4, c=5)], "xyzabc"),
    "pumakins": ({}, {}, [Pose(300, 200, 100, 10, 20, 30)], "xyzabc"),
    "scarakins": ({}, {}, [Pose(400, 200, 300, 1, 2, 30)], "xyzabc"),
    "rosekins": ({}, {}, [Pose(10, 20, 3), Pose(-10, -1, 4)], "xyz"),
    "rotatekins": ({}, {}, [Pose(10, 20, 3, 1, 2, 33, 4, 5, 6)], AXIS_NAMES),
    "tripodkins": ({}, {}, [Pose(0.3, 0.4, 2), Pose(0.3, 0.4, -2)], "xyz"),
    "scorbot-kins": ({}, {}, [Pose(300, 100, 200, 10, 20)], "xyzab"),
    "trivkins": ({"coordinates": "xyyz"}, {}, [Pose(1, 2, 3)], "xyz"),
}


@pytest.mark.parametrize("name", list(ROUND_TRIPS))
def test_forward_of_inverse_is_the_pose(name: str) -> None:
    params, pins, poses, letters = ROUND_TRIPS[name]
    kins = load_kinematics(name, **params)
    for pin_name, value in pins.items():
        setattr(own(kins).pins, pin_name, value)
    for pose in poses:
        joints = kins.inverse(pose)
        assert len(joints) >= len(set(letters) - set("uvw")) and all(map(math.isfinite, joints))
        assert_pose(kins.forward(joints), pose, letters, tol=1e-6)


def orientation(pose: Pose) -> np.ndarray:
    """The rotation matrix of a pose's roll, pitch and yaw (A B C): angles that differ by
    a turn, or at gimbal lock, are the same orientation."""
    return np.array(rpy_matrix(*(math.radians(v) for v in (pose.a, pose.b, pose.c))))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-60, 60), min_size=6, max_size=6))
def test_genserkins_inverse_of_forward_from_nearby_joints(joints: list[float]) -> None:
    """Inverse kinematics iterates from the last joints (here 2 degrees away) back to them."""
    kins = own(load_kinematics("genserkins"))
    pose = kins.forward(joints)
    kins.estimate = [j + 2.0 for j in joints]
    try:
        back = kins.inverse(pose)
    except KinematicsError:  # near a singular arm pose the Jacobian cannot be inverted
        return
    again = kins.forward(back)
    assert_pose(again, pose, "xyz", tol=1e-4)
    assert orientation(again) == pytest.approx(orientation(pose), abs=1e-6)


# --------------------------------------------------------------- known poses
@settings(max_examples=50, deadline=None)
@given(
    st.tuples(st.floats(-100, 100), st.floats(-100, 100), st.floats(-100, 100)),
    st.floats(-90, 90),
    st.floats(-360, 360),
)
def test_xyzac_trt_is_a_tilting_table_carrying_a_rotary_table(point, a: float, c: float) -> None:
    """The work point p sits on table C (turned by c about Z through the rotation point r),
    carried by table A (tilted by a about X through r + offsets d): the machine must put
    Rx(a)(Rz(c)(p - r) - d) + d + r under the tool (its length moves d along Z)."""
    kins = load_kinematics("xyzac-trt-kins")
    pins = own(kins).pins
    pins.x_rot_point, pins.y_rot_point, pins.z_rot_point = 3.0, -2.0, 5.0
    pins.y_offset, pins.z_offset, pins.tool_offset = 20.0, 10.0, 35.0
    r, d = np.array([3.0, -2.0, 5.0]), np.array([0.0, 20.0, 45.0])
    p = np.array(point)
    expected = rx(a) @ (rz(c) @ (p - r) - d) + d + r
    joints = kins.inverse(Pose(*point, a=a, c=c))
    assert joints == pytest.approx([*expected, a, c], abs=1e-9)


@settings(max_examples=50, deadline=None)
@given(
    st.tuples(st.floats(-100, 100), st.floats(-100, 100), st.floats(-100, 100)),
    st.floats(-90, 90),
    st.floats(-360, 360),
)
def test_xyzbc_trt_is_a_tilting_table_carrying_a_rotary_table(point, b: float, c: float) -> None:
    kins = load_kinematics("xyzbc-trt-kins")
    pins = own(kins).pins
    pins.x_rot_point, pins.y_rot_point, pins.z_rot_point = 3.0, -2.0, 5.0
    pins.x_offset, pins.z_offset, pins.tool_offset = 20.0, 10.0, 35.0
    r, d = np.array([3.0, -2.0, 5.0]), np.array([20.0, 0.0, 45.0])
    expected = ry(b) @ (rz(c) @ (np.array(point) - r) - d) + d + r
    joints = kins.inverse(Pose(*point, b=b, c=c))
    assert joints == pytest.approx([*expected, b, c], abs=1e-9)


def test_trt_coordinates_map_the_joints_and_pass_others_through() -> None:
    kins = load_kinematics("xyzac-trt-kins", coordinates="xyzacw")
    assert kins.num_joints == 6
    joints = kins.inverse(Pose(1, 2, 3, a=0, c=0, w=7))
    assert joints == pytest.approx([1, 2, 3, 0, 0, 7])
    with pytest.raises(KinematicsError, match="required coordinates xyzac"):
        load_kinematics("xyzac-trt-kins", coordinates="xyzab")


@pytest.mark.parametrize("pose", [Pose(0, 0, -50), Pose(30, -40, -120), Pose(-70, 0, 10)])
def test_lineardelta_rods_keep_their_length(pose: Pose) -> None:
    """Each carriage (on a tower at 120 degree steps on radius R, the first on +Y) is one rod
    length L from the effector."""
    kins = load_kinematics("lineardeltakins")
    kins.pins.R, kins.pins.L = 150.0, 280.0
    heights = kins.inverse(pose)[:3]
    for tower, height in enumerate(heights):
        angle = math.radians(90 + 120 * tower)
        carriage = np.array([150 * math.cos(angle), 150 * math.sin(angle), height])
        rod = np.linalg.norm(carriage - np.array([pose.x, pose.y, pose.z]))
        assert rod == pytest.approx(280.0, abs=1e-9)


@pytest.mark.parametrize("joints", [[0, 0, 0], [10, 30, -20], [45, 45, 45]])
def test_rotarydelta_shins_keep_their_length(joints: list[float]) -> None:
    """Hips on a circle at 120 degree steps (the first towards -Y), thighs turning down by
    the joint angle; each knee is one shin length from its foot on the effector."""
    kins = load_kinematics("rotarydeltakins")
    p = kins.pins
    pose = kins.forward(joints)
    effector = np.array([pose.x, pose.y, pose.z])
    for hip, angle in enumerate(joints):
        towards = rz(120 * hip) @ np.array([0.0, -1.0, 0.0])
        knee = towards * (p.platformradius + p.thighlength * math.cos(math.radians(angle)))
        knee[2] = -p.thighlength * math.sin(math.radians(angle))
        foot = effector + towards * p.footradius
        assert np.linalg.norm(knee - foot) == pytest.approx(p.shinlength, abs=1e-9)


def test_genhexkins_struts_join_base_and_platform_points() -> None:
    kins = load_kinematics("genhexkins")
    pins = own(kins).pins
    pose = Pose(1, -2, 20, a=3, b=-4, c=5)
    struts = kins.inverse(pose)
    rot = np.array(rpy_matrix(*(math.radians(v) for v in (pose.a, pose.b, pose.c)))).T
    for i, length in enumerate(struts):
        base = np.array([pins.base_x[i], pins.base_y[i], pins.base_z[i]])
        platform = np.array([pins.platform_x[i], pins.platform_y[i], pins.platform_z[i]])
        joint = np.array([pose.x, pose.y, pose.z]) + rot @ platform
        assert np.linalg.norm(joint - base) == pytest.approx(length, abs=1e-9)


def test_tripod_struts_and_the_side_of_the_base() -> None:
    kins = load_kinematics("tripodkins")
    kins.pins.Bx, kins.pins.Cx, kins.pins.Cy = 10.0, 4.0, 8.0
    below = Pose(3, 2, -6)
    lengths = kins.inverse(below)
    for base, length in zip([(0, 0, 0), (10, 0, 0), (4, 8, 0)], lengths, strict=True):
        assert math.dist(base, (3, 2, -6)) == pytest.approx(length)
    assert kins.forward(lengths).z == pytest.approx(-6)  # the side inverse was on
    kins.inverse(Pose(3, 2, 6))
    assert kins.forward(lengths).z == pytest.approx(6)


def test_five_axis_heads_pivot_about_the_tool_tip() -> None:
    """5axiskins and maxkins: with the head tilted 90 degrees the tool lies along X, its tip
    one pivot length (plus W) out from the pivot, which sits a pivot length above the tip of
    an upright tool."""
    five = load_kinematics("5axiskins")
    pose = five.forward([0, 0, 0, 90, 0, 0])  # coordinates XYZBCW
    assert (pose.x, pose.y, pose.z) == pytest.approx((250, 0, 250), abs=1e-9)
    pose = five.forward([0, 0, 0, 0, 0, 10])
    assert (pose.x, pose.y, pose.z) == pytest.approx((0, 0, -10), abs=1e-9)
    maxk = load_kinematics("maxkins")
    pose = maxk.forward([0, 0, 0, 0, 90, 0, 0, 0, 0.334])
    assert (pose.x, pose.z) == pytest.approx((1.0, 0.666), abs=1e-9)


def test_maxkins_table_rotation_turns_the_work_and_keeps_linuxcncs_quirks() -> None:
    kins = load_kinematics("maxkins")
    pose = kins.forward([10, 0, 0, 0, 0, 90, 0, 0, 0])
    assert (pose.x, pose.y) == pytest.approx((0, 10), abs=1e-9)
    # as LinuxCNC's: forward adds U sin(B) to Z where inverse should have taken it off
    back = kins.forward(kins.inverse(Pose(1, 2, 3, b=30, u=0.2)))
    assert back.z == pytest.approx(3 + 2 * 0.2 * math.sin(math.radians(30)))


def test_genserkins_default_arm_and_pumakins_agree() -> None:
    """Two formulations of one arm: genserkins' default links are a PUMA 560's, which
    pumakins computes in closed form (its tool length D6 set to 0). At zero joints the wrist
    is at (A2 + A3, D3, -D4) pointing down (roll 180)."""
    genser = load_kinematics("genserkins")
    puma = load_kinematics("pumakins")
    own(puma).pins.D6 = 0.0
    zero = genser.forward([0] * 9)
    assert (zero.x, zero.y, zero.z) == pytest.approx((350, 70, -400), abs=1e-9)
    assert abs(zero.a) == pytest.approx(180) and (zero.b, zero.c) == pytest.approx((0, 0))
    for joints in ([10, -20, 30, 40, -50, 60], [-30, 15, -45, 20, 35, -10]):
        g, p = genser.forward([*joints, 0, 0, 0]), puma.forward(joints)
        assert (g.x, g.y, g.z) == pytest.approx((p.x, p.y, p.z), abs=1e-9)
        assert orientation(g) == pytest.approx(orientation(p), abs=1e-9)


def test_genserkins_unrotate_and_iteration_pins() -> None:
    kins = own(load_kinematics("genserkins"))
    kins.pins.unrotate[2] = 1  # joint 2 turns with joint 1
    joints = [10, 20, 50, 0, 30, 0]
    pose = kins.forward(joints)
    plain = own(load_kinematics("genserkins")).forward([10, 20, 30, 0, 30, 0])
    assert_pose(pose, plain, "xyzabc", tol=1e-9)
    kins.estimate = [12, 22, 48, 2, 28, 2]
    assert kins.inverse(pose)[:6] == pytest.approx(joints, abs=1e-4)
    assert 1 <= kins.pins.last_iterations < 100
    kins.pins.max_iterations = 1
    kins.estimate = [12, 22, 48, 2, 28, 2]
    with pytest.raises(KinematicsError, match="did not converge in 1 iterations"):
        kins.inverse(pose)


def test_scara_puma_scorbot_known_poses() -> None:
    scara = load_kinematics("scarakins")
    pose = scara.forward([0, 0, 0, 0, 0, 0])  # arms straight out along X
    assert (pose.x, pose.y, pose.z) == pytest.approx((340 + 250 + 50, 0, 490 + 50 - 50))
    pose = scara.forward([90, 0, 10, 0, 0, 0])
    assert (pose.x, pose.y, pose.z, pose.c) == pytest.approx((0, 640, 480, 90), abs=1e-9)
    scorbot = load_kinematics("scorbot-kins")
    pose = scorbot.forward([0, 0, 0, 1, 2])  # both arms horizontal
    assert (pose.x, pose.y, pose.z, pose.a, pose.b) == pytest.approx((458, 0, 140, 1, 2))
    pose = scorbot.forward([90, 90, 0, 0, 0])  # upper arm up, forearm out along +Y
    assert (pose.x, pose.y, pose.z) == pytest.approx((0, 16 + 221, 140 + 221), abs=1e-9)
    with pytest.raises(KinematicsError, match="out of the arm's reach"):
        scorbot.inverse(Pose(1000, 0, 0))


def test_rosekins_counts_turns_across_minus_x() -> None:
    kins = load_kinematics("rosekins")
    angles = [kins.inverse(Pose(math.cos(t), math.sin(t), 0))[2] for t in (3.0, 3.3, 3.6)]
    assert angles[1] > angles[0] and angles[2] > angles[1]  # keeps turning the same way
    assert angles[1] == pytest.approx(math.degrees(3.3))
    assert kins.pins.revolutions == 1


# --------------------------------------------------------------- switching
def test_switchkins_types_and_pins() -> None:
    kins = load_kinematics("xyzac-trt-kins")
    pins = kins.type_pins
    own(kins).pins.z_offset = 10.0
    assert (pins.is_0, pins.is_1, pins.is_2) == (True, False, False)
    tilted = Pose(10, 0, 0, a=90)
    assert kins.inverse(tilted) != pytest.approx([10, 0, 0, 90, 0])
    kins.switch(1)  # identity
    assert (pins.is_0, pins.is_1, pins.is_2) == (False, True, False)
    assert kins.inverse(tilted) == pytest.approx([10, 0, 0, 90, 0])
    kins.switch(2)  # the user type: identity counting its calls
    kins.forward([0] * 5)
    kins.inverse(tilted)
    assert kins.types[2].pins.fct == 1 and kins.types[2].pins.ict == 1
    with pytest.raises(KinematicsError, match="bad kinstype 3"):
        kins.switch(3)
    assert (pins.is_0, pins.is_1, pins.is_2) == (False, False, False)


def test_identityfirst_swaps_the_first_two_types() -> None:
    kins = load_kinematics("xyzac-trt-kins", sparm="identityfirst")
    kins.types[1].pins.z_offset = 10.0
    tilted = Pose(10, 0, 0, a=90)
    assert kins.inverse(tilted) == pytest.approx([10, 0, 0, 90, 0])
    kins.switch(1)
    assert kins.inverse(tilted) != pytest.approx([10, 0, 0, 90, 0])


def test_millturn_lathe_type_maps_xyz_to_joints() -> None:
    kins = load_kinematics("millturn")
    assert kins.inverse(Pose(1, 2, 3, 4)) == pytest.approx([1, 2, 3, 4])
    kins.switch(1)
    assert kins.forward([3, -2, 1, 4]) == Pose(1, 2, 3, 4)  # X = j2, Y = -j1, Z = j0
    assert kins.inverse(Pose(1, 2, 3, 4)) == pytest.approx([3, -2, 1, 4])


# --------------------------------------------------------------- joint counts
def test_bare_trivkins_seen_through_fewer_joints() -> None:
    """``loadrt trivkins`` maps nine joints; motion with num_joints=3 is an XYZ machine."""
    kins = fit_joints(load_kinematics("trivkins"), 3)
    assert kins.num_joints == 3 and kins.axis_mask == 0b111
    assert kins.inverse(Pose(1, 2, 3, 4)) == [1, 2, 3]
    assert kins.forward([1, 2, 3]) == Pose(1, 2, 3)
    pose, joints = kins.home(Pose(), [4, 5, 6])
    assert joints == [4, 5, 6] and pose == Pose(4, 5, 6)


# --------------------------------------------------------------- realtime hygiene
def test_transformations_leave_no_cycles(collector_off) -> None:
    """Motion calls them every servo period in a host without a garbage collector
    (tests/motion/test_rt_garbage.py): they must leave no reference cycles behind."""
    modules = [(name, *ROUND_TRIPS[name][::2]) for name in ROUND_TRIPS]
    modules += [(name, {}, [Pose(300, 50, -300)]) for name in ("genserkins", "millturn")]
    made = [(load_kinematics(name, **params), poses) for name, params, poses in modules]
    gc.collect()
    for kins, poses in made:
        for _ in range(10):
            for pose in poses:
                with contextlib.suppress(KinematicsError):  # (a singular pose: as well)
                    kins.forward(kins.inverse(pose))
    assert gc.collect() == 0
