"""Probing helpers (cnc/ui/web/probing.py) against a simulated part: each step's MDI line
moves a simulated probe, which stops where it touches the part, as G38.2 does; the result
must find the part's edges, corner, bore or boss centre, and the offsets set on confirm
must make the work coordinates read what the operator asked."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import pytest

from cnc.ui.web.probing import ProbeError, confirm_lines, make_plan, run_plan

TIP = 2.0  # probe tip diameter


@dataclass
class Part:
    """What the probe can touch: a box (x0, x1, y0, y1, top), a bore (cx, cy, radius) cut
    into it, or a boss (cx, cy, radius, top) standing on the table."""

    box: tuple[float, float, float, float, float] | None = None
    bore: tuple[float, float, float] | None = None
    boss: tuple[float, float, float, float] | None = None

    def is_inside(self, x: float, y: float, z: float) -> bool:
        """Whether the probe's tip, centred at (x, y, z), overlaps material."""
        r = TIP / 2
        if self.bore is not None:
            cx, cy, radius = self.bore
            return math.hypot(x - cx, y - cy) > radius - r
        if self.boss is not None:
            cx, cy, radius, top = self.boss
            return z < top and math.hypot(x - cx, y - cy) < radius + r
        x0, x1, y0, y1, top = self.box  # type: ignore[misc]
        return z < top and x0 - r < x < x1 + r and y0 - r < y < y1 + r


@dataclass
class Machine:
    """Position (machine coordinates = work coordinates: no offsets) and the last probe."""

    part: Part
    position: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    lines: list[str] = field(default_factory=list)
    probe_tripped: bool = False
    probed_position: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    g5x_offset: list[float] = field(default_factory=lambda: [0.0] * 9)
    g92_offset: list[float] = field(default_factory=lambda: [0.0] * 9)
    tool_offset: list[float] = field(default_factory=lambda: [0.0] * 9)
    rotation_xy: float = 0.0

    def mdi(self, line: str) -> None:
        self.lines.append(line)
        words = dict(re.findall(r"([XYZ])(-?[\d.]+)", line))
        target = list(self.position)
        for axis, value in words.items():
            target["XYZ".index(axis)] = float(value)
        if "G38" not in line:
            self.position = target
            return
        self.probe_tripped = False
        start = list(self.position)
        steps = 20_000
        for n in range(1, steps + 1):  # 1 um steps over a 20 mm move
            point = [a + (b - a) * n / steps for a, b in zip(start, target, strict=True)]
            if self.part.is_inside(*point):
                self.probe_tripped = True
                self.probed_position = point
                self.position = point
                return
            self.position = point
        if "G38.2" in line:
            raise ProbeError("G38.2 move finished without making contact")

    def status(self) -> Machine:
        return self


def run(machine: Machine, kind: str, **params):  # type: ignore[no-untyped-def]
    plan = make_plan(kind, {"tip_diameter": TIP, "search": 20.0, **params}, scale=1.0)
    return run_plan(plan, machine.mdi, machine.status, lambda index: None)


def test_an_edge_is_found_with_the_tips_radius() -> None:
    machine = Machine(Part(box=(10.0, 60.0, -20.0, 20.0, 0.0)), position=[0.0, 0.0, -2.0])
    found = run(machine, "edge", axis="X", direction=1)
    assert found["kind"] == "edge"
    assert found["axes"]["X"] == pytest.approx(10.0, abs=0.002)
    assert machine.lines[0] == "G90 G38.2 X20 F200"  # fast, from X0 towards +X
    assert machine.lines[2].endswith("F20")  # the measured touch is slow


