"""Cutter radius compensation G41/G42/G41.1/G42.1/G40 (TOOL-028/029), LinuxCNC's way.

The interpreter offsets the programmed path itself; no canon call turns compensation on.
Because a corner can only be resolved once the next move is known, compensated moves wait in
a queue (``self.qc``); other canon calls made with ``_enq`` queue behind them while it is not
empty. When the next move arrives, the end point of the queued move is moved to the corner
point and the queue is flushed. Work happens in the plane's own coordinates: XY as (x, y, z),
XZ as (z, x, y).

LinuxCNC does several of these angle steps in long double; ``ldmath`` repeats them.
"""

from __future__ import annotations

import math

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from . import ldmath
from .block import G_0, G_1, G_2, G_3, Block
from .errors import InterpError

RIGHT, LEFT = 1, 2
TOLERANCE_EQUAL = 0.0001
TOLERANCE_CONCAVE_CORNER = 0.05
RADIUS_TOLERANCE_INCH = 0.00005
RADIUS_TOLERANCE_MM = RADIUS_TOLERANCE_INCH * 25.4
SPIRAL_RELATIVE_TOLERANCE = 0.001
MODE_ABSOLUTE = 0

# queue entry kinds (index 0 of each entry)
QARC, QFEED, QTRAVERSE, QOTHER = 0, 1, 2, 3


def _inside(side: int, turn: int) -> bool:
    """TOOL_INSIDE_ARC"""
    return (side == LEFT and turn > 0) or (side == RIGHT and turn < 0)


