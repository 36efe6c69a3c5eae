"""Toolpath preview: a program run through an interpreter of its own (GUI-022, ARCH-014).

The preview interpreter is created with ``task=0`` (``#<_task>`` = 0) and talks only to
``CollectingCanon``, which records the tool's moves and sends nothing anywhere: the preview
never moves the machine. Moves are in work coordinates (as the DRO's "Work" column), in
machine units. The first error stops the preview and is reported with its line. The
machine's parameter file is read (offsets, G28 positions ...) but never written.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from pathlib import Path
from typing import Any

from iocontrol.tooltable import ToolTable
from task.interp.canon import (
    PLANE_XY,
    PLANE_YZ,
    UNITS_INCHES,
    UNITS_MM,
    PrintingCanon,
)
from task.interp.errors import INTERP_ENDFILE, INTERP_EXIT, InterpError
from task.interp.interp import Interpreter

RAPID, FEED = 0, 1
MAX_POINTS = 200_000  # a bigger program is drawn up to here, and said to be cut short
ARC_STEP_RAD = math.radians(6)  # arcs are drawn as chords of at most this angle
MM_PER_INCH = 25.4


class CollectingCanon(PrintingCanon):
    """A canon that keeps the end point of every move: [x, y, z, kind, line]."""

    def __init__(self, tools: ToolTable, units_per_mm: float) -> None:
        super().__init__(lambda text: None, tools)
        self.units_per_mm = units_per_mm
        if units_per_mm != 1.0:
            self.length_unit_type = UNITS_INCHES  # the interpreter starts in machine units
        self.points: list[list[float]] = []

    def _factor(self) -> float:
        """Program units -> machine units."""
        return (MM_PER_INCH if self.length_unit_type == UNITS_INCHES else 1.0) * self.units_per_mm

    def _add(self, kind: int, line: int, x: float, y: float, z: float) -> None:
        if len(self.points) >= MAX_POINTS:
            raise PreviewTooLongError
        f = self._factor()
        self.points.append([round(x * f, 4), round(y * f, 4), round(z * f, 4), kind, line])

    def STRAIGHT_TRAVERSE(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        self._add(RAPID, line, x, y, z)
        self.position = [x, y, z, a, b, c]

    def STRAIGHT_FEED(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        self._add(FEED, line, x, y, z)
        self.position = [x, y, z, a, b, c]

    def STRAIGHT_PROBE(self, line, x, y, z, a, b, c, u, v, w, probe_type) -> None:
        self._add(FEED, line, x, y, z)
        super().STRAIGHT_PROBE(line, x, y, z, a, b, c, u, v, w, probe_type)

    def ARC_FEED(
        self, line, first_end, second_end, first_axis, second_axis, rotation, axis_end,
        a, b, c, u=0.0, v=0.0, w=0.0,
    ) -> None:  # fmt: skip
        """An arc (helix) in the active plane, as chords."""
        start = self.position
        plane = self.active_plane
        if plane == PLANE_XY:
            first, second, axis = start[0], start[1], start[2]
        elif plane == PLANE_YZ:
            first, second, axis = start[1], start[2], start[0]
        else:  # XZ: first is Z, second X
            first, second, axis = start[2], start[0], start[1]
        radius = math.hypot(first - first_axis, second - second_axis)
        begin = math.atan2(second - second_axis, first - first_axis)
        end = math.atan2(second_end - second_axis, first_end - first_axis)
        turns = abs(rotation) - 1 if rotation else 0
        if rotation > 0:  # counterclockwise
            if end <= begin:
                end += 2 * math.pi
            end += 2 * math.pi * turns
        else:
            if end >= begin:
                end -= 2 * math.pi
            end -= 2 * math.pi * turns
        steps = max(1, math.ceil(abs(end - begin) / ARC_STEP_RAD))
        for step in range(1, steps + 1):
            t = step / steps
            angle = begin + (end - begin) * t
            p = first_axis + radius * math.cos(angle)
            q = second_axis + radius * math.sin(angle)
            h = axis + (axis_end - axis) * t
            if step == steps:
                p, q, h = first_end, second_end, axis_end
            if plane == PLANE_XY:
                self._add(FEED, line, p, q, h)
            elif plane == PLANE_YZ:
                self._add(FEED, line, h, p, q)
            else:
                self._add(FEED, line, q, h, p)
        super().ARC_FEED(
            line, first_end, second_end, first_axis, second_axis, rotation, axis_end, a, b, c
        )

    def USER_DEFINED_FUNCTION(self, index: int, p: float, q: float) -> bool:
        return True  # M100..M199 do nothing in a preview


class PreviewTooLongError(Exception):
    """The program has more moves than the preview draws."""


def preview(
    program: str,
    *,
    units_per_mm: float = 1.0,
    parameter_file: str = "",
    tool_table: str | None = None,
    ini: Any = None,
) -> dict[str, Any]:
    """The moves of ``program``: {"points": [[x, y, z, kind, line], ...], "error": None or
    {"line", "message"}, "is_truncated": bool}."""
    tools = ToolTable()
    if tool_table and Path(tool_table).is_file():
        tools.load(tool_table, strict=False)
    canon = CollectingCanon(tools, units_per_mm)
    error = None
    is_truncated = False
    # The interpreter writes its parameter file (init() saves it): it gets a private copy,
    # never the machine's, which task owns.
    with tempfile.TemporaryDirectory(prefix="cnc-preview-") as folder:
        private = Path(folder) / "preview.var"
        if parameter_file and Path(parameter_file).is_file():
            shutil.copyfile(parameter_file, private)
        interp = Interpreter(canon, ini=ini, parameter_file=str(private), task=0)
        try:
            interp.init()
            canon.USE_LENGTH_UNITS(UNITS_MM if units_per_mm == 1.0 else UNITS_INCHES)
            interp.open(program)
            while interp.read() != INTERP_ENDFILE:
                if interp.execute() == INTERP_EXIT:
                    break
        except PreviewTooLongError:
            is_truncated = True
        except InterpError as exc:
            error = {"line": interp.sequence_number, "message": exc.message}
        finally:
            interp.close()
            interp.release_python()  # (the INI's [PYTHON] plug-in, for its remaps)
    return {"points": canon.points, "error": error, "is_truncated": is_truncated}
