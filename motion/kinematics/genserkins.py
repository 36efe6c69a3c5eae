"""genserkins: a general serial arm of six revolute joints (degrees), each link described
by its modified (Craig) Denavit-Hartenberg parameters on pins ``genserkins.A-N``,
``ALPHA-N`` (radians) and ``D-N`` for N = 0..5 (defaults: a PUMA-like arm). A B C are the
tool's roll, pitch and yaw; joints 6-8 pass through to U V W.

``genserkins.unrotate-N`` (N >= 1) takes that many times joint N-1's angle off joint N, for
arms whose joint N turns with joint N-1 (forward subtracts the already corrected angle,
inverse adds the resulting joint, as LinuxCNC does).

Inverse kinematics iterates from the last joint positions: Newton steps through the
inverse Jacobian until every joint step is below 1e-7 radians, at most
``genserkins.max-iterations`` (100) times; ``last-iterations`` shows how many it took.
Switchable: type 0 genser, 1 identity (``coordinates=``, default ``xyzabcuvw``), 2 the user
type; ``sparm=identityfirst`` swaps types 0 and 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from hal.api import RtComponent, pin
from motion.kinematics import (
    TO_DEG,
    TO_RAD,
    HalContext,
    KinematicsError,
    SwitchKins,
    check_pose,
    make_pins,
    realtime_module,
    switchable,
)
from motion.kinematics._rotation import rpy_matrix
from nml.pose import Pose

LINKS = 6
REQUIRED = "xyzabcuvw"
EPSILON = 1e-7  # gomath's GO_REAL_EPSILON: a joint step this small has converged
DEFAULT_A = (0.0, 0.0, 300.0, 50.0, 0.0, 0.0)
DEFAULT_ALPHA = (0.0, -math.pi / 2, 0.0, -math.pi / 2, math.pi / 2, -math.pi / 2)
DEFAULT_D = (0.0, 0.0, 70.0, 400.0, 0.0, 0.0)


class GenserPins(RtComponent):
    A = pin("float in", "A-{}", count=LINKS)
    ALPHA = pin("float in", "ALPHA-{}", count=LINKS)
    D = pin("float in", "D-{}", count=LINKS)
    unrotate = pin("s32 in", "unrotate-{}", count=LINKS)
    last_iterations = pin("u32 out")
    max_iterations = pin("u32 in", default=100)


def dh_transform(a: float, alpha: float, d: float, theta: float) -> np.ndarray:
    """One link's 4x4 transform in Craig's modified convention: Rx(alpha) Tx(a) Rz(theta)
    Tz(d)."""
    st, ct = math.sin(theta), math.cos(theta)
    sa, ca = math.sin(alpha), math.cos(alpha)
    return np.array(
        [
            [ct, -st, 0.0, a],
            [st * ca, ct * ca, -sa, -sa * d],
            [st * sa, ct * sa, ca, ca * d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def rpy_of(rot: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a rotation matrix (rows x columns) as gomath converts it: at a
    pitch of +90 degrees (within 1e-7) yaw is 0; -90 degrees has no special case there."""
    pitch = math.atan2(-rot[2, 0], math.hypot(rot[0, 0], rot[1, 0]))
    if abs(pitch - math.pi / 2) < EPSILON:
        return math.atan2(rot[0, 1], rot[1, 1]), math.pi / 2, 0.0
    return math.atan2(rot[2, 1], rot[2, 2]), pitch, math.atan2(rot[1, 0], rot[0, 0])


def rotation_vector(rot: np.ndarray) -> np.ndarray:
    """The rotation vector (axis times angle, angle in [0, pi]) of a rotation matrix."""
    trace = rot[0, 0] + rot[1, 1] + rot[2, 2]
    # the unit quaternion (s, v) with s >= 0, from its largest component for accuracy
    if trace > 0:
        s = 0.5 * math.sqrt(1.0 + trace)
        v = np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]])
        v /= 4 * s
    else:
        i = int(np.argmax(np.diag(rot)))
        j, k = (i + 1) % 3, (i + 2) % 3
        vi = 0.5 * math.sqrt(max(1.0 + rot[i, i] - rot[j, j] - rot[k, k], 0.0))
        v = np.zeros(3)
        v[i] = vi
        v[j] = (rot[j, i] + rot[i, j]) / (4 * vi)
        v[k] = (rot[k, i] + rot[i, k]) / (4 * vi)
        s = (rot[k, j] - rot[j, k]) / (4 * vi)
        if s < 0:
            s, v = -s, -v
    sine = float(np.linalg.norm(v))
    if sine < EPSILON:
        return np.zeros(3)
    return v * (2 * math.atan2(sine, s) / sine)


