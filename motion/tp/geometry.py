"""Path pieces of the coordinated planner: straight lines and circular/helical arcs in the
nine-axis space X Y Z A B C U V W.

Every piece is parametrised by its path length ``s`` in ``[0, length]``. For the per-axis
limits each piece knows two bounds over its whole length (``axis_bounds``):

- ``T[i] >= |dp_i/ds|``: axis speed is at most ``v * T[i]``;
- ``N[i] >= |d2p_i/ds2|``: axis acceleration is at most ``a_t * T[i] + v**2 * N[i]``.

From them the planner derives a speed cap and a tangential acceleration that keep every
axis inside its velocity and acceleration limits at every point of the piece.

Queueing a move builds its pieces, so the per-move work here uses plain floats (lists from
``tolist()`` and ``math``) wherever numpy's per-call overhead would dominate nine-element
arithmetic; the vectors a piece keeps stay numpy arrays.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from operator import mul

import numpy as np

from nml.axes import NUM_AXES

XYZ = slice(0, 3)
ABC = slice(3, 6)
UVW = slice(6, 9)
EPS = 1e-9


def path_length(delta: np.ndarray) -> float:
    """LinuxCNC's rule for a move's length: XYZ if they move, else UVW, else ABC."""
    x, y, z, a, b, c, u, v, w = delta.tolist()
    length = math.hypot(x, y, z)
    if length > EPS:
        return length
    length = math.hypot(u, v, w)
    if length > EPS:
        return length
    length = math.hypot(a, b, c)
    return length if length > EPS else 0.0


def flat_normal_share(normal_fraction: float) -> float:
    """The centripetal share of the acceleration budget on a flat circle.

    On a flat circle the tangential and centripetal accelerations turn together in the
    plane, so on every axis they add up in quadrature, not linearly: exactly,
    |a_i| <= sqrt(a_t**2 + a_n**2) * (the axis's share of the plane). Keeping the
    tangential share that the linear rule leaves at the speed cap (1 - ``normal_fraction``),
    the centripetal part may take sqrt(1 - (1 - normal_fraction)**2) of the budget: 0.866
    for 0.5, LinuxCNC's split for its blend arcs."""
    return math.sqrt(1.0 - (1.0 - normal_fraction) ** 2)


def norm(v: np.ndarray) -> float:
    """Euclidean length: what np.linalg.norm computes for a vector, without its
    Python-level overhead (several microseconds for a few values)."""
    return math.sqrt(v.dot(v))


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of two 3-vectors: np.cross's arithmetic, on plain floats (np.cross
    costs about ten microseconds)."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


