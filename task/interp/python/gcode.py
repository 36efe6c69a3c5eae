"""The ``gcode`` module: LinuxCNC's preview interpreter for UIs (GUI-022, REMAP-057).

``parse(filename, canon, unitcode, initcode[, interpname])`` (or ``parse(filename, canon,
initcodes)`` with a list of initial codes) runs a program through an interpreter of its own
and calls ``canon``'s lower-case methods for what a preview draws (``straight_feed``,
``arc_feed``, ``next_line`` ...), positions in inches as LinuxCNC gives them; it returns
``(status, last line number)``, and ``strerror(status)`` the last error's message.

The preview never moves the machine: ``#<_task>`` is 0 (a remap procedure tests it to skip
what only a machine can do, e.g. probing), there is no ``emctask`` module, and
``__delete__`` is not called (use ``atexit``). The INI named by ``$INI_FILE_NAME`` gives the
remaps and the ``[PYTHON]`` plug-in, as for LinuxCNC's preview.
"""

from __future__ import annotations

import os

from ..canon import UNITS_INCHES, UNITS_MM, PrintingCanon
from ..errors import (
    INTERP_ERROR,
    INTERP_EXECUTE_FINISH,
    INTERP_MIN_ERROR,
    INTERP_OK,
    InterpError,
)

MIN_ERROR = INTERP_MIN_ERROR
_last_error = ""
_POCKETS_MAX = 1000


class LineCode:
    """What ``next_line`` receives: the modal state at the start of a line."""

    def __init__(self, gcodes: list[int], mcodes: list[int], settings: list[float]) -> None:
        self.gcodes = tuple(gcodes)
        self.mcodes = tuple(mcodes)
        self.sequence_number = gcodes[0]
        self.feed_rate = settings[1]
        self.speed = settings[2]
        (
            self.motion_mode,
            self.block,
            self.plane,
            self.cutter_side,
            self.units,
            self.distance_mode,
            self.feed_mode,
            self.origin,
            self.tool_length_offset,
            self.retract_mode,
            self.path_mode,
        ) = gcodes[1:12]
        (
            self.stopping,
            self.spindle,
            self.toolchange,
            self.mist,
            self.flood,
            self.overrides,
        ) = mcodes[1:7]


