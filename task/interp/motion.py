"""Motion: G0/G1/G33, arcs, probes, G76 threading, splines, the G7x glue, end points (find_ends)."""

from __future__ import annotations

import math

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from . import ldmath
from .block import (
    G_0,
    G_1,
    G_2,
    G_3,
    G_5,
    G_5_1,
    G_5_2,
    G_33,
    G_33_1,
    G_38_2,
    G_38_3,
    G_38_4,
    G_38_5,
    G_53,
    G_70,
    G_71,
    G_71_1,
    G_71_2,
    G_72,
    G_72_1,
    G_72_2,
    G_76,
    G_80,
    GM_MODAL_0,
    GM_MOTION,
    Block,
    is_a_cycle,
)
from .common import (
    INVERSE_TIME,
    LEFT,
    MODE_ABSOLUTE,
    MODE_INCREMENTAL,
    RADIUS_TOLERANCE_INCH,
    RADIUS_TOLERANCE_MM,
    RIGHT,
    SPIRAL_RELATIVE_TOLERANCE,
    TINY,
    UNITS_PER_MINUTE,
    UNITS_PER_REVOLUTION,
    c_format,
    rotate,
    round_to_int,
    wrapped_msg,
)
from .errors import InterpError


class MotionMixin:
    """Motion conversions; mixed into the Interpreter."""

    # ================================================================ motion
    def convert_motion(self, motion: int, block: Block) -> None:
        ai = block.a_flag and self.a_indexer_jnum != -1
        bi = block.b_flag and self.b_indexer_jnum != -1
        ci = block.c_flag and self.c_indexer_jnum != -1
        if motion != G_0:
            for flag, letter in ((ai, "A"), (bi, "B"), (ci, "C")):
                if flag:
                    raise InterpError(f"Indexing axis {letter} can only be moved with G0")
        xyz = (
            block.x_flag
            or block.y_flag
            or block.z_flag
            or block.u_flag
            or block.v_flag
            or block.w_flag
        )
        if ai and (xyz or block.b_flag or block.c_flag):
            raise InterpError("Indexing axis A can only be moved alone")
        if bi and (xyz or block.a_flag or block.c_flag):
            raise InterpError("Indexing axis B can only be moved alone")
        if ci and (xyz or block.a_flag or block.b_flag):
            raise InterpError("Indexing axis C can only be moved alone")
        if not is_a_cycle(motion):
            self.cycle_il_flag = False
        if ai or bi or ci:
            axis, jnum = (
                (3, self.a_indexer_jnum)
                if ai
                else (4, self.b_indexer_jnum)
                if bi
                else (5, self.c_indexer_jnum)
            )
            ends = self.find_ends(block)
            self.issue_straight_index(axis, jnum, ends[axis], block.line_number)
        elif motion in (G_0, G_1, G_33, G_33_1, G_76):
            self.convert_straight(motion, block)
        elif motion in (G_2, G_3):
            self.convert_arc(motion, block)
        elif motion in (G_38_2, G_38_3, G_38_4, G_38_5):
            self.convert_probe(block, motion)
        elif motion == G_80:
            self._enq("COMMENT", "interpreter: motion mode set to none")
            self.motion_mode = G_80
        elif is_a_cycle(motion):
            self.convert_cycle(motion, block)
        elif motion in (G_70, G_71, G_71_1, G_71_2, G_72, G_72_1, G_72_2):
            self.convert_g7x(block)
        elif motion in (G_5, G_5_1):
            self.write_canon_state_tag(block)
            self.convert_spline(motion, block)
        elif motion == G_5_2:
            self.convert_nurbs(motion, block)
        else:
            raise InterpError(f"G{motion / 10:g} is not supported by this interpreter")

    def convert_straight(self, move: int, block: Block) -> None:
        self.arc_not_allowed = False
        if move == G_1:
            if self.feed_mode == UNITS_PER_MINUTE:
                if self.feed_rate == 0.0:
                    raise InterpError("Cannot do g1 with zero feed rate")
            elif self.feed_mode == UNITS_PER_REVOLUTION:
                if self.feed_rate == 0.0:
                    raise InterpError("Cannot do g1 with zero feed rate")
                if self.speed[self.active_spindle] == 0.0:
                    raise InterpError("Cannot feed with zero spindle speed in feed per rev mode")
            elif not block.f_flag:
                raise InterpError("F word missing with inverse time g1 move")
        self.motion_mode = move
        ends = self.find_ends(block)
        if move == G_1 and self.feed_mode == INVERSE_TIME:
            self.inverse_time_rate_straight(ends, block)
        self.write_canon_state_tag(block)
        if self.cutter_comp_side and self.cutter_comp_radius > 0.0:
            if block.g_modes[GM_MODAL_0] == G_53:
                raise InterpError("Cannot use g53 with cutter radius comp")
            if self.plane not in (C.PLANE_XY, C.PLANE_XZ):
                raise InterpError("BUG: Invalid plane for cutter compensation")
            if self.cutter_comp_firstmove:
                self.convert_straight_comp1(move, block, ends)
            else:
                self.convert_straight_comp2(move, block, ends)
            return
        canon = self.canon
        if move == G_0:
            canon.STRAIGHT_TRAVERSE(block.line_number, *ends)
        elif move == G_1:
            canon.STRAIGHT_FEED(block.line_number, *ends)
        elif move in (G_33, G_33_1):
            if block.dollar_flag:
                if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                    raise InterpError(
                        f"Invalid spindle ($) number in {'G33' if move == G_33 else 'G33.1'} move"
                    )
                self.active_spindle = int(block.dollar_number)
            if self.spindle_turning[self.active_spindle] not in (C.CLOCKWISE, C.COUNTERCLOCKWISE):
                raise InterpError(
                    "Spindle not turning in G33" if move == G_33 else "Spindle not turning in G33.1"
                )
            canon.START_SPEED_FEED_SYNCH(self.active_spindle, block.k_number, False)
            if move == G_33:
                canon.STRAIGHT_FEED(block.line_number, *ends)
            else:
                scale = 1.0
                if block.i_flag:
                    scale = max(block.i_number, 1.0)
                canon.RIGID_TAP(block.line_number, ends[0], ends[1], ends[2], scale)
            canon.STOP_SPEED_FEED_SYNCH()
            if move == G_33_1:
                for k in (3, 4, 5, 6, 7, 8):
                    self.current[k] = ends[k]
                return
        else:  # G76
            if block.dollar_flag:
                if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                    raise InterpError("Invalid D-number in G76 cycle")
                self.active_spindle = int(block.dollar_number)
            if self.spindle_turning[self.active_spindle] not in (C.CLOCKWISE, C.COUNTERCLOCKWISE):
                raise InterpError(f"Chosen spindle ({self.active_spindle}) not turning in G76")
            if ends[3:9] != self.current[3:9]:
                raise InterpError("Cannot move rotary axes with G76")
            self.convert_threading_cycle(block, ends)
            return
        self.current = list(ends)

    # ============================================================= threading
    def convert_threading_cycle(self, block: Block, ends: list[float]) -> None:
        """G76: passes of decreasing depth, then spring passes (LinuxCNC's algorithm)."""
        if self.cutter_comp_side:
            raise InterpError("Cannot use G76 threading cycle with cutter radius compensation on")
        if block.i_number == 0:
            raise InterpError("In G76, I must not be 0")
        if block.j_number <= 0:
            raise InterpError("In G76, J must be greater than 0")
        if block.k_number <= block.j_number:
            raise InterpError("In G76, K must be greater than J")
        start_x, start_y, start_z = self.current[0], self.current[1], self.current[2]
        i_number, j_number, k_number = block.i_number, block.j_number, block.k_number
        if self.lathe_diameter_mode:
            i_number /= 2
            j_number /= 2
            k_number /= 2
        boring = i_number > 0.0
        safe_x = start_x
        full_dia_depth = abs(i_number)
        start_depth = abs(i_number) + abs(j_number)
        cut_increment = abs(j_number)
        full_threadheight = abs(k_number)
        end_depth = abs(k_number) + abs(i_number)
        pitch = block.p_number
        compound = block.q_number
        if compound == -1:
            compound = 0.0
        compound = ldmath.degrees_to_radians(compound)
        end_x, end_y, end_z = ends[0], ends[1], ends[2]
        if end_z > start_z:
            compound = -compound
        spring_cuts = block.h_number if block.h_flag else 0
        degression = block.r_number
        if degression < 1.0 or not block.r_flag:
            degression = 1.0
        taper_dist = block.e_number if block.e_flag else 0.0
        if taper_dist < 0.0:
            taper_dist = 0.0
        taper_pitch = (
            pitch * ldmath.hypot(taper_dist, full_threadheight) / taper_dist
            if taper_dist > 0.0
            else pitch
        )
        if end_z > start_z:
            taper_dist = -taper_dist
        taper_flags = max(block.l_number, 0)
        entry_taper = taper_flags & 1
        exit_taper = taper_flags & 2
        target_z = end_z + abs(k_number) * math.tan(compound)
        passes = 1
        depth = start_depth
        zoff = (depth - full_dia_depth) * math.tan(compound)
        args = (
            block,
            boring,
            safe_x,
            end_depth,
            start_y,
            start_z,
            taper_dist,
            entry_taper,
            exit_taper,
            taper_pitch,
            pitch,
            full_threadheight,
            target_z,
        )
        while depth < end_depth:
            self._threading_pass(depth, zoff, *args)
            passes += 1
            depth = full_dia_depth + cut_increment * math.pow(passes, 1.0 / degression)
            zoff = (depth - full_dia_depth) * math.tan(compound)
        depth = end_depth
        zoff = (depth - full_dia_depth) * math.tan(compound)
        for _ in range(spring_cuts + 1):
            self._threading_pass(depth, zoff, *args)
        cur = self.current
        self.canon.STRAIGHT_TRAVERSE(block.line_number, end_x, end_y, end_z, *cur[3:9])
        cur[0], cur[1], cur[2] = end_x, end_y, end_z

    def _threading_pass(
        self,
        depth,
        zoff,
        block,
        boring,
        safe_x,
        end_depth,
        start_y,
        start_z,
        taper_dist,
        entry_taper,
        exit_taper,
        taper_pitch,
        pitch,
        full_threadheight,
        target_z,
    ) -> None:
        canon = self.canon
        line = block.line_number
        rest = self.current[3:9]
        spindle = self.active_spindle

        def x_at(d: float) -> float:
            return safe_x + d if boring else safe_x - d

        canon.STRAIGHT_TRAVERSE(line, x_at(depth - end_depth), start_y, start_z - zoff, *rest)
        if taper_dist and entry_taper:
            canon.DISABLE_FEED_OVERRIDE()
            canon.START_SPEED_FEED_SYNCH(spindle, taper_pitch, False)
            canon.STRAIGHT_FEED(
                line, x_at(depth - full_threadheight), start_y, start_z - zoff, *rest
            )
            canon.STRAIGHT_FEED(line, x_at(depth), start_y, start_z - zoff - taper_dist, *rest)
            canon.START_SPEED_FEED_SYNCH(spindle, pitch, False)
        else:
            canon.STRAIGHT_TRAVERSE(line, x_at(depth), start_y, start_z - zoff, *rest)
            canon.DISABLE_FEED_OVERRIDE()
            canon.START_SPEED_FEED_SYNCH(spindle, pitch, False)
        if taper_dist and exit_taper:
            canon.STRAIGHT_FEED(line, x_at(depth), start_y, target_z - zoff + taper_dist, *rest)
            canon.START_SPEED_FEED_SYNCH(spindle, taper_pitch, False)
            canon.STRAIGHT_FEED(
                line, x_at(depth - full_threadheight), start_y, target_z - zoff, *rest
            )
        else:
            canon.STRAIGHT_FEED(line, x_at(depth), start_y, target_z - zoff, *rest)
        canon.STOP_SPEED_FEED_SYNCH()
        canon.STRAIGHT_TRAVERSE(line, x_at(depth - end_depth), start_y, target_z - zoff, *rest)
        canon.ENABLE_FEED_OVERRIDE()

    # ========================================================== lathe cycles
    def convert_g7x(self, block: Block) -> None:
        """G70/G71/G72: read the profile from sub O<Q>, then cut it (see g7x.py)."""
        if not block.q_flag:
            raise InterpError("G7x.x  requires a Q word")
        cycle = block.g_modes[GM_MOTION]
        subcycle = cycle % 10
        cycle //= 10
        if self.cutter_comp_side and cycle != 70:
            raise InterpError(
                f"G{cycle}.{subcycle} cannot be used with cutter compensation enabled"
            )
        if self.plane != C.PLANE_XZ:
            raise InterpError(f"G{cycle}.{subcycle} can only be used in XZ plane (G18)")
        saved_distance, saved_ijk = self.distance_mode, self.ijk_distance_mode
        self.distance_mode = self.ijk_distance_mode = MODE_ABSOLUTE
        saved_readers = {k: self._readers.get(k) for k in "acuw"}
        full = self._make_readers(0x1FF)
        for k in "acuw":
            self._readers[k] = full[k]
        self._no_fast = True
        try:
            self._convert_g7x(block, cycle, subcycle, saved_distance, saved_ijk)
        finally:
            self._no_fast = False
            self.distance_mode, self.ijk_distance_mode = saved_distance, saved_ijk
            for k, reader in saved_readers.items():
                if reader is None:
                    self._readers.pop(k, None)
                else:
                    self._readers[k] = reader

    def _convert_g7x(self, block, cycle, subcycle, distance_mode, ijk_mode) -> None:
        from .g7x import Chamfer, Fillet, G7xError, G7xPath, Round, Straight, raise_g7x

        incremental = distance_mode == MODE_INCREMENTAL
        x, z = self.current[0], self.current[2]
        if incremental:
            x += block.x_number if block.x_flag else 0.0
            z += block.z_number if block.z_flag else 0.0
        else:
            x = block.x_number if block.x_flag else x
            z = block.z_number if block.z_flag else z
        words = {
            k: (getattr(block, k + "_flag"), getattr(block, k + "_number"))
            for k in ("e", "i", "r", "u", "w")
        }
        words["d"] = (block.d_flag, block.d_number_float)
        words["p"] = (block.p_flag, block.p_number)
        start_x, start_z = self.current[0], self.current[2]
        side = self.cutter_comp_side
        self.cutter_comp_side = 0  # the move to the cycle's start point is uncompensated
        try:
            self.convert_straight(G_0, block)
        finally:
            self.cutter_comp_side = side
        path = G7xPath(lambda text: self.canon.PRINT_LINE(text.rstrip("\n")))
        start = complex(z, x)
        exit_level = self.call_level
        self.read(f"O{block.q_number:f} CALL")
        while True:
            blk = self.block
            if blk.o_name is not None:
                self.convert_control_functions(blk)
            if self.call_level == exit_level:
                break
            self.apply_parameter_assignments()
            end = 0j if incremental else start
            center = 0j
            if blk.u_flag:
                if incremental:
                    raise InterpError("G7x error: Cannot use U in incremental mode (G91)")
                if blk.x_flag:
                    raise InterpError("G7x error: Cannot use U and X in the same block")
                u = blk.u_number / 2 if self.lathe_diameter_mode else blk.u_number
                end = complex(end.real, end.imag + u)
            elif blk.x_flag:
                end = complex(end.real, blk.x_number)
            if blk.w_flag:
                if incremental:
                    raise InterpError("G7x error: Cannot use W in incremental mode (G91)")
                if blk.z_flag:
                    raise InterpError("G7x error: Cannot use W and Z in the same block")
                end = complex(end.real + blk.w_number, end.imag)
            elif blk.z_flag:
                end = complex(blk.z_number, end.imag)
            if blk.i_flag:
                center = complex(center.real, blk.i_number)
            if blk.k_flag:
                center = complex(blk.k_number, center.imag)
            if incremental:
                end += start
            if blk.g_modes[GM_MOTION] != -1:
                self.motion_mode = blk.g_modes[GM_MOTION]
            if start != end:
                mode = self.motion_mode
                if mode in (G_0, G_1):
                    path.segments.append(Straight(start, end))
                elif mode in (G_2, G_3):
                    if blk.r_flag:
                        if blk.i_flag or blk.k_flag:
                            raise InterpError("G7X error: both R and I or K flag used for arc")
                        r = blk.r_number
                        center = complex((start + end).real / 2.0, (start + end).imag / 2.0)
                        chord = _norm_c(end - start)
                        root = math.sqrt((r * r - chord / 4) / chord)
                        d = complex(0.0 * root, root) * (end - start)
                        center = center + d if mode == G_3 else center - d
                    else:
                        if not blk.i_flag and not blk.k_flag:
                            raise InterpError("G7X error: either I or K must be present for arc")
                        if ijk_mode == MODE_INCREMENTAL:
                            center += start
                    path.segments.append(Round(int(mode == G_3), start, center, end))
                if mode in (G_0, G_1, G_2, G_3):
                    if blk.a_flag and blk.c_flag:
                        raise InterpError("G7X error: Both A and C parameters on a corner")
                    if blk.a_flag:
                        path.segments.append(Fillet(blk.a_number, end))
                    if blk.c_flag:
                        path.segments.append(Chamfer(blk.c_number, end))
                self.current[0], self.current[2] = end.imag, end.real
                start = end
            self.read()
        if len(path.segments) <= 1:
            return
        d = words["d"][1] if words["d"][0] else 0.0
        e = words["e"][1] if words["e"][0] else 0.0
        i = words["i"][1] if words["i"][0] else 1.0
        p = words["p"][1] if words["p"][0] else 1.0
        r = words["r"][1] if words["r"][0] else 0.5
        u = words["u"][1] if words["u"][0] else 0.0
        w = words["w"][1] if words["w"][0] else 0.0
        # LinuxCNC 2.9.10: the cycle starts from where the G7x block left the tool, not from
        # the end of the profile the subroutine drew
        self.current[0], self.current[2] = start_x, start_z
        if i <= 0:
            raise InterpError("G7X error: I must be greater than zero.")
        first, last = path.segments[0], path.segments[-1]
        d_front, d_back = first.end - first.start, last.end - last.start
        motion = _G7xMachine(self, self.block)
        try:
            if cycle == 70:
                path.do_g70(motion, x, z, d, e, p)
            elif cycle == 71:
                # 2.9.10: a profile ending away from the start X gets its closing X move
                # (the missing last pass)
                if abs(d_back.real) > 0 and d_front.imag * (x - start.imag) < 0:
                    path.segments.append(Straight(start, complex(start.real, x)))
                path.do_g71(motion, subcycle, x, z, u, w, d, i, r)
            else:
                if abs(d_back.imag) > 0 and d_front.real * (z - start.real) < 0:
                    path.segments.append(Straight(start, complex(z, start.imag)))
                path.do_g72(motion, subcycle, x, z, u, w, d, i, r)
        except G7xError as error:
            raise_g7x(error)

    # =============================================================== splines
    def convert_spline(self, mode: int, block: Block) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot convert spline with cutter radius compensation")
        if self.feed_mode == UNITS_PER_MINUTE:
            if self.feed_rate == 0.0:
                raise InterpError("Cannot make arc with zero feed rate")
        elif self.feed_mode == INVERSE_TIME and not block.f_flag:
            raise InterpError("F word missing with inverse time arc move")
        if self.plane != C.PLANE_XY:
            raise InterpError("Splines must be in the XY plane")
        if block.z_flag or block.a_flag or block.b_flag or block.c_flag:
            raise InterpError("Splines may not have motion in Z, A, B, or C")
        cur = self.current
        if mode == G_5_1:
            if not block.i_flag or not block.j_flag:
                raise InterpError("Must specify both I and J with G5.1")
            x1, y1 = cur[0] + block.i_number, cur[1] + block.j_number
            ends = self.find_ends(block)
            points = [(cur[0], cur[1], 1.0), (x1, y1, 1.0), (ends[0], ends[1], 1.0)]
            self.canon.NURBS_FEED(block.line_number, points, 3)
        else:
            if not block.i_flag or not block.j_flag:
                if block.i_flag or block.j_flag:
                    raise InterpError("Must specify both I and J, or neither")
                x1, y1 = cur[0] + self.cycle_i, cur[1] + self.cycle_j
            else:
                x1, y1 = cur[0] + block.i_number, cur[1] + block.j_number
            ends = self.find_ends(block)
            if not block.p_flag or not block.q_flag:
                raise InterpError("Must specify both P and Q with G5")
            x2, y2 = ends[0] + block.p_number, ends[1] + block.q_number
            points = [(cur[0], cur[1], 1.0), (x1, y1, 1.0), (x2, y2, 1.0), (ends[0], ends[1], 1.0)]
            self.canon.NURBS_FEED(block.line_number, points, 4)
            self.cycle_i = -block.p_number
            self.cycle_j = -block.q_number
        self.nurbs_points = []
        cur[0], cur[1] = ends[0], ends[1]

    def convert_nurbs(self, mode: int, block: Block) -> None:
        points = self.nurbs_points
        if mode == G_5_2:
            if block.x_flag != block.y_flag:
                raise InterpError("You must specify both X and Y coordinates for Control Points")
            if not block.x_flag and block.p_number > 0 and points:
                raise InterpError("Can specify P without X and Y only for the first control point")
            if block.p_number <= 0 and points:
                raise InterpError("Must specify positive weight P for every Control Point")
            if self.feed_mode == UNITS_PER_MINUTE and self.feed_rate == 0.0:
                raise InterpError("Cannot make a NURBS with 0 feedrate")
            if self.motion_mode != mode:
                points.clear()
            if not points:
                weight = block.p_number if (not block.x_flag and block.p_number > 0) else 1.0
                self.nurbs_order = 3
                points.append((self.current[0], self.current[1], weight))
            if block.l_number != -1 and block.l_number > 3:
                self.nurbs_order = block.l_number
            if block.x_flag and block.y_flag:
                ends = self.find_ends(block)
                points.append((ends[0], ends[1], block.p_number))
            self.motion_mode = mode
        else:
            if self.motion_mode != G_5_2:
                raise InterpError("Cannot use G5.3 without G5.2 first")
            if len(points) < self.nurbs_order:
                raise InterpError(
                    "You must specify a number of control points at least equal "
                    f"to the order L = {self.nurbs_order}"
                )
            self.current[0], self.current[1] = points[-1][0], points[-1][1]
            self.canon.NURBS_FEED(block.line_number, list(points), self.nurbs_order)
            points.clear()
            self.motion_mode = -1

    def inverse_time_rate_arc(self, x1, y1, z1, cx, cy, turn, x2, y2, z2, block: Block) -> None:
        """G93: the feed rate that makes the arc take 1/F minutes."""
        if self.feed_mode != INVERSE_TIME:
            return
        radius = ldmath.hypot(cx - x1, cy - y1)
        theta = ldmath.find_turn(x1, y1, cx, cy, turn, x2, y2)
        length = radius * abs(theta) if z2 == z1 else ldmath.hypot(radius * theta, z2 - z1)
        rate = max(0.1, length * block.f_number)
        self._enq("SET_FEED_RATE", rate)
        self.feed_rate = rate

    def inverse_time_rate_straight(self, ends: list[float], block: Block) -> None:
        cur = list(self.current)
        if (
            self.cutter_comp_side
            and self.cutter_comp_radius > 0.0
            and not self.cutter_comp_firstmove
        ):
            cur[0], cur[1], cur[2] = self.program_x, self.program_y, self.program_z
        length = _straight_length(ends, cur)
        rate = max(0.1, length * block.f_number)
        self._enq("SET_FEED_RATE", rate)
        self.feed_rate = rate

    def convert_probe(self, block: Block, g_code: int) -> None:
        probe_type = g_code - G_38_2
        if self.cutter_comp_side:
            raise InterpError("Cannot probe with cutter radius comp on")
        if self.feed_rate == 0.0:
            raise InterpError("Cannot probe with zero feed rate")
        if self.feed_mode == UNITS_PER_REVOLUTION:
            raise InterpError("Cannot probe with feed per rev mode")
        ends = self.find_ends(block)
        if not (probe_type & 1) and ends == self.current:
            raise InterpError("Start point too close to probe point")
        canon = self.canon
        canon.TURN_PROBE_ON()
        canon.STRAIGHT_PROBE(block.line_number, *ends, probe_type)
        canon.TURN_PROBE_OFF()
        self.motion_mode = g_code
        self.probe_flag = True

    # =================================================================== arcs
    def convert_arc(self, move: int, block: Block) -> None:
        if self.arc_not_allowed:
            raise InterpError(
                "The move just after exiting cutter compensation mode must be straight, not an arc"
            )
        ijk_flag = block.i_flag or block.j_flag or block.k_flag
        plane = self.plane
        if plane in (C.PLANE_UV, C.PLANE_VW, C.PLANE_UW):
            raise InterpError("Cannot do an arc in planes G17.1, G18.1, or G19.1")
        if not block.r_flag and not ijk_flag:
            raise InterpError("R i j k words all missing for arc")
        if block.r_flag and ijk_flag:
            raise InterpError("Mixed radius ijk format for arc")
        if self.feed_mode == UNITS_PER_MINUTE:
            if self.feed_rate == 0.0:
                raise InterpError("Cannot make arc with zero feed rate")
        elif self.feed_mode == UNITS_PER_REVOLUTION:
            if self.feed_rate == 0.0:
                raise InterpError("Cannot make arc with zero feed rate")
            if self.speed[self.active_spindle] == 0.0:
                raise InterpError("Cannot feed with zero spindle speed in feed per rev mode")
        elif not block.f_flag:
            raise InterpError("F word missing with inverse time arc move")
        absolute = self.ijk_distance_mode == MODE_ABSOLUTE
        if ijk_flag:
            if plane == C.PLANE_XY:
                if block.k_flag:
                    raise InterpError("K word given for arc in xy plane")
                first, second = "i", "j"
            elif plane == C.PLANE_YZ:
                if block.i_flag:
                    raise InterpError("I word given for arc in yz plane")
                first, second = "j", "k"
            else:
                if block.j_flag:
                    raise InterpError("J word given for arc in xz plane")
                first, second = "i", "k"
            if not getattr(block, first + "_flag"):
                if absolute:
                    raise InterpError(f"{first.upper()} word missing in absolute center arc")
                setattr(block, first + "_number", 0.0)
            elif not getattr(block, second + "_flag"):
                if absolute:
                    raise InterpError(f"{second.upper()} word missing in absolute center arc")
                setattr(block, second + "_number", 0.0)
        else:
            if plane == C.PLANE_XY:
                if not (block.x_flag or block.y_flag or block.radius_flag or block.theta_flag):
                    raise InterpError("X and y words missing for arc in xy plane")
            elif plane == C.PLANE_YZ:
                if not (block.y_flag or block.z_flag):
                    raise InterpError("Y and z words missing for arc in yz plane")
            elif not (block.x_flag or block.z_flag):
                raise InterpError("X and z words missing for arc in xz plane")
        ends = self.find_ends(block)
        self.motion_mode = move
        self.write_canon_state_tag(block)
        if plane == C.PLANE_XY:
            axes = (0, 1, 2)
            offsets = (block.i_number, block.j_number)
        elif plane == C.PLANE_XZ:
            axes = (2, 0, 1)
            offsets = (block.k_number, block.i_number)
        else:
            axes = (1, 2, 0)
            offsets = (block.j_number, block.k_number)
        if self.cutter_comp_side and self.cutter_comp_radius != 0.0 and plane != C.PLANE_YZ:
            if self.cutter_comp_firstmove:
                self.convert_arc_comp1(move, block, ends, offsets)
            else:
                self.convert_arc_comp2(move, block, ends, offsets)
            return
        self.convert_arc2(move, block, axes, ends, offsets)

    def convert_arc2(self, move: int, block: Block, axes, ends, offsets) -> None:
        a1, a2, a3 = axes
        cur = self.current
        current1, current2, current3 = cur[a1], cur[a2], cur[a3]
        end1, end2, end3 = ends[a1], ends[a2], ends[a3]
        inch = self.length_units == C.UNITS_INCHES
        spiral_abs = (
            self.center_arc_radius_tolerance_inch if inch else self.center_arc_radius_tolerance_mm
        )
        radius_tol = RADIUS_TOLERANCE_INCH if inch else RADIUS_TOLERANCE_MM
        p_number = round_to_int(block.p_number) if block.p_flag else 1
        if block.r_flag:
            center1, center2, turn = self.arc_data_r(
                move, current1, current2, end1, end2, block.r_number, p_number, radius_tol
            )
        else:
            center1, center2, turn = self.arc_data_ijk(
                move,
                current1,
                current2,
                end1,
                end2,
                self.ijk_distance_mode == MODE_ABSOLUTE,
                offsets[0],
                offsets[1],
                p_number,
                radius_tol,
                spiral_abs,
                SPIRAL_RELATIVE_TOLERANCE,
            )
        self.inverse_time_rate_arc(
            current1, current2, current3, center1, center2, turn, end1, end2, end3, block
        )
        self.canon.ARC_FEED(
            block.line_number,
            end1,
            end2,
            center1,
            center2,
            turn,
            end3,
            ends[3],
            ends[4],
            ends[5],
            ends[6],
            ends[7],
            ends[8],
        )
        self.current = list(ends)

    def _arc_axis_names(self) -> tuple[str, str]:
        return {C.PLANE_XY: ("X", "Y"), C.PLANE_XZ: ("Z", "X"), C.PLANE_YZ: ("Y", "Z")}.get(
            self.plane, ("!", "!")
        )

    def arc_data_ijk(
        self,
        move,
        cx,
        cy,
        ex,
        ey,
        absolute,
        i,
        j,
        p_number,
        radius_tol,
        spiral_abs,
        spiral_rel,
        comp_side=0,
        tool_radius=0.0,
    ):
        a, b = self._arc_axis_names()
        if absolute:
            center_x, center_y = i, j
        else:
            center_x, center_y = cx + i, cy + j
        radius = ldmath.hypot(center_x - cx, center_y - cy)
        radius2 = ldmath.hypot(center_x - ex, center_y - ey)
        if radius < radius_tol or radius2 < radius_tol:
            raise InterpError(
                f"Zero-radius arc: start=({a}{cx:.4f},{b}{cy:.4f}) center=({a}{center_x:.4f},"
                f"{b}{center_y:.4f}) end=({a}{ex:.4f},{b}{ey:.4f}) r1={radius:.4f} "
                f"r2={radius2:.4f}"
            )
        abs_err = abs(radius - radius2)
        rel_err = abs_err / max(radius, radius2)
        if abs_err > spiral_abs * 100.0 or (rel_err > spiral_rel and abs_err > spiral_abs):
            raise InterpError(
                f"Radius to end of arc differs from radius to start: "
                f"start=({a}{cx:.4f},{b}{cy:.4f}) center=({a}{center_x:.4f},{b}{center_y:.4f}) "
                f"end=({a}{ex:.4f},{b}{ey:.4f}) r1={radius:.4f} r2={radius2:.4f} "
                f"abs_err={c_format('%.4g', abs_err)} rel_err={rel_err * 100:.4f}%"
            )
        if (
            comp_side
            and radius <= tool_radius
            and ((comp_side == LEFT and move == G_3) or (comp_side == RIGHT and move == G_2))
        ):
            raise InterpError("Tool radius not less than arc radius with comp")
        turn = -p_number if move == G_2 else p_number
        return center_x, center_y, turn

    def arc_data_r(self, move, cx, cy, ex, ey, radius, p_number, tolerance):
        if ex == cx and ey == cy:
            raise InterpError("Current point same as end point of arc")
        abs_radius = abs(radius)
        mid_x = (ex + cx) / 2.0
        mid_y = (ey + cy) / 2.0
        half_length = ldmath.hypot(mid_x - ex, mid_y - ey)
        if half_length - abs_radius > tolerance:
            raise InterpError("Arc radius too small to reach end point")
        if half_length / abs_radius > 1 - TINY:
            half_length = abs_radius
        if (move == G_2 and radius > 0) or (move == G_3 and radius < 0):
            theta = ldmath.minus_pi_2(math.atan2(ey - cy, ex - cx))
        else:
            theta = ldmath.plus_pi_2(math.atan2(ey - cy, ex - cx))
        turn2 = math.asin(half_length / abs_radius)
        offset = abs_radius * math.cos(turn2)
        center_x = mid_x + offset * math.cos(theta)
        center_y = mid_y + offset * math.sin(theta)
        turn = -p_number if move == G_2 else p_number
        return center_x, center_y, turn

    # ================================================================= ends
    def find_ends(self, block: Block) -> list[float]:
        cur = self.current
        if block.g_modes[GM_MODAL_0] == G_53:
            if block.radius_flag or block.theta_flag:
                raise InterpError("Cannot use polar coordinates with G53")
            off, org, tlo = self.axis_offset, self.origin_offset, self.tool_offset
            cx, cy = rotate(cur[0] + off[0], cur[1] + off[1], self.rotation_xy)
            px = block.x_number - org[0] - tlo[0] if block.x_flag else cx
            py = block.y_number - org[1] - tlo[1] if block.y_flag else cy
            px, py = rotate(px, py, -self.rotation_xy)
            px -= off[0]
            py -= off[1]
            pz = block.z_number - org[2] - off[2] - tlo[2] if block.z_flag else cur[2]
            result = [px, py, pz]
            for k, letter, wrapped in (
                (3, "a", self.a_axis_wrapped),
                (4, "b", self.b_axis_wrapped),
                (5, "c", self.c_axis_wrapped),
            ):
                if getattr(block, letter + "_flag"):
                    value = getattr(block, letter + "_number")
                    if wrapped:
                        result.append(
                            self.unwrap_rotary(
                                value, value - org[k] - off[k] - tlo[k], cur[k], letter.upper()
                            )
                        )
                    else:
                        result.append(value - org[k] - off[k])
                else:
                    result.append(cur[k])
            for k, letter in ((6, "u"), (7, "v"), (8, "w")):
                if getattr(block, letter + "_flag"):
                    result.append(getattr(block, letter + "_number") - org[k] - off[k] - tlo[k])
                else:
                    result.append(cur[k])
            return result
        comp = self.cutter_comp_side
        middle = not self.cutter_comp_firstmove
        cm = comp and middle
        plane = self.plane
        if self.distance_mode == MODE_ABSOLUTE:
            px = block.x_number if block.x_flag else (self.program_x if cm else cur[0])
            py = (
                block.y_number
                if block.y_flag
                else (self.program_y if cm and plane == C.PLANE_XY else cur[1])
            )
            if block.radius_flag or block.theta_flag:
                if block.x_flag or block.y_flag:
                    raise InterpError("Cannot specify X or Y words with polar coordinate")
                if block.radius_flag and block.theta_flag:
                    t = block.theta * (math.pi / 180.0)
                    px, py = block.radius * math.cos(t), block.radius * math.sin(t)
                elif block.radius_flag:
                    if py == 0 and px == 0:
                        raise InterpError("Must specify angle in polar coordinate if at the origin")
                    t = math.atan2(py, px)
                    px, py = block.radius * math.cos(t), block.radius * math.sin(t)
                else:
                    radius = ldmath.hypot(py, px)
                    t = block.theta * (math.pi / 180.0)
                    px, py = radius * math.cos(t), radius * math.sin(t)
            pz = (
                block.z_number
                if block.z_flag
                else (self.program_z if cm and plane == C.PLANE_XZ else cur[2])
            )
            result = [px, py, pz]
            for k, letter, wrapped in (
                (3, "a", self.a_axis_wrapped),
                (4, "b", self.b_axis_wrapped),
                (5, "c", self.c_axis_wrapped),
            ):
                if getattr(block, letter + "_flag"):
                    value = getattr(block, letter + "_number")
                    if wrapped:
                        result.append(self.unwrap_rotary(value, value, cur[k], letter.upper()))
                    else:
                        result.append(value)
                else:
                    result.append(cur[k])
            result.append(block.u_number if block.u_flag else cur[6])
            result.append(block.v_number if block.v_flag else cur[7])
            result.append(block.w_number if block.w_flag else cur[8])
            return result
        px = self.program_x if cm else cur[0]
        if block.x_flag:
            px += block.x_number
        py = self.program_y if cm and plane == C.PLANE_XY else cur[1]
        if block.y_flag:
            py += block.y_number
        if block.radius_flag:
            if block.x_flag or block.y_flag:
                raise InterpError("Cannot specify X or Y words with polar coordinate")
            if py == 0 and px == 0:
                raise InterpError(
                    "Incremental motion with polar coordinates is indeterminate when at the origin"
                )
            t = math.atan2(py, px)
            radius = ldmath.hypot(py, px) + block.radius
            px, py = radius * math.cos(t), radius * math.sin(t)
        if block.theta_flag:
            if block.x_flag or block.y_flag:
                raise InterpError("Cannot specify X or Y words with polar coordinate")
            if py == 0 and px == 0:
                raise InterpError(
                    "G91 motion with polar coordinates is indeterminate when at the origin"
                )
            t = math.atan2(py, px) + block.theta * (math.pi / 180.0)
            radius = ldmath.hypot(py, px)
            px, py = radius * math.cos(t), radius * math.sin(t)
        pz = self.program_z if cm and plane == C.PLANE_XZ else cur[2]
        if block.z_flag:
            pz += block.z_number
        return [
            px,
            py,
            pz,
            cur[3] + block.a_number if block.a_flag else cur[3],
            cur[4] + block.b_number if block.b_flag else cur[4],
            cur[5] + block.c_number if block.c_flag else cur[5],
            cur[6] + block.u_number if block.u_flag else cur[6],
            cur[7] + block.v_number if block.v_flag else cur[7],
            cur[8] + block.w_number if block.w_flag else cur[8],
        ]

    def unwrap_rotary(self, sign_of: float, commanded: float, current: float, axis: str) -> float:
        if sign_of <= -360.0 or sign_of >= 360.0:
            raise InterpError(wrapped_msg(sign_of, axis))
        neg = math.copysign(1.0, sign_of) < 0.0
        d = math.floor(current / 360.0)
        result = abs(commanded) + d * 360.0
        if not neg and result < current:
            result += 360.0
        if neg and result > current:
            result -= 360.0
        return result

    def find_relative(self, absolute: list[float]) -> list[float]:
        org, tlo, off = self.origin_offset, self.tool_offset, self.axis_offset
        x = absolute[0] - org[0] - tlo[0]
        y = absolute[1] - org[1] - tlo[1]
        x, y = rotate(x, y, -self.rotation_xy)
        result = [x - off[0], y - off[1], absolute[2] - org[2] - off[2] - tlo[2]]
        for k, wrapped, letter in (
            (3, self.a_axis_wrapped, "A"),
            (4, self.b_axis_wrapped, "B"),
            (5, self.c_axis_wrapped, "C"),
        ):
            if wrapped:
                result.append(
                    self.unwrap_rotary(
                        absolute[k], absolute[k] - org[k] - off[k] - tlo[k], self.current[k], letter
                    )
                )
            else:
                result.append(absolute[k] - org[k] - off[k])
        for k in (6, 7, 8):
            result.append(absolute[k] - org[k] - off[k] - tlo[k])
        return result

    def find_current_in_system(self, system: int, with_tlo: bool = False) -> list[float]:
        p = self.parameters
        cur = self.current
        off, org, tlo = self.axis_offset, self.origin_offset, self.tool_offset
        v = [cur[k] + off[k] for k in range(9)]
        v[0], v[1] = rotate(v[0], v[1], self.rotation_xy)
        for k in range(9):
            v[k] += org[k]
        if with_tlo:
            for k in range(9):
                v[k] += tlo[k]
        base = 5200 + system * 20
        stored = self._u2p_pose(p[base + 1 : base + 10])
        for k in range(9):
            v[k] -= stored[k]
        v[0], v[1] = rotate(v[0], v[1], -p[base + 10])
        if p[5210]:
            g92 = self._u2p_pose(p[5211:5220])
            for k in range(9):
                v[k] -= g92[k]
        return v