class Piece:
    """Common state of a path piece; see ``LinePiece`` and ``ArcPiece``."""

    __slots__ = (
        "acc",
        "acc_head",
        "acc_tail",
        "exit_max",
        "is_kink_end",
        "length",
        "move",
        "s0",
        "v_body",
        "v_exit",
        "v_mid",
        "vcap",
        "vplan",
        "window",
    )

    def __init__(self, move: object, length: float) -> None:
        self.move = move
        self.length = length
        self.s0 = 0.0  # cumulative path position of the piece's start
        self.vcap = 0.0  # speed cap from axis and move limits
        self.vplan = 0.0  # speed the lookahead plans with (cap and highest feed)
        self.acc = 0.0  # tangential acceleration available everywhere on the piece
        self.exit_max = 0.0  # highest speed allowed at the junction with the next piece
        self.v_exit = 0.0  # planned exit speed (lookahead result)
        # A servo period that crosses from one piece into another can only use the lower
        # of their accelerations. ``window`` is what one period can travel; the first and
        # last ``window`` of the piece are planned with the lowest acceleration of the
        # pieces a period may touch there (``acc_head``/``acc_tail``, set by the planner).
        # These zones, head, body (at ``acc``) and tail, are what the planner's backward
        # pass and braking curves use; a piece shorter than two windows is all tail, at
        # the lowest of the three accelerations.
        self.window = 0.0
        self.acc_head = self.acc_tail = 0.0
        self.v_mid = 0.0  # planned speed where the tail zone begins
        self.v_body = 0.0  # planned speed where the head zone ends
        self.is_kink_end = False  # passes an unblended, nearly tangent joint at speed

    def apply_limits(
        self,
        max_acc: Sequence[float],
        inv_vel: Sequence[float],
        inv_acc: Sequence[float],
        move_vel: float,
        move_acc: float,
        normal_fraction: float,
    ) -> None:
        """Set ``vcap`` and ``acc`` from the axis limits (see the module docstring);
        ``inv_vel``/``inv_acc`` are the reciprocals of the axis limits (nine floats each).

        At most ``normal_fraction`` of the acceleration budget goes to the centripetal part;
        what the cap leaves unused is given to the tangential part."""
        t, n = self.axis_bounds()
        vcap = move_vel
        worst = max(map(mul, t, inv_vel))
        if worst > 0:
            vcap = min(vcap, 1.0 / worst)
        worst = max(map(mul, n, inv_acc)) if n is not None else 0.0
        if worst > 0:
            vcap = min(vcap, math.sqrt(normal_fraction / worst))
            v2 = vcap * vcap
            acc = move_acc
            for t_i, n_i, max_acc_i in zip(t, n, max_acc, strict=True):
                if t_i > EPS:
                    axis_acc = (max_acc_i - v2 * n_i) / t_i
                    if axis_acc < acc:  # (as min(), without a call per axis)
                        acc = axis_acc
        else:
            worst = max(map(mul, t, inv_acc))
            acc = min(move_acc, 1.0 / worst) if worst > 0 else move_acc
        self.vcap = max(vcap, 0.0)
        self.acc = self.acc_head = self.acc_tail = max(acc, EPS)

    def point(self, s: float) -> np.ndarray:
        raise NotImplementedError

    def tangent(self, s: float) -> np.ndarray:
        raise NotImplementedError

    def axis_bounds(self) -> tuple[list[float], list[float] | None]:
        """``T`` and ``N`` per axis (see the module docstring); ``N`` None: straight."""
        raise NotImplementedError


class LinePiece(Piece):
    __slots__ = ("_end", "_is_single", "direction", "full_length", "start")

    def __init__(self, move: object, start: np.ndarray, end: np.ndarray) -> None:
        delta = end - start
        length = path_length(delta)
        super().__init__(move, length)
        self.start = start.copy()
        self.direction = delta / length if length > 0 else np.zeros(NUM_AXES)
        self.full_length = length  # before blends trimmed it
        self._end: np.ndarray | None = None  # ``end``, computed once until a trim
        self._is_single: bool | None = None  # ``is_single_group``, computed once

    @property
    def end(self) -> np.ndarray:
        """The end point (shared, not to be modified in place)."""
        if self._end is None:
            self._end = self.start + self.direction * self.length
        return self._end

    def is_xyz_only(self) -> bool:
        return max(map(abs, self.direction[3:].tolist())) <= EPS

    def is_single_group(self) -> bool:
        """True when the path length is the full 9-D length (only one axis group moves),
        which is when a tangent blend arc in 9-D keeps the feed meaning intact."""
        if self._is_single is None:  # (asked twice per blended line: as new piece, as tail)
            # (ndarray.dot: the same sum as ``@``, at half the cost)
            self._is_single = abs(float(self.direction.dot(self.direction)) - 1.0) < 1e-9
        return self._is_single

    def point(self, s: float) -> np.ndarray:
        return self.start + self.direction * s

    def tangent(self, s: float) -> np.ndarray:
        return self.direction

    def axis_bounds(self) -> tuple[list[float], list[float] | None]:
        return list(map(abs, self.direction.tolist())), None

    def trim_start(self, d: float) -> None:
        self.start = self.start + self.direction * d
        self.length -= d
        self._end = None

    def trim_end(self, d: float) -> None:
        self.length -= d
        self._end = None