def test_a_corner_from_outside_and_a_bore_and_a_boss_centre() -> None:
    outside = Machine(Part(box=(10.0, 60.0, 5.0, 50.0, 0.0)), position=[0.0, 0.0, -2.0])
    corner = run(outside, "corner", x_direction=1, y_direction=1, clearance=10.0)
    assert corner["axes"]["X"] == pytest.approx(10.0, abs=0.002)
    assert corner["axes"]["Y"] == pytest.approx(5.0, abs=0.002)
    assert outside.position[:2] == pytest.approx([0.0, 0.0])  # back at the start
    bore = Machine(Part(bore=(50.0, 40.0, 12.0)), position=[47.0, 42.0, -3.0])
    found = run(bore, "bore")
    assert found["axes"]["X"] == pytest.approx(50.0, abs=0.002)
    assert found["axes"]["Y"] == pytest.approx(40.0, abs=0.002)
    assert found["diameter"] == pytest.approx(24.0, abs=0.01)
    assert bore.position[:2] == pytest.approx([50.0, 40.0], abs=0.002)  # left in the centre
    boss = Machine(Part(boss=(30.0, 20.0, 8.0, 0.0)), position=[31.0, 19.0, 5.0])
    found = run(boss, "boss", boss_diameter=16.0, clearance=5.0, depth=8.0)
    assert found["axes"]["X"] == pytest.approx(30.0, abs=0.002)
    assert found["axes"]["Y"] == pytest.approx(20.0, abs=0.002)
    assert found["diameter"] == pytest.approx(16.0, abs=0.01)


def test_a_probe_that_touches_nothing_stops_the_helper() -> None:
    machine = Machine(Part(box=(100.0, 160.0, -20.0, 20.0, 0.0)), position=[0.0, 0.0, -2.0])
    with pytest.raises(ProbeError, match="without making contact"):
        run(machine, "edge", axis="X", direction=1)
    assert len(machine.lines) == 1  # nothing after the failed step


def test_confirmed_offsets_make_the_work_position_read_what_was_asked() -> None:
    """The edge at machine X 10 (with G92 X2 and a tool X offset 0.5 in force) is to read
    X 0 in G55: the G55 offset is 10 - 2 - 0.5 - 0 = 7.5, set in program units."""
    machine = Machine(Part())
    machine.g92_offset[0], machine.tool_offset[0] = 2.0, 0.5
    result = {"kind": "edge", "axes": {"X": 10.0}}
    lines = confirm_lines(result, {"system": "G55", "values": {"X": 0}}, machine, 1.0, None)
    assert lines == ["G10 L2 P2 X7.500000"]
    inch = confirm_lines(result, {"system": "G54", "values": {"X": 2.5}}, machine, 1 / 25.4, None)
    assert inch == [f"G10 L2 P1 X{5.0 / 25.4:.6f}"]


def test_a_tool_length_is_the_difference_to_the_reference_tools_touch() -> None:
    sensor = {"x": 100.0, "y": 50.0, "z": -10.0, "maxprobe": -30.0, "search_vel": 200.0,
              "probe_vel": 20.0}  # fmt: skip
    plan = make_plan("tool_length", {}, 1.0, sensor)
    machine = Machine(Part(box=(90.0, 110.0, 40.0, 60.0, -25.0)), position=[0.0, 0.0, 0.0])
    found = run_plan(plan, machine.mdi, machine.status, lambda index: None)
    assert machine.lines[:3] == ["G90 G53 G0 Z0", "G90 G53 G0 X100 Y50", "G90 G53 G0 Z-10"]
    assert found["touch_z"] == pytest.approx(-25.0, abs=0.002)
    (line,) = confirm_lines(found, {"tool": 3}, machine, 1.0, reference_z=-40.0)
    assert line.startswith("G10 L1 P3 Z") and float(line[11:]) == pytest.approx(15.0, abs=0.002)
    with pytest.raises(ProbeError, match="measure the reference tool first"):
        confirm_lines(found, {"tool": 3}, machine, 1.0, reference_z=None)
    with pytest.raises(ProbeError, match="no tool setter"):
        make_plan("tool_length", {}, 1.0, None)


def test_a_rotated_coordinate_system_is_refused() -> None:
    machine = Machine(Part(box=(10.0, 60.0, -20.0, 20.0, 0.0)))
    machine.rotation_xy = 30.0
    with pytest.raises(ProbeError, match="without rotation"):
        run(machine, "edge", axis="X", direction=1)