class _CallbackCanon(PrintingCanon):
    """The canon of a preview: the world model of rs274's, drawing through the callback."""

    def __init__(self, callback) -> None:
        super().__init__(lambda text: None)
        self.callback = callback
        self.interp = None
        self.metric = False
        self.last_line = -1
        self._tools: dict[int, object] = {}

    # --------------------------------------------------------------- lines
    def new_line(self, line: int | None = None) -> None:
        interp = self.interp
        if interp is None:
            return
        number = interp.sequence_number if line is None else line
        if number == self.last_line:
            return
        self.last_line = number
        gcodes = interp.active_g_codes()
        gcodes[0] = number
        self.callback.next_line(LineCode(gcodes, interp.active_m_codes(), interp.active_settings()))

    def _inches(self, values) -> list[float]:
        if not self.metric:
            return list(values)
        return [v / 25.4 if k in (0, 1, 2, 6, 7, 8) else v for k, v in enumerate(values)]

    # -------------------------------------------------------------- motion
    def STRAIGHT_TRAVERSE(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        super().STRAIGHT_TRAVERSE(line, x, y, z, a, b, c, u, v, w)
        self.new_line(line)
        self.callback.straight_traverse(*self._inches((x, y, z, a, b, c, u, v, w)))

    def STRAIGHT_FEED(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        super().STRAIGHT_FEED(line, x, y, z, a, b, c, u, v, w)
        self.new_line(line)
        self.callback.straight_feed(*self._inches((x, y, z, a, b, c, u, v, w)))

    def STRAIGHT_PROBE(self, line, x, y, z, a, b, c, u, v, w, probe_type) -> None:
        super().STRAIGHT_PROBE(line, x, y, z, a, b, c, u, v, w, probe_type)
        self.new_line(line)
        self.callback.straight_probe(*self._inches((x, y, z, a, b, c, u, v, w)))

    def ARC_FEED(self, line, e1, e2, a1, a2, rotation, axis_end, a, b, c, u=0.0, v=0.0, w=0.0):
        super().ARC_FEED(line, e1, e2, a1, a2, rotation, axis_end, a, b, c, u, v, w)
        scale = 1 / 25.4 if self.metric else 1.0
        self.new_line(line)
        self.callback.arc_feed(
            e1 * scale,
            e2 * scale,
            a1 * scale,
            a2 * scale,
            rotation,
            axis_end * scale,
            a,
            b,
            c,
            u * scale,
            v * scale,
            w * scale,
        )

    def RIGID_TAP(self, line, x, y, z, scale) -> None:
        self.new_line(line)
        self.callback.rigid_tap(*self._inches((x, y, z))[:3])

    def NURBS_FEED(self, line, points, order) -> None:
        for x, y, _ in points:
            self.STRAIGHT_FEED(line, x, y, *self.position[2:6])

    # --------------------------------------------------------------- state
    def USE_LENGTH_UNITS(self, units: int) -> None:
        super().USE_LENGTH_UNITS(units)
        self.metric = units == UNITS_MM

    def SET_G5X_OFFSET(self, index, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        super().SET_G5X_OFFSET(index, x, y, z, a, b, c, u, v, w)
        self.new_line()
        self.callback.set_g5x_offset(index, *self._inches((x, y, z, a, b, c, u, v, w)))

    def SET_G92_OFFSET(self, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        super().SET_G92_OFFSET(x, y, z, a, b, c, u, v, w)
        self.new_line()
        self.callback.set_g92_offset(*self._inches((x, y, z, a, b, c, u, v, w)))

    def SET_XY_ROTATION(self, t: float) -> None:
        self.new_line()
        self.callback.set_xy_rotation(t)

    def SELECT_PLANE(self, plane: int) -> None:
        super().SELECT_PLANE(plane)
        self.new_line()
        self.callback.set_plane(plane)

    def SET_TRAVERSE_RATE(self, rate: float) -> None:
        self.new_line()
        self.callback.set_traverse_rate(rate)

    def SET_FEED_RATE(self, rate: float) -> None:
        super().SET_FEED_RATE(rate)
        self.new_line()
        self.callback.set_feed_rate(rate / 25.4 if self.metric else rate)

    def CHANGE_TOOL(self, slot: int) -> None:
        self.new_line()
        self.callback.change_tool(slot)

    def DWELL(self, seconds: float) -> None:
        self.new_line()
        self.callback.dwell(seconds)

    def MESSAGE(self, text: str) -> None:
        self.new_line()
        self.callback.message(text)

    def COMMENT(self, text: str) -> None:
        self.new_line()
        self.callback.comment(text)

    def USE_TOOL_LENGTH_OFFSET(self, offset) -> None:
        super().USE_TOOL_LENGTH_OFFSET(offset)
        self.new_line()
        self.callback.tool_offset(*self._inches(offset))

    def USER_DEFINED_FUNCTION(self, index: int, p: float, q: float) -> bool:
        self.new_line()
        function = getattr(self.callback, "user_defined_function", None)
        if function is not None:
            function(index, p, q)
        return True

    # ------------------------------------------------------- information
    def GET_BLOCK_DELETE(self) -> bool:
        return bool(self.callback.get_block_delete())

    def GET_EXTERNAL_LENGTH_UNITS(self) -> float:
        return float(self.callback.get_external_length_units())

    def GET_EXTERNAL_ANGLE_UNITS(self) -> float:
        return float(self.callback.get_external_angular_units())

    def GET_EXTERNAL_LENGTH_UNIT_TYPE(self) -> int:
        return UNITS_INCHES

    def GET_EXTERNAL_AXIS_MASK(self) -> int:
        return int(self.callback.get_axis_mask())

    def GET_EXTERNAL_TOOL_TABLE(self, idx: int):
        from iocontrol.tooltable import ToolEntry

        entry = self._tools.get(idx)
        if entry is None:
            values = self.callback.get_tool(idx)
            entry = ToolEntry(
                toolno=int(values[0]),
                pocketno=idx,
                offset=[float(v) for v in values[1:10]],
                diameter=float(values[10]),
                frontangle=float(values[11]),
                backangle=float(values[12]),
                orientation=int(values[13]),
            )
            self._tools[idx] = entry
        return entry.copy()

    def find_tool_index(self, toolno: int) -> int:
        if toolno == 0:
            return 0
        for idx in range(_POCKETS_MAX):
            if self.GET_EXTERNAL_TOOL_TABLE(idx).toolno == toolno:
                return idx
        return -1


def parse(filename: str, canon, unitcode="", initcode="", interpname: str = "") -> tuple:
    """Preview ``filename`` through ``canon``; ``(status, last line number)``.
    (``interpname``, a pluggable interpreter of LinuxCNC's, is not supported: ignored.)"""
    global _last_error
    from cnc.ini import IniError, IniFile

    from ..interp import Interpreter

    initcodes = list(unitcode) if isinstance(unitcode, list) else None
    adapter = _CallbackCanon(canon)
    ini = None
    ini_path = os.environ.get("INI_FILE_NAME")
    if ini_path:
        try:
            ini = IniFile.load(ini_path)
        except IniError as error:
            _last_error = str(error)
            return INTERP_ERROR, 0
    parameter_file = getattr(canon, "parameter_file", "") or ""
    if not isinstance(parameter_file, str | os.PathLike):
        _last_error = f"canon.parameter_file is no file name: {parameter_file!r}"
        return INTERP_ERROR, 0
    interp = Interpreter(adapter, ini=ini, parameter_file=str(parameter_file), task=0)
    status = INTERP_OK
    error_offset = 0
    try:
        interp.init()
        adapter.interp = interp  # (next_line from here on)
        interp.open(filename)
        adapter.new_line()
        codes = initcodes if initcodes is not None else [unitcode, initcode]
        for code in codes:
            if code:
                interp.read(code)
                status = interp.execute()
        while status in (INTERP_OK, INTERP_EXECUTE_FINISH):
            error_offset = 1
            status = interp.read()
            if status not in (INTERP_OK, INTERP_EXECUTE_FINISH):
                break
            error_offset = 0
            status = interp.execute()
    except InterpError as error:
        _last_error = error.message
        status = INTERP_ERROR
    finally:
        interp.use_lazy_close = False
        interp.close()
        interp.release_python()  # (no __delete__ in a preview)
    adapter.new_line()
    return status, adapter.last_line + error_offset


def strerror(status: int) -> str:
    """The message of the last error (``parse`` returned ``status``)."""
    return _last_error