class ArcPiece(Piece):
    """p(phi) = centre + r(phi) (cos(phi) e1 + sin(phi) e2) + h phi, r(phi) = r0 + dr phi,
    with phi = s * k. ``e1``/``e2`` are orthonormal 9-D vectors; ``h`` carries the helix
    (motion along the normal) and the linear motion of the other axes, per radian."""

    __slots__ = ("centre", "dr", "e1", "e2", "full_length", "h", "has_h", "k", "r0", "theta")

    @property
    def is_flat(self) -> bool:
        """A circle (no spiral, no helix or other axes moving along): see apply_limits."""
        return not self.has_h and abs(self.dr) <= EPS

    def __init__(
        self,
        move: object,
        centre: np.ndarray,
        e1: np.ndarray,
        e2: np.ndarray,
        r0: float,
        r1: float,
        theta: float,
        h: np.ndarray,
    ) -> None:
        dr = (r1 - r0) / theta
        radial = math.hypot(0.5 * (r0 + r1), dr)  # mean radius and spiral, per radian
        # length by the XYZ (else UVW, else ABC) rule applied to the tangent magnitude
        e1_list, h_list = e1.tolist(), h.tolist()
        per_radian = 0.0
        for g in (XYZ, UVW, ABC):
            per_radian = math.hypot(radial * math.hypot(*e1_list[g]), *h_list[g])
            if per_radian > EPS:
                break
        super().__init__(move, per_radian * theta)
        self.centre, self.e1, self.e2, self.h = centre, e1, e2, h
        self.has_h = any(h_list)  # a helix, or other axes moving along
        self.r0, self.dr, self.theta = r0, dr, theta
        self.k = theta / self.length if self.length > 0 else 0.0
        self.full_length = self.length  # before blends trimmed it

    def point(self, s: float) -> np.ndarray:
        phi = s * self.k
        r = self.r0 + self.dr * phi
        # (this runs every servo period: the sums go in place, and a zero h is not added)
        p = self.centre + (r * math.cos(phi)) * self.e1
        p += (r * math.sin(phi)) * self.e2
        if self.has_h:
            p += self.h * phi
        return p

    def tangent(self, s: float) -> np.ndarray:
        phi = s * self.k
        r = self.r0 + self.dr * phi
        c, sn = math.cos(phi), math.sin(phi)
        dp = self.dr * (c * self.e1 + sn * self.e2) + r * (c * self.e2 - sn * self.e1) + self.h
        return dp * self.k

    def plane_normal(self) -> np.ndarray | None:
        """The XYZ normal of a flat circle in XYZ only (no spiral, helix or other axes),
        the arcs a corner blend may cut into; None for any other arc."""
        if abs(self.dr) > EPS or max(map(abs, self.h.tolist())) > EPS:
            return None
        if max(map(abs, self.e1[3:].tolist() + self.e2[3:].tolist())) > EPS:
            return None
        return cross3(self.e1[XYZ], self.e2[XYZ])

    def trim_start(self, d: float) -> None:
        """Start ``d`` further along (the end stays where it is)."""
        phi = d * self.k
        c, sn = math.cos(phi), math.sin(phi)
        self.centre = self.centre + self.h * phi
        self.e1, self.e2 = c * self.e1 + sn * self.e2, c * self.e2 - sn * self.e1
        self.r0 += self.dr * phi
        self.theta -= phi
        self.length -= d

    def trim_end(self, d: float) -> None:
        self.theta -= d * self.k
        self.length -= d

    def apply_limits(
        self,
        max_acc: Sequence[float],
        inv_vel: Sequence[float],
        inv_acc: Sequence[float],
        move_vel: float,
        move_acc: float,
        normal_fraction: float,
    ) -> None:
        """As ``Piece.apply_limits``; on a flat circle with the exact, quadrature bound of
        ``flat_normal_share`` instead of the linear sum of ``axis_bounds`` (which holds for
        spirals and helices too, but overstates a circle's axis accelerations up to 1.41x)."""
        if not self.is_flat:
            super().apply_limits(max_acc, inv_vel, inv_acc, move_vel, move_acc, normal_fraction)
            return
        # per unit of path: axis i moves at v * (r k) * plane_i; its acceleration is at most
        # sqrt(a_t**2 + (v**2 k)**2) * (r k) * plane_i
        rk = self.r0 * self.k
        plane = list(map(math.hypot, self.e1.tolist(), self.e2.tolist()))
        vcap = move_vel
        worst = rk * max(map(mul, plane, inv_vel))
        if worst > 0:
            vcap = min(vcap, 1.0 / worst)
        worst = rk * max(map(mul, plane, inv_acc))
        acc = move_acc
        if worst > 0 and self.k > 0:
            reach = 1.0 / worst  # the largest sqrt(a_t**2 + a_n**2) every axis allows
            share = flat_normal_share(normal_fraction)
            vcap = min(vcap, math.sqrt(share * reach / self.k))
            normal = vcap * vcap * self.k
            acc = min(acc, math.sqrt(max(reach * reach - normal * normal, 0.0)))
        self.vcap = max(vcap, 0.0)
        self.acc = self.acc_head = self.acc_tail = max(acc, EPS)

    def axis_bounds(self) -> tuple[list[float], list[float] | None]:
        rmax = max(self.r0, self.r0 + self.dr * self.theta)
        k, dr = self.k, abs(self.dr)
        plane = list(map(math.hypot, self.e1.tolist(), self.e2.tolist()))
        t_plane, n_plane = (dr + rmax) * k, (2 * dr + rmax) * k * k
        if self.has_h:
            h = self.h.tolist()
            t = [t_plane * p + abs(h_i) * k for p, h_i in zip(plane, h, strict=True)]
        else:
            t = [t_plane * p for p in plane]
        return t, [n_plane * p for p in plane]


