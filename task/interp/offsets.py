"""Coordinate systems and offsets: G54..G59.3, G10 L2/L20, G28/G30, G52/G92 (modal group 0)."""

from __future__ import annotations

import math

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from .block import (
    G_5_3,
    G_10,
    G_28,
    G_28_1,
    G_30,
    G_30_1,
    G_52,
    G_92,
    G_92_1,
    G_92_2,
    G_92_3,
    Block,
)
from .common import (
    axis_words,
    rotate,
    wrapped_msg,
)
from .errors import InterpError


class OffsetsMixin:
    """Offset conversions; mixed into the Interpreter."""

    def convert_coordinate_system(self, g_code: int) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot change coordinate systems with cutter radius compensation on")
        origin = {540: 1, 550: 2, 560: 3, 570: 4, 580: 5, 590: 6, 591: 7, 592: 8, 593: 9}[g_code]
        if origin == self.origin_index:
            self._enq("COMMENT", "interpreter: continuing to use same coordinate system")
            return
        self.current = self.find_current_in_system(origin)
        self.origin_index = origin
        pars = self.parameters
        pars[5220] = float(origin)
        base = 5200 + origin * 20
        self.origin_offset = self._u2p_pose(pars[base + 1 : base + 10])
        self.rotation_xy = pars[base + 10]
        self.canon.SET_G5X_OFFSET(origin, *self.origin_offset)
        self.canon.SET_G92_OFFSET(*self.axis_offset)
        self.canon.SET_XY_ROTATION(self.rotation_xy)

    # =============================================================== modal 0
    def convert_modal_0(self, code: int, block: Block) -> None:
        if code == G_10:
            lnum = block.l_number
            if lnum in (1, 10, 11):
                self.convert_setup_tool(block)
            elif lnum == 0:
                tno = self.tool_table[0].toolno
                if tno > 0:
                    raise InterpError(f"G10 L0 not allowed with loaded tool <{tno}>\n")
                self.toolchange_flag = True
                self.canon.RELOAD_TOOLDATA()
            else:
                self.convert_setup(block)
        elif code in (G_28, G_30):
            self.convert_home(code, block)
        elif code in (G_28_1, G_30_1):
            self.convert_savehome(code)
        elif code in (G_52, G_92):
            self.convert_axis_offsets(code, block)
        elif code == G_5_3:
            self.convert_nurbs(code, block)

    def convert_axis_offsets(self, g_code: int, block: Block) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot change axis offsets with cutter radius comp")
        for letter, wrapped in (
            ("a", self.a_axis_wrapped),
            ("b", self.b_axis_wrapped),
            ("c", self.c_axis_wrapped),
        ):
            value = getattr(block, letter + "_number")
            if getattr(block, letter + "_flag") and wrapped and (value <= -360.0 or value >= 360.0):
                raise InterpError(wrapped_msg(value, letter.upper()))
        pars = self.parameters
        cur = self.current
        off = self.axis_offset
        if g_code in (G_52, G_92):
            pars[5210] = 1.0
            words = axis_words(block)
            for k, value in enumerate(words):
                if value is None:
                    continue
                if g_code == G_52:
                    cur[k] += off[k] - value
                    off[k] = value
                else:
                    off[k] = cur[k] + off[k] - value
                    cur[k] = value
            self.canon.SET_G92_OFFSET(*off)
            for k in range(9):
                pars[5211 + k] = self.p2u_len(off[k]) if k in (0, 1, 2, 6, 7, 8) else off[k]
        elif g_code in (G_92_1, G_92_2):
            pars[5210] = 0.0
            for k in range(9):
                cur[k] = cur[k] + off[k]
            self.canon.SET_G92_OFFSET(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            self.axis_offset = [0.0] * 9
            if g_code == G_92_1:
                for k in range(9):
                    pars[5211 + k] = 0.0
        elif g_code == G_92_3:
            pars[5210] = 1.0
            new = self._u2p_pose(pars[5211:5220])
            for k in range(9):
                cur[k] = cur[k] + off[k] - new[k]
            self.axis_offset = new
            self.canon.SET_G92_OFFSET(*new)

    def convert_savehome(self, code: int) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot set reference point with cutter compensation in effect")
        cur, off, org, tlo = self.current, self.axis_offset, self.origin_offset, self.tool_offset
        x, y = rotate(cur[0] + off[0], cur[1] + off[1], self.rotation_xy)
        values = [
            self.p2u_len(x + tlo[0] + org[0]),
            self.p2u_len(y + tlo[1] + org[1]),
            self.p2u_len(cur[2] + tlo[2] + org[2] + off[2]),
        ]
        for k in (3, 4, 5):
            values.append(cur[k] + tlo[k] + org[k] + off[k])
        for k in (6, 7, 8):
            values.append(self.p2u_len(cur[k] + tlo[k] + org[k] + off[k]))
        for k, wrapped in (
            (3, self.a_axis_wrapped),
            (4, self.b_axis_wrapped),
            (5, self.c_axis_wrapped),
        ):
            if wrapped:
                values[k] = math.fmod(values[k], 360.0)
                if values[k] < 0:
                    values[k] += 360.0
        base = 5161 if code == G_28_1 else 5181
        self.parameters[base : base + 9] = values

    def convert_home(self, move: int, block: Block) -> None:
        ends = self.find_ends(block)
        if self.cutter_comp_side:
            raise InterpError("Cannot use g28 or g30 with cutter radius comp")
        self._index_rotaries(ends, block.line_number)
        self.canon.STRAIGHT_TRAVERSE(block.line_number, *ends)
        self.current = list(ends)
        base = 5161 if move == G_28 else 5181
        home = self.find_relative(self._u2p_pose(self.parameters[base : base + 9]))
        words = axis_words(block)
        if all(w is None for w in words):
            ends = home
        else:
            ends = [home[k] if words[k] is not None else ends[k] for k in range(9)]
        self._index_rotaries(ends, block.line_number)
        self.canon.STRAIGHT_TRAVERSE(block.line_number, *ends)
        self.current = list(ends)

    def _index_rotaries(self, ends: list[float], line: int) -> None:
        for k, jnum in (
            (3, self.a_indexer_jnum),
            (4, self.b_indexer_jnum),
            (5, self.c_indexer_jnum),
        ):
            if ends[k] != self.current[k] and jnum != -1:
                self.issue_straight_index(k, jnum, ends[k], line)

    def issue_straight_index(self, axis: int, jnum: int, target: float, line: int) -> None:
        canon = self.canon
        save_mode = canon.GET_EXTERNAL_MOTION_CONTROL_MODE()
        save_tol = canon.GET_EXTERNAL_MOTION_CONTROL_TOLERANCE()
        save_cam = canon.GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE()
        if save_mode != C.EXACT_PATH:
            canon.SET_MOTION_CONTROL_MODE(C.EXACT_PATH, 0)
        target_pose = list(self.current)
        target_pose[axis] = target
        canon.STRAIGHT_TRAVERSE(line, *target_pose)
        if save_mode != C.EXACT_PATH:
            canon.SET_MOTION_CONTROL_MODE(save_mode, save_tol)
            canon.SET_NAIVECAM_TOLERANCE(save_cam)
        self.current[axis] = target

    def convert_setup(self, block: Block) -> None:
        """G10 L2 / L20: set a coordinate system's origin."""
        if block.i_flag or block.j_flag:
            raise InterpError("I J words not allowed with G10 L2")
        pars = self.parameters
        p_int = int(block.p_number + 0.0001)
        if p_int == 0:
            p_int = self.origin_index
        l20 = block.l_number == 20
        for letter, wrapped in (
            ("a", self.a_axis_wrapped),
            ("b", self.b_axis_wrapped),
            ("c", self.c_axis_wrapped),
        ):
            value = getattr(block, letter + "_number")
            if (
                l20
                and getattr(block, letter + "_flag")
                and wrapped
                and (value <= -360.0 or value >= 360.0)
            ):
                raise InterpError(wrapped_msg(value, letter.upper()))
        if self.cutter_comp_side and p_int == self.origin_index:
            raise InterpError(
                "Cannot change the active coordinate system with cutter radius compensation on"
            )
        cs = self.find_current_in_system(p_int)
        base = 5200 + p_int * 20
        if block.r_flag:
            if l20:
                raise InterpError("R not allowed in G10 L20")
            r = block.r_number
            pars[base + 10] = r
        else:
            r = pars[base + 10]
        if l20:
            oldx, oldy = rotate(cs[0], cs[1], r)
            x = block.x_number if block.x_flag else cs[0]
            y = block.y_number if block.y_flag else cs[1]
            x, y = rotate(x, y, r)
            x = oldx + self.u2p_len(pars[base + 1]) - x
            y = oldy + self.u2p_len(pars[base + 2]) - y
            pars[base + 1] = self.p2u_len(x)
            pars[base + 2] = self.p2u_len(y)
            if p_int == self.origin_index:
                self.current[0], self.current[1] = rotate(
                    self.current[0], self.current[1], self.rotation_xy
                )
                self.rotation_xy = 0.0
        else:
            if block.x_flag:
                x = block.x_number
                pars[base + 1] = self.p2u_len(x)
            else:
                x = self.u2p_len(pars[base + 1])
            if block.y_flag:
                y = block.y_number
                pars[base + 2] = self.p2u_len(y)
            else:
                y = self.u2p_len(pars[base + 2])
        values = [x, y]
        for k, letter in ((2, "z"), (3, "a"), (4, "b"), (5, "c"), (6, "u"), (7, "v"), (8, "w")):
            linear = k not in (3, 4, 5)
            if getattr(block, letter + "_flag"):
                v = getattr(block, letter + "_number")
                if l20:
                    stored = self.u2p_len(pars[base + 1 + k]) if linear else pars[base + 1 + k]
                    v = cs[k] + stored - v
                pars[base + 1 + k] = self.p2u_len(v) if linear else v
            else:
                v = self.u2p_len(pars[base + 1 + k]) if linear else pars[base + 1 + k]
            values.append(v)
        if p_int == self.origin_index:
            cur = self.current
            cur[0], cur[1] = rotate(cur[0], cur[1], self.rotation_xy)
            for k in range(9):
                cur[k] += self.origin_offset[k]
            self.origin_offset = list(values)
            for k in range(9):
                cur[k] -= values[k]
            self.canon.SET_G5X_OFFSET(p_int, *values)
            cur[0], cur[1] = rotate(cur[0], cur[1], -r)
            self.rotation_xy = r
            self.canon.SET_XY_ROTATION(self.rotation_xy)
        else:
            self._enq("COMMENT", "interpreter: setting coordinate system origin")