def _norm_c(z: complex) -> float:
    return z.real * z.real + z.imag * z.imag


class _G7xMachine:
    """Turns the lathe cycles' moves into ordinary G0/G1/G2/G3 conversions."""

    def __init__(self, interp: MotionMixin, block: Block) -> None:
        self.interp = interp
        self.block = block

    def _to(self, end: complex) -> None:
        block = self.block
        block.x_flag = block.z_flag = True
        block.x_number, block.z_number = end.imag, end.real

    def straight_move(self, end: complex) -> None:
        self._to(end)
        self.interp.convert_straight(G_1, self.block)

    def straight_rapid(self, end: complex) -> None:
        self._to(end)
        self.interp.convert_straight(G_0, self.block)

    def uncompensated_rapid(self, end: complex) -> None:
        """A rapid with cutter compensation suspended (G70's move to its start point)."""
        side = self.interp.cutter_comp_side
        self.interp.cutter_comp_side = 0
        try:
            self.straight_rapid(end)
        finally:
            self.interp.cutter_comp_side = side

    def circular_move(self, ccw: int, center: complex, end: complex) -> None:
        self._to(end)
        block = self.block
        block.i_flag = block.k_flag = True
        block.i_number, block.k_number = center.imag, center.real
        cur = self.interp.current
        if abs(cur[2] - block.z_number) >= 0.0001 or abs(cur[0] - block.x_number) >= 0.0001:
            self.interp.convert_arc(G_3 if ccw else G_2, block)


def _straight_length(end: list[float], start: list[float]) -> float:
    tiny = 1e-7
    if (
        abs(start[0] - end[0]) > tiny
        or abs(start[1] - end[1]) > tiny
        or abs(start[2] - end[2]) > tiny
    ):
        return math.sqrt(
            (end[0] - start[0]) ** 2 + (end[1] - start[1]) ** 2 + (end[2] - start[2]) ** 2
        )
    if (
        abs(start[6] - end[6]) > tiny
        or abs(start[7] - end[7]) > tiny
        or abs(start[8] - end[8]) > tiny
    ):
        return math.sqrt(
            (end[6] - start[6]) ** 2 + (end[7] - start[7]) ** 2 + (end[8] - start[8]) ** 2
        )
    return math.sqrt((end[3] - start[3]) ** 2 + (end[4] - start[4]) ** 2 + (end[5] - start[5]) ** 2)