class Genser:
    def __init__(self, pins: Any) -> None:
        self.pins = pins
        for i in range(LINKS):
            pins.A[i], pins.ALPHA[i], pins.D[i] = DEFAULT_A[i], DEFAULT_ALPHA[i], DEFAULT_D[i]
        # the joints inverse kinematics starts from: LinuxCNC's motion hands over the
        # current joint positions; here, those of the last forward or inverse result
        self.estimate = [0.0] * LINKS

    def frames(self, angles: Sequence[float]) -> list[np.ndarray]:
        """The base-frame transform of each link's frame, for joint angles in radians."""
        p = self.pins
        frames, pose = [], np.eye(4)
        for i in range(LINKS):
            pose = pose @ dh_transform(p.A[i], p.ALPHA[i], p.D[i], angles[i])
            frames.append(pose)
        return frames

    def forward(self, joints: Sequence[float]) -> Pose:
        unrotate = self.pins.unrotate
        angles: list[float] = []
        for i in range(LINKS):
            angle = joints[i] * TO_RAD
            if i and unrotate[i]:
                angle -= unrotate[i] * angles[i - 1]
            angles.append(angle)
        self.estimate = [float(j) for j in joints[:LINKS]]
        tool = self.frames(angles)[-1]
        roll, pitch, yaw = rpy_of(tool[:3, :3])
        extra = [*joints[LINKS:9], 0.0, 0.0, 0.0][:3]
        x, y, z = (float(v) for v in tool[:3, 3])
        return Pose(x, y, z, roll * TO_DEG, pitch * TO_DEG, yaw * TO_DEG, *map(float, extra))

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        p = self.pins
        target_rot = np.array(rpy_matrix(pose.a * TO_RAD, pose.b * TO_RAD, pose.c * TO_RAD)).T
        target_pos = np.array([pose.x, pose.y, pose.z])
        estimate = np.array(self.estimate) * TO_RAD
        for iteration in range(p.max_iterations):
            p.last_iterations = iteration
            frames = self.frames(estimate)
            screw = self.error(frames[-1], target_pos, target_rot)
            try:
                step = np.linalg.solve(self.jacobian(frames), screw)
            except np.linalg.LinAlgError:
                raise KinematicsError("genserkins: singular Jacobian") from None
            if np.all(np.abs(step) < EPSILON):
                joints = [float(a) * TO_DEG for a in estimate]
                for i in range(1, LINKS):
                    if p.unrotate[i]:
                        joints[i] += p.unrotate[i] * joints[i - 1]
                self.estimate = joints
                return [*joints, pose.u, pose.v, pose.w]
            estimate = estimate + step
        raise KinematicsError(
            f"genserkins: inverse kinematics did not converge in {p.max_iterations} iterations"
        )

    @staticmethod
    def jacobian(frames: list[np.ndarray]) -> np.ndarray:
        """The 6x6 geometric Jacobian (linear velocity of the tool's origin over angular
        velocity, base frame) of six revolute joints turning about their frames' Z axes."""
        tip = frames[-1][:3, 3]
        columns = []
        for frame in frames:
            axis = frame[:3, 2]
            columns.append(np.concatenate((np.cross(axis, tip - frame[:3, 3]), axis)))
        return np.array(columns).T

    @staticmethod
    def error(tool: np.ndarray, position: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """The screw from the tool's pose to the target's, in the base frame."""
        here = tool[:3, :3]
        turn = here @ rotation_vector(here.T @ rot)
        return np.concatenate((position - tool[:3, 3], turn))


def create(coordinates: str = "", sparm: str = "", hal: HalContext | None = None) -> SwitchKins:
    own = Genser(make_pins(GenserPins, hal, "genserkins"))
    return switchable("genserkins", own, REQUIRED, coordinates, sparm, hal)


rtapi_app_main: Any = realtime_module(create)