def circle_piece(
    move: object,
    start: np.ndarray,
    end: np.ndarray,
    centre: np.ndarray,
    normal: np.ndarray,
    turns: int,
) -> ArcPiece:
    """The arc of an EMC_TRAJ_CIRCULAR_MOVE: centre and normal in XYZ, counter-clockwise
    about the normal, ``turns`` extra full turns; the other axes move linearly."""
    nrm = norm(normal)
    if not nrm > EPS:
        raise ValueError("circle normal vector is zero")
    nhat = normal / nrm
    rel0 = start[XYZ] - centre
    rel1 = end[XYZ] - centre
    axial0 = float(rel0.dot(nhat))  # (ndarray.dot: the same sum as ``@``, cheaper)
    axial1 = float(rel1.dot(nhat))
    p0 = rel0 - axial0 * nhat
    p1 = rel1 - axial1 * nhat
    r0 = norm(p0)
    r1 = norm(p1)
    if r0 < 1e-7 or r1 < 1e-7:
        raise ValueError("circle start or end lies on the centre (zero radius)")
    e1x = p0 / r0
    e2x = cross3(nhat, e1x)
    angle = math.atan2(float(p1.dot(e2x)), float(p1.dot(e1x)))
    if angle <= 1e-12:
        angle += 2 * math.pi  # same start and end: one full turn, like LinuxCNC
    theta = angle + 2 * math.pi * int(turns)
    e1 = np.zeros(NUM_AXES)
    e2 = np.zeros(NUM_AXES)
    e1[XYZ], e2[XYZ] = e1x, e2x
    centre9 = start.copy()
    centre9[XYZ] = centre + axial0 * nhat
    h = (end - start) / theta
    h[XYZ] = (axial1 - axial0) * nhat / theta
    return ArcPiece(move, centre9, e1, e2, r0, r1, theta, h)


def blend_arc(
    move: object,
    corner: np.ndarray,
    u1: np.ndarray,
    u2: np.ndarray,
    radius: float,
    turn: float,
) -> ArcPiece:
    """The tangent arc of ``radius`` between a line arriving along ``u1`` and one leaving
    along ``u2`` at ``corner``, turning by ``turn`` radians."""
    d = radius * math.tan(0.5 * turn)
    # e1 points from the centre to the arc's start (away from the corner's inside), so
    # the centre lies ``radius`` back along it from the start. (Few numpy calls, two of
    # them in place: this runs for every blended corner.)
    e1 = math.cos(turn) * u1 - u2
    e1 /= math.hypot(*e1.tolist())
    centre = corner - u1 * d
    centre -= e1 * radius
    return ArcPiece(move, centre, e1, u1.copy(), radius, radius, turn, np.zeros(NUM_AXES))
