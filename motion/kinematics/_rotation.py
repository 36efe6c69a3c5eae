"""Rotation matrices and roll-pitch-yaw angles as LinuxCNC's posemath defines them, for
the robot kinematics. A matrix is three columns ``(x, y, z)`` of three numbers each
(``m[0][2]`` is posemath's ``m.x.z``); R = Rz(yaw) Ry(pitch) Rx(roll)."""

from __future__ import annotations

import math

Matrix = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]
PITCH_FUZZ = 1.0e-6  # posemath's RPY_P_FUZZ


def rpy_matrix(roll: float, pitch: float, yaw: float) -> Matrix:
    sa, sb, sg = math.sin(yaw), math.sin(pitch), math.sin(roll)
    ca, cb, cg = math.cos(yaw), math.cos(pitch), math.cos(roll)
    return (
        (ca * cb, sa * cb, -sb),
        (ca * sb * sg - sa * cg, sa * sb * sg + ca * cg, cb * sg),
        (ca * sb * cg + sa * sg, sa * sb * cg - ca * sg, cb * cg),
    )


def matrix_rpy(m: Matrix) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a rotation matrix; at pitch +-90 degrees yaw is 0."""
    pitch = math.atan2(-m[0][2], math.sqrt(m[0][0] ** 2 + m[0][1] ** 2))
    if abs(pitch - math.pi / 2) < PITCH_FUZZ:
        return math.atan2(m[1][0], m[1][1]), math.pi / 2, 0.0
    if abs(pitch + math.pi / 2) < PITCH_FUZZ:
        return -math.atan2(m[1][0], m[1][1]), -math.pi / 2, 0.0
    return math.atan2(m[1][2], m[2][2]), pitch, math.atan2(m[0][1], m[0][0])
