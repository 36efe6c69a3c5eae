"""Tools: T, M6, M61, G43/G43.1/G43.2/G49, G10 L1/L10/L11 and #5400..#5413 (TOOL-017..027)."""

from __future__ import annotations

from . import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from .block import (
    G_43,
    G_43_1,
    G_49,
    Block,
)
from .common import (
    axis_words,
    is_near_int,
    rotate,
)
from .errors import InterpError


class ToolsMixin:
    """Tool conversions; mixed into the Interpreter."""

    # ================================================================== tools
    def load_tool_table(self) -> None:
        canon = self.canon
        self.tool_table = _ToolTableView(canon)
        self.set_tool_parameters()

    def find_tool_index(self, toolno: int) -> int:
        idx = self.canon.find_tool_index(toolno)
        if idx == -1:
            raise InterpError(f"Requested tool {toolno} not found in the tool table")
        return idx

    def find_tool_pocket(self, toolno: int) -> tuple[int, int]:
        """(status, pocket number in the tool table) of ``toolno`` (Python's
        find_tool_pocket): INTERP_ERROR and pocket 0 when the table has no such tool."""
        idx = self.canon.find_tool_index(toolno)
        if idx == -1:
            self.saved_error = f"Requested tool {toolno} not found in the tool table"
            return 5, 0  # INTERP_ERROR
        return 0, self.tool_table[idx].pocketno

    def convert_tool_select(self, block: Block) -> None:
        idx = self.find_tool_index(block.t_number)
        self.canon.SELECT_TOOL(block.t_number)
        self.selected_pocket = idx
        self.selected_tool = block.t_number

    def convert_tool_change(self) -> None:
        if self.selected_pocket < 0:
            raise InterpError("Need tool prepared -Txx- for toolchange")
        if self.cutter_comp_side:
            raise InterpError("Cannot change tools with cutter radius compensation on")
        canon = self.canon
        canon.START_CHANGE()
        if not self.tool_change_with_spindle_on:
            for s in range(self.num_spindles):
                canon.STOP_SPINDLE_TURNING(s)
                self.spindle_turning[s] = C.STOPPED
        if self.tool_change_quill_up:
            up_z = self.find_relative([0.0] * 9)[2]
            canon.COMMENT("AXIS,hide")
            pose = list(self.current)
            pose[2] = up_z
            canon.STRAIGHT_TRAVERSE(-1, *pose)
            canon.COMMENT("AXIS,show")
            self.current[2] = up_z
        if self.tool_change_at_g30:
            ends = self.find_relative(self._u2p_pose(self.parameters[5181:5190]))
            canon.COMMENT("AXIS,hide")
            self._index_rotaries(ends, -1)
            canon.STRAIGHT_TRAVERSE(-1, *ends)
            canon.COMMENT("AXIS,show")
            self.current = list(ends)
        canon.CHANGE_TOOL(self.selected_pocket)
        self.current_pocket = self.selected_pocket
        self.toolchange_flag = True
        self.set_tool_parameters()

    def convert_tool_length_offset(self, g_code: int, block: Block) -> None:
        if self.cutter_comp_side:
            raise InterpError("Cannot change tool offset with cutter radius compensation on")
        if g_code == G_49:
            offset = [0.0] * 9
        elif g_code == G_43:
            if block.h_flag:
                idx = self.find_tool_index(block.h_number)
                if idx == 0 and self.random_toolchanger:
                    idx = self.current_pocket
            elif self.toolchange_flag:
                idx = self.current_pocket
            else:
                idx = 0
            offset = self._u2p_pose(self.tool_table[idx].offset)
        elif g_code == G_43_1:
            offset = list(self.tool_offset)
            for k, value in enumerate(axis_words(block)):
                if value is not None:
                    offset[k] = value
        else:
            has_axes = any(w is not None for w in axis_words(block))
            if block.h_flag and has_axes:
                raise InterpError("G43.2: Can not have both H and axis words")
            if not block.h_flag and not has_axes:
                raise InterpError("G43.2: No axes specified and H word missing")
            idx = self.find_tool_index(block.h_number)
            offset = list(self.tool_offset)
            if block.h_flag:
                add = self._u2p_pose(self.tool_table[idx].offset)
            else:
                add = [w if w is not None else 0.0 for w in axis_words(block)]
            for k in range(9):
                offset[k] += add[k]
        self.canon.USE_TOOL_LENGTH_OFFSET(offset)
        old = self.tool_offset
        dx, dy = rotate(old[0] - offset[0], old[1] - offset[1], -self.rotation_xy)
        cur = self.current
        cur[0] += dx
        cur[1] += dy
        for k in range(2, 9):
            cur[k] += old[k] - offset[k]
        self.tool_offset = offset
        # #5081-#5089: the offset now applied, in user units (LinuxCNC 2.9.10; #5401-#5409
        # stay the loaded tool's stored offset)
        p2u = self.p2u_len
        self.parameters[5081:5090] = [
            *(p2u(v) for v in offset[:3]),
            *offset[3:6],
            *(p2u(v) for v in offset[6:]),
        ]

    def convert_setup_tool(self, block: Block) -> None:
        """G10 L1 / L10 / L11: change a tool table entry."""
        direct = block.l_number == 1
        _, toolno = is_near_int(block.p_number)
        idx = self.find_tool_index(toolno)
        words = axis_words(block)
        if not (
            any(w is not None for w in words)
            or block.r_flag
            or block.q_flag
            or block.i_flag
            or block.j_flag
        ):
            raise InterpError("G10 L1 without offsets has no effect")
        entry = self.tool_table[idx]
        toff = list(entry.offset)
        if direct:
            for k, value in enumerate(words):
                if value is not None:
                    toff[k] = self.p2u_len(value) if k not in (3, 4, 5) else value
        else:
            to_fixture = block.l_number == 11
            dest = 9 if to_fixture else self.origin_index
            t = self.find_current_in_system(dest, with_tlo=True)
            pars = self.parameters
            if to_fixture and pars[5210]:
                g92 = self._u2p_pose(pars[5211:5220])
                for k in range(9):
                    t[k] += g92[k]
            rot = pars[5210 + dest * 20]
            if block.x_flag and block.y_flag:
                tx, ty = rotate(t[0] - block.x_number, t[1] - block.y_number, rot)
                toff[0], toff[1] = self.p2u_len(tx), self.p2u_len(ty)
            elif block.x_flag or block.y_flag:
                ox, oy = rotate(self.u2p_len(toff[0]), self.u2p_len(toff[1]), -rot)
                if block.x_flag:
                    ox = 0.0
                    tx, ty = t[0] - block.x_number, 0.0
                else:
                    oy = 0.0
                    tx, ty = 0.0, t[1] - block.y_number
                ox, oy = rotate(ox, oy, rot)
                tx, ty = rotate(tx, ty, rot)
                toff[0], toff[1] = self.p2u_len(tx + ox), self.p2u_len(ty + oy)
            for k in range(2, 9):
                if words[k] is not None:
                    value = t[k] - words[k]
                    toff[k] = self.p2u_len(value) if k not in (3, 4, 5) else value
        entry.offset = toff
        if block.r_flag:
            entry.diameter = self.p2u_len(block.r_number) * 2.0
        if block.i_flag:
            entry.frontangle = block.i_number
        if block.j_flag:
            entry.backangle = block.j_number
        if block.q_number != -1.0:
            ok, q = is_near_int(block.q_number)
            if not ok:
                raise InterpError("Q number in G10 is not an integer")
            if q > 9:
                raise InterpError("Invalid tool orientation")
            entry.orientation = q
        self.tool_table.set(idx, entry)
        canon = self.canon
        canon.SET_TOOL_TABLE_ENTRY(
            idx,
            entry.toolno,
            entry.offset,
            entry.diameter,
            entry.frontangle,
            entry.backangle,
            entry.orientation,
        )
        if not self.random_toolchanger and self.current_pocket == idx:
            self.tool_table.set(0, entry)
        spindle = self.tool_table[0]
        pars = self.parameters
        if self.random_toolchanger:
            pars[5400] = float(spindle.toolno if spindle.toolno >= 0 else -1)
        else:
            pars[5400] = float(spindle.toolno if spindle.toolno > 0 else 0)
        self._set_tool_params_from(spindle)
        if not self.random_toolchanger and idx == self.current_pocket:
            canon.SET_TOOL_TABLE_ENTRY(
                0,
                entry.toolno,
                entry.offset,
                entry.diameter,
                entry.frontangle,
                entry.backangle,
                entry.orientation,
            )

    def _set_tool_params_from(self, entry) -> None:
        pars = self.parameters
        pars[5401:5410] = entry.offset
        pars[5410] = entry.diameter
        pars[5411] = entry.frontangle
        pars[5412] = entry.backangle
        pars[5413] = entry.orientation

    def set_tool_parameters(self) -> None:
        spindle = self.tool_table[0]
        if not self.random_toolchanger and spindle.toolno <= 0:
            self.default_tool_parameters()
            return
        self.parameters[5400] = float(spindle.toolno)
        self._set_tool_params_from(spindle)

    def default_tool_parameters(self) -> None:
        self.parameters[5400:5414] = [0.0] * 14

    def init_tool_parameters(self) -> None:
        if self.random_toolchanger:
            spindle = self.tool_table[0]
            self.parameters[5400] = float(spindle.toolno)
            self._set_tool_params_from(spindle)
        elif self.tool_table[0].toolno == -1:
            self.default_tool_parameters()


class _ToolTableView:
    """The interpreter's copy of the tool table (``settings.tool_table``), taken lazily."""

    def __init__(self, canon) -> None:
        self._canon = canon
        self._entries: dict = {}

    def __getitem__(self, idx: int):
        entry = self._entries.get(idx)
        if entry is None:
            entry = self._canon.GET_EXTERNAL_TOOL_TABLE(idx)
            self._entries[idx] = entry
        return entry.copy()

    def set(self, idx: int, entry) -> None:
        self._entries[idx] = entry.copy()
