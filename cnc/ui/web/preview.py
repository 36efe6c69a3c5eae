"""Toolpath preview: a program run through an interpreter of its own (GUI-022, ARCH-014).

The preview interpreter is created with ``task=0`` (``#<_task>`` = 0) and talks only to
``CollectingCanon``, which records the tool's moves and sends nothing anywhere: the preview
never moves the machine. Moves are in work coordinates (as the DRO's "Work" column), in
machine units. The first error stops the preview and is reported with its line (a check,
``is_checking_all``, goes on after errors and reports each). The machine's parameter file
is read (offsets, G28 positions ...) but never written.

The toolpath is a binary stream of ``RECORD``s, 16 bytes each: x, y, z (float32, little
endian) and ``line << 1 | kind``; the first is the start (the origin), each next one the
end of a move from the one before (a line strip). The page uploads these bytes to the
graphics card as they are; ``decode`` reads them back (tests). Large programs are given to
``sink`` in chunks as they are interpreted, so a page draws them while they load.
"""

from __future__ import annotations

import math
import shutil
import struct
import tempfile
from collections.abc import Callable
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
RECORD = struct.Struct("<fffI")  # x, y, z, line << 1 | kind
MAX_POINTS = 5_000_000  # 80 MB of toolpath: a bigger program is drawn up to here
CHUNK_POINTS = 16_384  # records given to the sink at once
# Arcs are drawn as chords at most ARC_TOLERANCE_MM from the arc, each of at least
# MIN_ARC_STEP_RAD (at most 60 chords a turn) and at most MAX_ARC_STEP_RAD of it.
ARC_TOLERANCE_MM = 0.005
MIN_ARC_STEP_RAD = math.radians(6)
MAX_ARC_STEP_RAD = math.radians(45)
MAX_CHECK_ERRORS = 100  # a check stops reporting after this many
MM_PER_INCH = 25.4

Sink = Callable[[bytes], None]


class CollectingCanon(PrintingCanon):
    """A canon that writes the end point of every move as a ``RECORD`` to ``sink``."""

    def __init__(self, tools: ToolTable, units_per_mm: float, sink: Sink) -> None:
        super().__init__(lambda text: None, tools)
        self.units_per_mm = units_per_mm
        if units_per_mm != 1.0:
            self.length_unit_type = UNITS_INCHES  # the interpreter starts in machine units
        self.sink = sink
        self.point_count = 0
        self._records = bytearray()
        self._factor = self.factor()
        self._add(RAPID, 0, 0.0, 0.0, 0.0)  # where the first move starts

    def factor(self) -> float:
        """Program units -> machine units."""
        return (MM_PER_INCH if self.length_unit_type == UNITS_INCHES else 1.0) * self.units_per_mm

    def USE_LENGTH_UNITS(self, units: int) -> None:
        super().USE_LENGTH_UNITS(units)
        self._factor = self.factor()  # (once here, not for every point)

    def _add(self, kind: int, line: int, x: float, y: float, z: float) -> None:
        if self.point_count >= MAX_POINTS:
            raise PreviewTooLongError
        f = self._factor
        self._records += RECORD.pack(x * f, y * f, z * f, (line << 1 | kind) if line > 0 else kind)
        self.point_count += 1
        if len(self._records) >= CHUNK_POINTS * RECORD.size:
            self.flush_records()

    def flush_records(self) -> None:
        if self._records:
            self.sink(bytes(self._records))
            self._records.clear()

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
        steps = max(1, math.ceil(abs(end - begin) / _arc_step(radius * self._factor)))
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


def _arc_step(radius_mm: float) -> float:
    """The angle of one chord of an arc of this radius (millimetres)."""
    if radius_mm <= ARC_TOLERANCE_MM:
        return MAX_ARC_STEP_RAD
    step = 2 * math.acos(1 - ARC_TOLERANCE_MM / radius_mm)
    return min(max(step, MIN_ARC_STEP_RAD), MAX_ARC_STEP_RAD)


class PreviewTooLongError(Exception):
    """The program has more moves than the preview draws."""


def preview(
    program: str,
    sink: Sink,
    *,
    units_per_mm: float = 1.0,
    parameter_file: str = "",
    tool_table: str | None = None,
    ini: Any = None,
    is_checking_all: bool = False,
) -> dict[str, Any]:
    """Run ``program``, giving its toolpath to ``sink`` (``RECORD``s, in chunks); what
    happened: {"points": records given, "error": None or {"line", "message"} (the first),
    "errors": every error (``is_checking_all``: the interpreter goes on after each, as
    rs274 -n 0 does), "is_truncated": bool, "end_line": the last line read}."""
    tools = ToolTable()
    if tool_table and Path(tool_table).is_file():
        tools.load(tool_table, strict=False)
    canon = CollectingCanon(tools, units_per_mm, sink)
    errors: list[dict[str, Any]] = []
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
            while True:
                try:
                    if interp.read() == INTERP_ENDFILE or interp.execute() == INTERP_EXIT:
                        break
                except InterpError as exc:
                    line = interp.sequence_number
                    is_repeated = bool(errors) and errors[-1]["line"] == line
                    if not is_repeated:
                        errors.append({"line": line, "message": exc.message})
                    if not is_checking_all or is_repeated or len(errors) >= MAX_CHECK_ERRORS:
                        break
                    interp.reset()  # and on with the next line
        except PreviewTooLongError:
            is_truncated = True
        except InterpError as exc:  # init or open
            errors.append({"line": interp.sequence_number, "message": exc.message})
        finally:
            end_line = interp.sequence_number
            interp.close()
            interp.release_python()  # (the INI's [PYTHON] plug-in, for its remaps)
    canon.flush_records()
    return {
        "points": canon.point_count,
        "error": errors[0] if errors else None,
        "errors": errors,
        "is_truncated": is_truncated,
        "end_line": end_line,
    }


def decode(data: bytes) -> list[list[float]]:
    """``RECORD``s as [[x, y, z, kind, line], ...] (values as float32 holds them)."""
    points = []
    for x, y, z, tag in RECORD.iter_unpack(data):
        points.append([x, y, z, tag & 1, tag >> 1])
    return points