class CompMixin:
    """Cutter compensation; mixed into the Interpreter."""

    # ------------------------------------------------------------- queue
    def _qc_clear(self) -> None:
        if self.qc:
            self._qc_stale_front = self.qc[0]  # what front() reads once emptied
        self.qc.clear()

    def _qc_front(self):
        """``qc().front()``: LinuxCNC reads it unguarded, so an empty queue gives its last
        first element (the vector keeps its memory)."""
        return self.qc[0] if self.qc else self._qc_stale_front

    def qc_reset(self) -> None:
        self._qc_clear()
        self.endpoint_valid = False

    def set_endpoint(self, x: float, y: float) -> None:
        self.endpoint = [x, y]
        self.endpoint_valid = True

    def qc_scale(self, factor: float) -> None:
        if not self.qc:
            return
        for q in self.qc:
            self.endpoint = [self.endpoint[0] * factor, self.endpoint[1] * factor]
            if q[0] == QARC:
                for k in (3, 4, 5, 6, 8, 12, 13, 14):
                    q[k] *= factor
            elif q[0] in (QFEED, QTRAVERSE):
                for k in (5, 6, 7, 11, 12, 13):
                    q[k] *= factor

    def _enqueue_move(
        self,
        kind: int,
        line: int,
        d1: float,
        d2: float,
        d3: float,
        x: float,
        y: float,
        z: float,
        rest,
    ) -> None:
        """enqueue_STRAIGHT_FEED/TRAVERSE: store in machine axis order."""
        if self.plane == C.PLANE_XZ:
            entry = [kind, line, d2, d3, d1, y, z, x, *rest]
        else:
            entry = [kind, line, d1, d2, d3, x, y, z, *rest]
        self.qc.append(entry)

    def _enqueue_arc(
        self, line, original_turns, end1, end2, center1, center2, turn, end3, rest
    ) -> None:
        self.qc.append(
            [QARC, line, original_turns, end1, end2, center1, center2, turn, end3, *rest]
        )

    def _lathe_x(self, x: float) -> float:
        if self.plane != C.PLANE_XZ:
            return x
        o, r = self.cutter_comp_orientation, self.cutter_comp_radius
        if o in (2, 6, 1):
            x -= r
        if o in (3, 8, 4):
            x += r
        return x

    def _lathe_z(self, z: float) -> float:
        if self.plane != C.PLANE_XZ:
            return z
        o, r = self.cutter_comp_orientation, self.cutter_comp_radius
        if o in (2, 7, 3):
            z -= r
        if o in (1, 5, 4):
            z += r
        return z

    def dequeue_canons(self) -> None:
        self.endpoint_valid = False
        if not self.qc:
            return
        canon = self.canon
        for q in self.qc:
            kind = q[0]
            if kind == QARC:
                canon.ARC_FEED(
                    q[1],
                    self._lathe_z(q[3]),
                    self._lathe_x(q[4]),
                    self._lathe_z(q[5]),
                    self._lathe_x(q[6]),
                    q[7],
                    q[8],
                    *q[9:15],
                )
            elif kind == QFEED:
                canon.STRAIGHT_FEED(q[1], self._lathe_x(q[5]), q[6], self._lathe_z(q[7]), *q[8:14])
            elif kind == QTRAVERSE:
                canon.STRAIGHT_TRAVERSE(
                    q[1], self._lathe_x(q[5]), q[6], self._lathe_z(q[7]), *q[8:14]
                )
            else:
                getattr(canon, q[1])(*q[2])
        self._qc_clear()

    def move_endpoint_and_flush(self, x: float, y: float) -> None:
        if not self.qc:
            return
        xz = self.plane == C.PLANE_XZ
        for q in self.qc:
            kind = q[0]
            if kind == QARC:
                r1 = ldmath.hypot(q[3] - q[5], q[4] - q[6])
                l1 = q[2]
                q[3], q[4] = x, y
                r2 = ldmath.hypot(x - q[5], y - q[6])
                l2 = ldmath.find_turn(self.endpoint[0], self.endpoint[1], q[5], q[6], q[7], x, y)
                if abs(r1 - r2) > 0.01:
                    raise InterpError(
                        "BUG: cutter compensation has generated an invalid arc with mismatched "
                        f"radii r1 {r1:f} r2 {r2:f}\n"
                    )
                tol = 0.0254 if self.length_units == C.UNITS_MM else 0.001
                if l1 != 0.0 and self.endpoint_valid and abs(l2) > abs(l1) + tol:
                    raise InterpError(
                        "Arc move in concave corner cannot be reached by the tool without gouging"
                    )
            elif kind in (QFEED, QTRAVERSE):
                if xz:
                    x1, y1 = q[4], q[2]
                else:
                    x1, y1 = q[2], q[3]
                x2 = x - self.endpoint[0]
                y2 = y - self.endpoint[1]
                dot = x1 * x2 + y1 * y2
                if self.endpoint_valid and dot < 0:
                    what = "Straight traverse" if kind == QTRAVERSE else "Straight feed"
                    raise InterpError(
                        f"{what} in concave corner cannot be reached by the tool without gouging"
                    )
                if xz:
                    q[7], q[5] = x, y
                else:
                    q[5], q[6] = x, y
        self.dequeue_canons()
        self.set_endpoint(x, y)

    # -------------------------------------------------------- plane access
    def comp_get_current(self) -> tuple[float, float, float]:
        cur = self.current
        if self.plane == C.PLANE_XZ:
            return cur[2], cur[0], cur[1]
        return cur[0], cur[1], cur[2]

    def comp_set_current(self, x: float, y: float, z: float) -> None:
        cur = self.current
        if self.plane == C.PLANE_XZ:
            cur[0], cur[1], cur[2] = y, z, x
        else:
            cur[0], cur[1], cur[2] = x, y, z

    def comp_get_programmed(self) -> tuple[float, float, float]:
        if self.plane == C.PLANE_XZ:
            return self.program_z, self.program_x, self.program_y
        return self.program_x, self.program_y, self.program_z

    def comp_set_programmed(self, x: float, y: float, z: float) -> None:
        if self.plane == C.PLANE_XZ:
            self.program_x, self.program_y, self.program_z = y, z, x
        else:
            self.program_x, self.program_y, self.program_z = x, y, z

    def _plane_ends(self, ends: list[float]) -> tuple[float, float, float]:
        if self.plane == C.PLANE_XZ:
            return ends[2], ends[0], ends[1]
        return ends[0], ends[1], ends[2]

    # ------------------------------------------------------------- lines
    def convert_straight_comp1(self, move: int, block: Block, ends: list[float]) -> None:
        px, py, pz = self._plane_ends(ends)
        radius = self.cutter_comp_radius
        side = self.cutter_comp_side
        cx, cy, _cz = self.comp_get_current()
        distance = ldmath.hypot(px - cx, py - cy)
        if side not in (LEFT, RIGHT):
            raise InterpError("Bug side not right or left")
        if distance <= radius:
            raise InterpError(
                "Length of cutter compensation entry move is not greater than the tool radius"
            )
        angle = math.atan2(py - cy, px - cx)
        alpha = ldmath.plus_pi_2(angle) if side == LEFT else ldmath.minus_pi_2(angle)
        end_x = px + radius * math.cos(alpha)
        end_y = py + radius * math.sin(alpha)
        self.set_endpoint(cx, cy)
        kind = QTRAVERSE if move == G_0 else QFEED
        self._enqueue_move(
            kind,
            block.line_number,
            math.cos(alpha),
            math.sin(alpha),
            0.0,
            end_x,
            end_y,
            pz,
            ends[3:9],
        )
        self.cutter_comp_firstmove = False
        self.comp_set_current(end_x, end_y, pz)
        self.current[3:9] = ends[3:9]
        self.comp_set_programmed(px, py, pz)

    def convert_straight_comp2(self, move: int, block: Block, ends: list[float]) -> None:
        px, py, pz = self._plane_ends(ends)
        small = TOLERANCE_CONCAVE_CORNER
        cx, cy, cz = self.comp_get_current()
        end_x, end_y = cx, cy
        opx, opy, opz = self.comp_get_programmed()
        kind = QTRAVERSE if move == G_0 else QFEED
        rest = ends[3:9]
        if py == opy and px == opx:
            self._enqueue_move(
                kind, block.line_number, px - opx, py - opy, pz - opz, cx, cy, pz, rest
            )
        else:
            side = self.cutter_comp_side
            radius = self.cutter_comp_radius
            theta = math.atan2(cy - opy, cx - opx)
            alpha = math.atan2(py - opy, px - opx)
            ld, pi, pi_2 = ldmath.ld, ldmath.pi_ld(), ldmath.pi_2_ld()
            if side == LEFT:
                if theta < alpha:
                    theta = float(ld(theta) + 2 * pi)
                beta = float((ld(theta) - ld(alpha)) - pi_2)
                gamma = math.pi / 2
            elif side == RIGHT:
                if alpha < theta:
                    alpha = float(ld(alpha) + 2 * pi)
                beta = float((ld(alpha) - ld(theta)) - pi_2)
                gamma = -math.pi / 2
            else:
                raise InterpError("Bug side not right or left")
            end_x = px + radius * math.cos(alpha + gamma)
            end_y = py + radius * math.sin(alpha + gamma)
            mid_x = opx + radius * math.cos(alpha + gamma)
            mid_y = opy + radius * math.sin(alpha + gamma)
            arc_first = (
                bool(self.qc)
                and self.qc[0][0] == QARC
                and ((side == RIGHT and self.qc[0][7] > 0) or (side == LEFT and self.qc[0][7] < 0))
            )
            if beta < -small or ld(beta) > pi + small or (ld(beta) > pi - small and arc_first):
                concave = True
            else:
                concave = False
            if not concave and beta > small:
                self.move_endpoint_and_flush(cx, cy)
                if move == G_1:
                    self._enqueue_arc(
                        block.line_number,
                        0.0,
                        mid_x,
                        mid_y,
                        opx,
                        opy,
                        -1 if side == LEFT else 1,
                        cz,
                        rest,
                    )
                else:
                    self._enqueue_move(
                        QTRAVERSE, block.line_number, 0.0, 0.0, 0.0, mid_x, mid_y, cz, rest
                    )
                self.dequeue_canons()
                self.set_endpoint(mid_x, mid_y)
            elif concave:
                front = self._qc_front()
                if front is None or front[0] != QARC:
                    halfcorner = float((ld(beta) + pi) / 2.0)
                    if halfcorner == 0.0:
                        raise InterpError(
                            "Zero degree inside corner is invalid for cutter compensation"
                        )
                    retreat = radius / math.tan(halfcorner)
                    mid_x = cx + retreat * math.cos(theta + gamma)
                    mid_y = cy + retreat * math.sin(theta + gamma)
                    self.move_endpoint_and_flush(mid_x, mid_y)
                else:
                    p_end1, p_end2, p_c1, p_c2, p_turn = (
                        front[3],
                        front[4],
                        front[5],
                        front[6],
                        front[7],
                    )
                    oldrad = ldmath.hypot(p_c2 - p_end2, p_c1 - p_end1)
                    base_dir = math.atan2(py - opy, px - opx)
                    theta2 = (
                        float(ld(base_dir) + pi_2) if p_turn > 0 else float(ld(base_dir) - pi_2)
                    )
                    phi = math.atan2(p_c2 - opy, p_c1 - opx)
                    inside = _inside(side, p_turn)
                    oldrad_uncomp = oldrad + radius if inside else oldrad - radius
                    d = oldrad_uncomp * math.cos(theta2 - phi)
                    d2 = d - radius if inside else d + radius
                    ratio = d2 / oldrad
                    if ratio > 1.0 or ratio < -1.0:
                        raise InterpError(
                            "Arc to straight motion makes a corner the compensated tool can't "
                            "fit in without gouging"
                        )
                    if (p_turn > 0) == inside:
                        angle = float(-ld(math.acos(ratio)) + ld(theta2) + pi)
                    else:
                        angle = float(ld(math.acos(ratio)) + ld(theta2) + pi)
                    mid_x = p_c1 + oldrad * math.cos(angle)
                    mid_y = p_c2 + oldrad * math.sin(angle)
                    self.move_endpoint_and_flush(mid_x, mid_y)
            else:
                self.dequeue_canons()
                self.set_endpoint(cx, cy)
            self._enqueue_move(
                kind, block.line_number, px - opx, py - opy, pz - opz, end_x, end_y, pz, rest
            )
        self.comp_set_current(end_x, end_y, pz)
        self.current[3:9] = rest
        self.comp_set_programmed(px, py, pz)

    # --------------------------------------------------------------- arcs
    def _comp_tolerances(self) -> tuple[float, float]:
        inch = self.length_units == C.UNITS_INCHES
        spiral = (
            self.center_arc_radius_tolerance_inch if inch else self.center_arc_radius_tolerance_mm
        )
        return spiral, (RADIUS_TOLERANCE_INCH if inch else RADIUS_TOLERANCE_MM)

    def _arc_p(self, block: Block) -> int:
        return round(block.p_number) if block.p_flag else 1

    def convert_arc_comp1(self, move: int, block: Block, ends: list[float], offsets) -> None:
        end_x, end_y, end_z = self._plane_ends(ends)
        side = self.cutter_comp_side
        tool_radius = self.cutter_comp_radius
        spiral_abs, radius_tol = self._comp_tolerances()
        cx, cy, cz = self.comp_get_current()
        if ldmath.hypot(end_x - cx, end_y - cy) <= tool_radius:
            raise InterpError(
                "Radius of cutter compensation entry arc is not greater than the tool radius"
            )
        if block.r_flag:
            if abs(block.r_number) <= tool_radius and _inside_move(side, move):
                raise InterpError("Tool radius not less than arc radius with comp")
            center_x, center_y, turn = self.arc_data_r(
                move, cx, cy, end_x, end_y, block.r_number, self._arc_p(block), radius_tol
            )
        else:
            center_x, center_y, turn = self.arc_data_ijk(
                move,
                cx,
                cy,
                end_x,
                end_y,
                self.ijk_distance_mode == MODE_ABSOLUTE,
                offsets[0],
                offsets[1],
                self._arc_p(block),
                radius_tol,
                spiral_abs,
                SPIRAL_RELATIVE_TOLERANCE,
                comp_side=side,
                tool_radius=tool_radius,
            )
        self.inverse_time_rate_arc(cx, cy, cz, center_x, center_y, turn, end_x, end_y, end_z, block)
        if _inside(side, turn):
            gamma = math.atan2(center_y - end_y, center_x - end_x)
        else:
            gamma = math.atan2(end_y - center_y, end_x - center_x)
        self.cutter_comp_firstmove = False
        self.comp_set_programmed(end_x, end_y, end_z)
        end_x += tool_radius * math.cos(gamma)
        end_y += tool_radius * math.sin(gamma)
        b_len = ldmath.hypot(cy - end_y, cx - end_x) / 2.0
        ab_ang = math.atan2(center_y - end_y, center_x - end_x)
        a_ang = math.atan2(cy - end_y, cx - end_x) - ab_ang
        if abs(math.cos(a_ang)) < TOLERANCE_EQUAL:
            raise InterpError("Tool radius not less than arc radius with comp")
        c_len = b_len / math.cos(a_ang)
        center_x = end_x + c_len * math.cos(ab_ang)
        center_y = end_y + c_len * math.sin(ab_ang)
        if (
            abs(
                ldmath.hypot(center_x - end_x, center_y - end_y)
                - ldmath.hypot(center_x - cx, center_y - cy)
            )
            > spiral_abs
        ):
            raise InterpError("Bug in tool radius comp")
        rest = ends[3:9]
        if self.cutter_comp_orientation not in (0, 9):
            self._enqueue_move(QFEED, block.line_number, 0.0, 0.0, 0.0, cx, cy, cz, rest)
            self.set_endpoint(cx, cy)
        self._enqueue_arc(
            block.line_number,
            ldmath.find_turn(cx, cy, center_x, center_y, turn, end_x, end_y),
            end_x,
            end_y,
            center_x,
            center_y,
            turn,
            end_z,
            rest,
        )
        self.comp_set_current(end_x, end_y, end_z)
        self.current[3:9] = rest

    def convert_arc_comp2(self, move: int, block: Block, ends: list[float], offsets) -> None:
        end_x, end_y, end_z = self._plane_ends(ends)
        small = TOLERANCE_CONCAVE_CORNER
        spiral_abs, radius_tol = self._comp_tolerances()
        opx, opy, opz = self.comp_get_programmed()
        cx, cy, cz = self.comp_get_current()
        if block.r_flag:
            centerx, centery, turn = self.arc_data_r(
                move, opx, opy, end_x, end_y, block.r_number, self._arc_p(block), radius_tol
            )
        else:
            centerx, centery, turn = self.arc_data_ijk(
                move,
                opx,
                opy,
                end_x,
                end_y,
                self.ijk_distance_mode == MODE_ABSOLUTE,
                offsets[0],
                offsets[1],
                self._arc_p(block),
                radius_tol,
                spiral_abs,
                SPIRAL_RELATIVE_TOLERANCE,
            )
        self.inverse_time_rate_arc(
            opx, opy, opz, centerx, centery, turn, end_x, end_y, end_z, block
        )
        side = self.cutter_comp_side
        tool_radius = self.cutter_comp_radius
        arc_radius = ldmath.hypot(centerx - end_x, centery - end_y)
        ld, pi, pi_2 = ldmath.ld, ldmath.pi_ld(), ldmath.pi_2_ld()
        theta = math.atan2(cy - opy, cx - opx)
        theta = float(ld(theta) - pi_2) if side == LEFT else float(ld(theta) + pi_2)
        delta = math.atan2(centery - opy, centerx - opx)
        alpha = float(ld(delta) - pi_2) if move == G_3 else float(ld(delta) + pi_2)
        beta = theta - alpha if side == LEFT else alpha - theta
        if ld(beta) > 1.5 * pi:
            beta = float(ld(beta) - 2 * pi)
        elif ld(beta) < -pi_2:
            beta = float(ld(beta) + 2 * pi)
        if (side == LEFT and move == G_3) or (side == RIGHT and move == G_2):
            gamma = math.atan2(centery - end_y, centerx - end_x)
            if arc_radius <= tool_radius:
                raise InterpError("Tool radius not less than arc radius with comp")
        else:
            gamma = math.atan2(end_y - centery, end_x - centerx)
            delta = float(ld(delta) + pi)
        new_end_x = end_x + tool_radius * math.cos(gamma)
        new_end_y = end_y + tool_radius * math.sin(gamma)
        rest = ends[3:9]
        if (
            beta < -small
            or ld(beta) > pi + small
            or (abs(ld(beta) - pi) < small and not _inside(side, turn))
        ):
            front = self._qc_front()
            if front is None or front[0] != QARC:
                cy2 = arc_radius * ldmath.sinl(ld(beta) - pi_2)
                if _inside(side, turn):
                    dist_from_center = arc_radius - tool_radius
                    toward_nominal = cy2 + tool_radius
                    ratio = toward_nominal / dist_from_center
                    _check_gouge(ratio)
                    angle = theta + math.asin(ratio) if turn > 0 else theta - math.asin(ratio)
                else:
                    dist_from_center = arc_radius + tool_radius
                    toward_nominal = cy2 - tool_radius
                    ratio = toward_nominal / dist_from_center
                    _check_gouge(ratio)
                    if turn > 0:
                        angle = float(ld(theta) + pi - ld(math.asin(ratio)))
                    else:
                        angle = float(ld(theta) + pi + ld(math.asin(ratio)))
                midx = centerx + dist_from_center * math.cos(angle)
                midy = centery + dist_from_center * math.sin(angle)
                self.move_endpoint_and_flush(midx, midy)
            else:
                p_end1, p_end2, p_c1, p_c2, p_turn = (
                    front[3],
                    front[4],
                    front[5],
                    front[6],
                    front[7],
                )
                oldrad = ldmath.hypot(p_c2 - p_end2, p_c1 - p_end1)
                newrad = (
                    arc_radius - tool_radius if _inside(side, turn) else arc_radius + tool_radius
                )
                arc_cc = ldmath.hypot(p_c2 - centery, p_c1 - centerx)
                if oldrad == 0 or arc_cc == 0:
                    raise InterpError(
                        "Arc to arc motion is invalid because the arcs have the same center"
                    )
                a = (oldrad * oldrad + arc_cc * arc_cc - newrad * newrad) / (2 * oldrad * arc_cc)
                if a > 1.0 or a < -1.0:
                    raise InterpError(
                        "Arc to arc motion makes a corner the compensated tool can't fit in "
                        "without gouging"
                    )
                pullback = math.acos(a)
                cc_dir = math.atan2(centery - p_c2, centerx - p_c1)
                if _inside(side, p_turn):
                    direction = cc_dir + pullback if turn > 0 else cc_dir - pullback
                else:
                    direction = cc_dir - pullback if turn > 0 else cc_dir + pullback
                midx = p_c1 + oldrad * math.cos(direction)
                midy = p_c2 + oldrad * math.sin(direction)
                self.move_endpoint_and_flush(midx, midy)
            self._enqueue_arc(
                block.line_number,
                ldmath.find_turn(opx, opy, centerx, centery, turn, end_x, end_y),
                new_end_x,
                new_end_y,
                centerx,
                centery,
                turn,
                end_z,
                rest,
            )
        elif beta > small:
            midx = opx + tool_radius * math.cos(delta)
            midy = opy + tool_radius * math.sin(delta)
            self.dequeue_canons()
            self._enqueue_arc(
                block.line_number, 0.0, midx, midy, opx, opy, -1 if side == LEFT else 1, cz, rest
            )
            self.dequeue_canons()
            self.set_endpoint(midx, midy)
            self._enqueue_arc(
                block.line_number,
                ldmath.find_turn(opx, opy, centerx, centery, turn, end_x, end_y),
                new_end_x,
                new_end_y,
                centerx,
                centery,
                turn,
                end_z,
                rest,
            )
        else:
            self.dequeue_canons()
            self.set_endpoint(cx, cy)
            self._enqueue_arc(
                block.line_number,
                ldmath.find_turn(opx, opy, centerx, centery, turn, end_x, end_y),
                new_end_x,
                new_end_y,
                centerx,
                centery,
                turn,
                end_z,
                rest,
            )
        self.comp_set_programmed(end_x, end_y, end_z)
        self.comp_set_current(new_end_x, new_end_y, end_z)
        self.current[3:9] = rest


def _inside_move(side: int, move: int) -> bool:
    return (side == LEFT and move == G_3) or (side == RIGHT and move == G_2)


def _check_gouge(ratio: float) -> None:
    if ratio > 1.0 or ratio < -1.0:
        raise InterpError(
            "Arc move in concave corner cannot be reached by the tool without gouging"
        )
