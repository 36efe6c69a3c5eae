"""Forward kinematics of parallel machines (hexapods, pentapods) by Newton-Raphson, as
LinuxCNC's genhexkins and pentakins do it: start from the last pose, compare the strut
lengths its inverse kinematics gives with the joints, and correct the pose through the
numerically differentiated inverse kinematics until every strut is within the
convergence criterion."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from motion.kinematics import SingularityError

STEP = 1e-4  # the pose change that differentiates the inverse kinematics


def solve_forward(
    inverse: Callable[[Sequence[float]], list[float]],
    joints: Sequence[float],
    start: Sequence[float],
    *,
    max_error: float,
    criterion: float,
    iteration_limit: int,
    name: str,
) -> tuple[list[float], int]:
    """(the pose coordinates whose struts are ``joints``, iterations it took)."""
    coord = np.array(start, dtype=float)
    wanted = np.array(joints[: len(coord)], dtype=float)
    size = len(coord)
    error_sum = 1.0
    iteration = 0
    while True:
        if not -max_error <= error_sum <= max_error:
            raise SingularityError(f"{name}: forward kinematics does not converge")
        iteration += 1
        if iteration > iteration_limit:
            raise SingularityError(f"{name}: forward kinematics took too many iterations")
        lengths = np.array(inverse(coord))
        difference = lengths - wanted
        jacobian = np.empty((size, size))  # d(strut lengths) / d(pose)
        for i in range(size):
            moved = coord.copy()
            moved[i] += STEP
            jacobian[:, i] = (np.array(inverse(moved)) - lengths) / STEP
        try:
            coord -= np.linalg.solve(jacobian, difference)
        except np.linalg.LinAlgError:
            raise SingularityError(f"{name}: singular position") from None
        error_sum = float(np.abs(difference).sum())
        if not np.any(np.abs(difference) > criterion):
            return coord.tolist(), iteration
