"""Canned cycles G73, G74, G81..G89 with G98/G99 retract and L repeats (INTERP-028).

One implementation serves the three planes: ``aa``/``bb`` are the plane's first and second
axes and ``cc`` the drilling axis (XY: X Y Z, YZ: Y Z X, XZ: Z X Y), as in LinuxCNC.
"""

from __future__ import annotations

import math

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from . import ldmath
from .block import G_73, G_74, G_81, G_82, G_83, G_84, G_85, G_86, G_87, G_88, G_89, Block
from .errors import InterpError

G83_RAPID_DELTA = 0.010
R_PLANE = 0
MODE_ABSOLUTE, MODE_INCREMENTAL = 0, 1
INVERSE_TIME = 1

# plane -> (index of aa, bb, cc in a 9-axis pose, letters, error texts)
_PLANES = {
    C.PLANE_XY: (
        (0, 1, 2),
        "xyz",
        "Z value unspecified in xy plane canned cycle",
        "R less than z in cycle in xy plane",
    ),
    C.PLANE_YZ: (
        (1, 2, 0),
        "yzx",
        "X value unspecified in yz plane canned cycle",
        "R less than x in cycle in yz plane",
    ),
    C.PLANE_XZ: (
        (2, 0, 1),
        "zxy",
        "Y value unspecified in xz plane canned cycle",
        "R less than y in cycle in xz plane",
    ),
}
_PLANE_NAMES = {
    C.PLANE_XY: "XY",
    C.PLANE_YZ: "YZ",
    C.PLANE_XZ: "XZ",
    C.PLANE_UV: "UV",
    C.PLANE_VW: "VW",
    C.PLANE_UW: "UW",
}


class CyclesMixin:
    """Canned cycles; mixed into the Interpreter."""

    def convert_cycle(self, motion: int, block: Block) -> None:
        if self.feed_rate == 0.0:
            raise InterpError("Cannot feed with zero feed rate")
        if self.feed_mode == INVERSE_TIME:
            raise InterpError("Cannot use inverse time feed with canned cycles")
        if self.cutter_comp_side:
            raise InterpError("Cannot use canned cycles with cutter compensation on")
        plane = self.plane
        if not block.r_flag:
            if self.motion_mode == motion:
                block.r_number = self.cycle_r
            else:
                raise InterpError("R clearance plane unspecified in cycle")
        if block.l_number == 0:
            raise InterpError("Cannot do zero repeats of cycle")
        if block.l_number == -1:
            block.l_number = 1
        name = _PLANE_NAMES.get(plane, "invalid")
        if plane in _PLANES:
            for letter, article in (("u", "a U"), ("v", "a V"), ("w", "a W")):
                if getattr(block, letter + "_flag"):
                    raise InterpError(f"Cannot put {article} in a canned cycle in the {name} plane")
        else:
            for letter, article in (("x", "an X"), ("y", "a Y"), ("z", "a Z")):
                if getattr(block, letter + "_flag"):
                    raise InterpError(f"Cannot put {article} in a canned cycle in the {name} plane")
            raise InterpError(f"Canned cycles in the {name} plane are not supported")
        # the tag shows the cycle as the motion mode (as LinuxCNC's), though the mode
        # changes only once the cycle is converted
        saved_mode, self.motion_mode = self.motion_mode, motion
        self.write_canon_state_tag(block)
        self.motion_mode = saved_mode
        self._convert_cycle_plane(motion, block, plane)
        self.cycle_l = block.l_number
        self.cycle_r = block.r_number
        self.motion_mode = motion

    def _convert_cycle_plane(self, motion: int, block: Block, plane: int) -> None:
        (ia, ib, ic), letters, missing_msg, r_less_msg = _PLANES[plane]
        la, lb, lc = letters
        cur = self.current
        current_cc = cur[ic]
        if self.motion_mode != motion and not getattr(block, lc + "_flag"):
            raise InterpError(missing_msg)
        cc_word = getattr(block, lc + "_number") if getattr(block, lc + "_flag") else self.cycle_cc
        setattr(block, lc + "_number", cc_word)
        if self.cycle_il_flag:
            old_cc = self.cycle_il
        else:
            old_cc = self.cycle_il = current_cc
            self.cycle_il_flag = True
        aa_increment = bb_increment = 0.0
        radius_increment = theta_increment = 0.0
        if self.distance_mode == MODE_ABSOLUTE:
            r = block.r_number
            cc = cc_word
            if plane == C.PLANE_XY and (block.radius_flag or block.theta_flag):
                radius = block.radius if block.radius_flag else ldmath.hypot(cur[1], cur[0])
                theta = (
                    block.theta * (math.pi / 180.0)
                    if block.theta_flag
                    else math.atan2(cur[1], cur[0])
                )
                aa = radius * math.cos(theta)
                bb = radius * math.sin(theta)
            else:
                aa = getattr(block, la + "_number") if getattr(block, la + "_flag") else cur[ia]
                bb = getattr(block, lb + "_number") if getattr(block, lb + "_flag") else cur[ib]
        else:
            if getattr(block, la + "_flag"):
                aa_increment = getattr(block, la + "_number")
            if getattr(block, lb + "_flag"):
                bb_increment = getattr(block, lb + "_number")
            if plane == C.PLANE_XY:
                if block.radius_flag:
                    radius_increment = block.radius
                if block.theta_flag:
                    theta_increment = block.theta * (math.pi / 180.0)
            r = block.r_number + old_cc
            cc = r + cc_word
            aa = cur[ia]
            bb = cur[ib]
        if r < cc:
            raise InterpError(r_less_msg)
        canon = self.canon
        if old_cc < r:
            pose = list(cur)
            pose[ic] = r
            canon.STRAIGHT_TRAVERSE(block.line_number, *pose)
            old_cc = r
            current_cc = old_cc
        clear_cc = r if self.retract_mode == R_PLANE else old_cc
        save_mode = canon.GET_EXTERNAL_MOTION_CONTROL_MODE()
        save_tolerance = canon.GET_EXTERNAL_MOTION_CONTROL_TOLERANCE()
        save_cam = canon.GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE()
        if save_mode != C.EXACT_PATH:
            canon.SET_MOTION_CONTROL_MODE(C.EXACT_PATH, 0)

        axes = (ia, ib, ic)
        spindle = self.active_spindle

        def traverse(a: float, b: float, c: float) -> None:
            pose = list(self.current)
            pose[ia], pose[ib], pose[ic] = a, b, c
            canon.STRAIGHT_TRAVERSE(block.line_number, *pose)

        def feed(a: float, b: float, c: float) -> None:
            pose = list(self.current)
            pose[ia], pose[ib], pose[ic] = a, b, c
            canon.STRAIGHT_FEED(block.line_number, *pose)

        def tap_feed(a: float, b: float, c: float) -> None:
            # LinuxCNC passes the YZ and XZ tapping moves in a rotated order; keep it so
            pose = list(self.current)
            if plane == C.PLANE_XY:
                pose[0], pose[1], pose[2] = a, b, c
            elif plane == C.PLANE_YZ:
                pose[0], pose[1], pose[2] = b, c, a
            else:
                pose[0], pose[1], pose[2] = c, a, b
            canon.STRAIGHT_FEED(block.line_number, *pose)

        # words and checks before the repeats
        if motion in (G_82, G_86, G_88, G_89):
            if self.motion_mode != motion and block.p_number == -1.0:
                raise InterpError(f"Dwell time p word missing with g{motion // 10}")
            block.p_number = self.cycle_p if block.p_number == -1.0 else block.p_number
        elif motion in (G_73, G_83):
            if self.motion_mode != motion and block.q_number == -1.0:
                raise InterpError(f"Q word missing with g{motion // 10}")
            block.q_number = self.cycle_q if block.q_number == -1.0 else block.q_number
        elif motion in (G_74, G_84):
            block.p_number = self.cycle_p if block.p_number == -1.0 else block.p_number
            if block.dollar_flag:
                if block.dollar_number < 0 or block.dollar_number >= self.num_spindles:
                    raise InterpError("Invalid spindle ($) number in G74/G84 cycle")
                self.active_spindle = int(block.dollar_number)
                spindle = self.active_spindle
        elif motion == G_87:
            if self.motion_mode != G_87:
                if not block.i_flag:
                    raise InterpError("I word missing with g87")
                if not block.j_flag:
                    raise InterpError("J word missing with g87")
                if not block.k_flag:
                    raise InterpError("K word missing with g87")
            i = block.i_number if block.i_flag else self.cycle_i
            j = block.j_number if block.j_flag else self.cycle_j
            k = block.k_number if block.k_flag else self.cycle_k
            self.cycle_i, self.cycle_j, self.cycle_k = i, j, k
            # offsets along aa/bb and the back bore height along cc, per plane
            if plane == C.PLANE_XY:
                off_a, off_b, middle = i, j, k
            elif plane == C.PLANE_YZ:
                off_a, off_b, middle = j, k, i
            else:
                off_a, off_b, middle = k, i, j
            if self.distance_mode == MODE_INCREMENTAL:
                middle = cc + middle
        direction = self.spindle_turning[self.active_spindle]

        def one_cycle(a: float, b: float) -> None:
            if motion == G_81:
                feed(a, b, cc)
                traverse(a, b, clear_cc)
            elif motion == G_82:
                feed(a, b, cc)
                canon.DWELL(block.p_number)
                traverse(a, b, clear_cc)
            elif motion in (G_73, G_83):
                delta = block.q_number
                if delta <= 0.0:
                    raise InterpError("Negative or zero q value used")
                rapid_delta = G83_RAPID_DELTA
                if self.length_units == C.UNITS_MM:
                    rapid_delta = rapid_delta * 25.4
                depth = r - delta
                while depth > cc:
                    feed(a, b, depth)
                    if motion == G_83:
                        traverse(a, b, r)
                    traverse(a, b, depth + rapid_delta)
                    depth = depth - delta
                feed(a, b, cc)
                traverse(a, b, clear_cc)
            elif motion in (G_74, G_84):
                self._cycle_tap(
                    motion, a, b, cc, clear_cc, direction, block.p_number, spindle, tap_feed
                )
            elif motion == G_85:
                feed(a, b, cc)
                feed(a, b, r)
                traverse(a, b, clear_cc)
            elif motion == G_86:
                if direction not in (C.CLOCKWISE, C.COUNTERCLOCKWISE):
                    raise InterpError("Spindle not turning in g86")
                feed(a, b, cc)
                canon.DWELL(block.p_number)
                canon.STOP_SPINDLE_TURNING(spindle)
                traverse(a, b, clear_cc)
                self._restart_spindle(direction, spindle)
            elif motion == G_87:
                if direction not in (C.CLOCKWISE, C.COUNTERCLOCKWISE):
                    raise InterpError("Spindle not turning in g87")
                oa, ob = a + off_a, b + off_b
                traverse(oa, ob, r)
                canon.STOP_SPINDLE_TURNING(spindle)
                canon.ORIENT_SPINDLE(spindle, 0.0, direction)
                traverse(oa, ob, cc)
                traverse(a, b, cc)
                self._restart_spindle(direction, spindle)
                feed(a, b, middle)
                feed(a, b, cc)
                canon.STOP_SPINDLE_TURNING(spindle)
                canon.ORIENT_SPINDLE(spindle, 0.0, direction)
                traverse(oa, ob, cc)
                traverse(oa, ob, clear_cc)
                traverse(a, b, clear_cc)
                self._restart_spindle(direction, spindle)
            elif motion == G_88:
                if direction not in (C.CLOCKWISE, C.COUNTERCLOCKWISE):
                    raise InterpError("Spindle not turning in g88")
                feed(a, b, cc)
                canon.DWELL(block.p_number)
                canon.STOP_SPINDLE_TURNING(spindle)
                canon.PROGRAM_STOP()
                self._restart_spindle(direction, spindle)
            elif motion == G_89:
                feed(a, b, cc)
                canon.DWELL(block.p_number)
                feed(a, b, clear_cc)
            else:
                raise InterpError("Bug function should not have been called")

        repeat = block.l_number
        while repeat > 0:
            aa = aa + aa_increment
            bb = bb + bb_increment
            if radius_increment:
                if bb == 0 and aa == 0:
                    raise InterpError(
                        "Incremental motion with polar coordinates is "
                        "indeterminate when at the origin"
                    )
                theta = math.atan2(bb, aa)
                radius = ldmath.hypot(bb, aa) + radius_increment
                aa, bb = radius * math.cos(theta), radius * math.sin(theta)
            if theta_increment:
                if bb == 0 and aa == 0:
                    raise InterpError(
                        "Incremental motion with polar coordinates is "
                        "indeterminate when at the origin"
                    )
                theta = math.atan2(bb, aa) + theta_increment
                radius = ldmath.hypot(bb, aa)
                aa, bb = radius * math.cos(theta), radius * math.sin(theta)
            if repeat == block.l_number and current_cc > r:
                traverse(aa, bb, current_cc)
                traverse(aa, bb, r)
            else:
                traverse(aa, bb, clear_cc)
                if clear_cc > r:
                    traverse(aa, bb, r)
            one_cycle(aa, bb)
            repeat -= 1
        if motion in (G_82, G_74, G_84, G_86, G_88, G_89):
            self.cycle_p = block.p_number
        elif motion in (G_73, G_83):
            self.cycle_q = block.q_number
        self.current[axes[0]] = aa
        self.current[axes[1]] = bb
        self.current[axes[2]] = clear_cc
        self.cycle_cc = cc_word
        if save_mode != C.EXACT_PATH:
            canon.SET_MOTION_CONTROL_MODE(save_mode, save_tolerance)
            canon.SET_NAIVECAM_TOLERANCE(save_cam)

    def _restart_spindle(self, direction: int, spindle: int) -> None:
        if direction == C.CLOCKWISE:
            self.canon.START_SPINDLE_CLOCKWISE(spindle)
        else:
            self.canon.START_SPINDLE_COUNTERCLOCKWISE(spindle)

    def _cycle_tap(self, motion, a, b, cc, clear_cc, direction, dwell, spindle, feed) -> None:
        name = "G74" if motion == G_74 else "G84"
        if direction == C.STOPPED:
            raise InterpError(f"Spindle not turning in {name}")
        if direction == C.CLOCKWISE and motion == G_74:
            raise InterpError("Spindle turning clockwise in G74")
        if direction == C.COUNTERCLOCKWISE and motion == G_84:
            raise InterpError("Spindle turning counterclockwise in G84")
        canon = self.canon
        save_fo = canon.GET_EXTERNAL_FEED_OVERRIDE_ENABLE()
        save_so = canon.GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE(spindle)
        canon.DISABLE_FEED_OVERRIDE()
        canon.DISABLE_SPEED_OVERRIDE(spindle)
        feed(a, b, cc)
        canon.STOP_SPINDLE_TURNING(spindle)
        if motion == G_84:
            canon.START_SPINDLE_COUNTERCLOCKWISE(spindle)
        else:
            canon.START_SPINDLE_CLOCKWISE(spindle)
        canon.DWELL(dwell)
        feed(a, b, clear_cc)
        canon.STOP_SPINDLE_TURNING(spindle)
        if motion == G_84:
            canon.START_SPINDLE_CLOCKWISE(spindle)
        else:
            canon.START_SPINDLE_COUNTERCLOCKWISE(spindle)
        if save_fo:
            canon.ENABLE_FEED_OVERRIDE()
        if save_so:
            canon.ENABLE_SPEED_OVERRIDE(spindle)
