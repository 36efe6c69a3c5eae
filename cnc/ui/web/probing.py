"""Probing helpers built on G38: edge, corner, bore or boss centre, tool length.

Each helper is a ``ProbePlan``: the MDI lines it sends, one ``Step`` at a time, each with
the words the page shows while it runs. A step that touches (``measure`` set) stores the
position where the probe tripped (``stat.probed_position``, machine coordinates). When every
step is done, ``plan.result(measured)`` turns the touches into what the operator is asked
to confirm: a work offset (``G10 L2``, for the coordinate system chosen) or a tool length
(``G10 L1``). Nothing is set before the operator confirms (``confirm_lines``).

Each line is made when its step comes, from the position then: absolute (G90) work
coordinates in the program units of the moment (lengths are converted from machine units
with the ``scale`` given), so that a helper stopped half way leaves no relative mode behind;
G91 is restored at the end if it was in force. A touch probes fast, backs off, probes again
slowly and backs off again: the slow touch is the one measured. Probing assumes no G5x
rotation (refused otherwise).

The tool length helper moves to the tool setter ([TOOLSENSOR] X Y Z, machine coordinates,
as gmoccapy has it) and probes down at most MAXPROBE. The length it proposes is the touch
height minus that of a reference tool (measured once with "reference": the reference tool's
length is 0), as tool setters are used with a master tool.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

AXES = "XYZ"
SYSTEMS = ("G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3")


class ProbeError(ValueError):
    """Bad helper parameters; str() says which and why."""


Found = dict[str, list[float]]  # "start" (machine position at the start) and the touches
LineMaker = Callable[[Found, Any], str]  # (touches so far, a polled stat) -> the MDI line


@dataclass(frozen=True)
class Step:
    text: str  # what the operator reads
    mdi: LineMaker  # makes the line sent
    measure: str | None = None  # the name the touch is stored under
    note: str | None = None  # the name the position before the step is stored under


@dataclass
class ProbePlan:
    kind: str
    steps: list[Step]
    result: Callable[[Found], dict[str, Any]]
    is_incremental: bool = False  # G91 was in force: sent back at the end


@dataclass
class Settings:
    """The helper's parameters, in machine units (lengths) and units per minute (feeds)."""

    fast_feed: float = 200.0
    slow_feed: float = 20.0
    search: float = 20.0  # how far a touch looks
    retract: float = 1.0  # how far it backs off between and after touches
    tip_diameter: float = 0.0
    clearance: float = 5.0  # boss: beyond its radius; corner: along the face
    depth: float = 5.0  # boss: how far below its top the probe touches its sides
    boss_diameter: float = 0.0


def _number(params: dict[str, Any], key: str, default: float, minimum: float = 0.0) -> float:
    value = params.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ProbeError(f"'{key}' must be a number")
    if value < minimum or value != value:
        raise ProbeError(f"'{key}' must be at least {minimum:g}")
    return float(value)


def read_settings(params: dict[str, Any]) -> Settings:
    return Settings(
        fast_feed=_number(params, "fast_feed", 200.0, 0.001),
        slow_feed=_number(params, "slow_feed", 20.0, 0.001),
        search=_number(params, "search", 20.0, 0.001),
        retract=_number(params, "retract", 1.0, 0.001),
        tip_diameter=_number(params, "tip_diameter", 0.0),
        clearance=_number(params, "clearance", 5.0, 0.001),
        depth=_number(params, "depth", 5.0, 0.001),
        boss_diameter=_number(params, "boss_diameter", 0.0),
    )


def _work(s: Any, index: int) -> float:
    """Where axis ``index`` is now in work coordinates (machine units; no rotation)."""
    return s.position[index] - s.g5x_offset[index] - s.g92_offset[index] - s.tool_offset[index]


class _Builder:
    """Collects the steps of a plan; lengths in machine units, written in program units."""

    def __init__(self, scale: float) -> None:
        self.scale = scale  # program units per machine unit
        self.steps: list[Step] = []

    def _len(self, value: float) -> str:
        return f"{value * self.scale:.6f}".rstrip("0").rstrip(".") or "0"

    def _feed(self, value: float) -> str:
        return f"{value * self.scale:.4f}".rstrip("0").rstrip(".")

    def _by(self, s: Any, moves: dict[str, float]) -> str:
        """Axis words for a move by ``moves`` from where the machine is."""
        return " ".join(f"{a}{self._len(_work(s, AXES.index(a)) + d)}" for a, d in moves.items())

    def move(self, text: str, note: str | None = None, **moves: float) -> None:
        """A rapid by these distances (``note``: remember where it starts)."""
        self.steps.append(Step(text, lambda found, s: f"G90 G0 {self._by(s, moves)}", note=note))

    def probe(self, text: str, axis: str, distance: float, feed: float, code: str,
              measure: str | None = None) -> None:  # fmt: skip
        """A probe move by ``distance``: G38.2 (an error if nothing is touched) or G38.3
        (stops where something is touched, no error otherwise)."""

        def line(found: Found, s: Any) -> str:
            return f"G90 {code} {self._by(s, {axis: distance})} F{self._feed(feed)}"

        self.steps.append(Step(text, line, measure))

    def machine_move(self, text: str, **moves: float) -> None:
        """A rapid to machine coordinates (G53 needs G90)."""
        words = " ".join(f"{axis}{self._len(value)}" for axis, value in moves.items())
        self.steps.append(Step(text, lambda found, s: f"G90 G53 G0 {words}"))

    def move_to(self, text: str, where: Callable[[Found], dict[str, float]]) -> None:
        """A rapid to machine coordinates known once earlier steps have run."""

        def line(found: Found, s: Any) -> str:
            words = " ".join(f"{axis}{self._len(value)}" for axis, value in where(found).items())
            return f"G90 G53 G0 {words}"

        self.steps.append(Step(text, line))

    def bore_sides(self, axis: str, name: str, s: Settings) -> None:
        """From inside a bore: touch its wall towards + (``<name>_plus``) and - ."""
        self.touch(f"{name}_plus", axis, 1, s, s.search)
        self.touch(f"{name}_minus", axis, -1, s, 2 * s.search)

    def boss_sides(self, axis: str, name: str, s: Settings) -> None:
        """From above a boss: for its + and - side, out beyond it, down (G38.3: stops,
        without an error, on anything in the way), touch inwards, up, back over it."""
        out = s.boss_diameter / 2 + s.clearance
        for side, direction in (("plus", -1), ("minus", 1)):
            sign = "+" if side == "plus" else "-"
            over = f"over_{name}_{side}"
            self.move(f"Out beyond the {axis}{sign} side", note=over, **{axis: -direction * out})
            self.probe("Down beside the boss", "Z", -s.depth, s.fast_feed, "G38.3")
            self.touch(f"{name}_{side}", axis, direction, s, out)
            self.move("Up", Z=s.depth)
            self.move_to("Back over the boss", lambda found, over=over: _xy(found[over]))

    def back_to_start(self) -> None:
        self.move_to("Back to the start", lambda found: _xy(found["start"]))

    def touch(self, name: str, axis: str, direction: int, s: Settings, reach: float) -> None:
        """Fast probe, back off, slow probe (measured), back off."""
        sign = "+" if direction > 0 else "-"
        back = -direction * s.retract
        self.probe(f"Probe {axis}{sign} (fast)", axis, direction * reach, s.fast_feed, "G38.2")
        self.move(f"Back off {axis}", **{axis: back})
        self.probe(f"Probe {axis}{sign} (slow)", axis, direction * 2 * s.retract, s.slow_feed,
                   "G38.2", name)  # fmt: skip
        self.move(f"Back off {axis}", **{axis: back})


def _xy(position: list[float]) -> dict[str, float]:
    return {"X": position[0], "Y": position[1]}


def _middle(found: Found, name: str, index: int) -> float:
    """Halfway between the touches ``<name>_plus`` and ``<name>_minus``."""
    return (found[f"{name}_plus"][index] + found[f"{name}_minus"][index]) / 2


def _direction(params: dict[str, Any], key: str) -> int:
    value = params.get(key)
    if value not in (1, -1):
        raise ProbeError(f"'{key}' must be 1 or -1")
    return int(value)


def _axis(params: dict[str, Any]) -> str:
    axis = str(params.get("axis", "")).upper()
    if axis not in AXES:
        raise ProbeError("'axis' must be X, Y or Z")
    return axis


def make_plan(
    kind: str, params: dict[str, Any], scale: float, tool_sensor: dict[str, float] | None = None
) -> ProbePlan:
    """The plan of helper ``kind`` (edge, corner, bore, boss, tool_length)."""
    s = read_settings(params)
    b = _Builder(scale)
    radius = s.tip_diameter / 2
    if kind == "edge":
        axis, direction = _axis(params), _direction(params, "direction")
        b.touch("edge", axis, direction, s, s.search)
        index = AXES.index(axis)
        shift = direction * radius if axis != "Z" else 0.0

        def edge(found: Found) -> dict[str, Any]:
            return {"kind": "edge", "axes": {axis: found["edge"][index] + shift}}

        return ProbePlan(kind, b.steps, edge)
    if kind == "corner":
        x_dir, y_dir = _direction(params, "x_direction"), _direction(params, "y_direction")
        is_inside = bool(params.get("is_inside", False))
        # outside: the probe starts diagonally off the corner and steps along each face
        if not is_inside:
            b.move("Along the X face", Y=y_dir * s.clearance)
        b.touch("x", "X", x_dir, s, s.search)
        b.back_to_start()
        if not is_inside:
            b.move("Along the Y face", X=x_dir * s.clearance)
        b.touch("y", "Y", y_dir, s, s.search)
        b.back_to_start()

        def corner(found: Found) -> dict[str, Any]:
            return {
                "kind": "corner",
                "axes": {"X": found["x"][0] + x_dir * radius, "Y": found["y"][1] + y_dir * radius},
            }

        return ProbePlan(kind, b.steps, corner)
    if kind in ("bore", "boss"):
        # X, to the X centre, Y (through the true centre: the true Y centre and size),
        # to the centre, X again (now through the centre: the true X size)
        is_bore = kind == "bore"
        if not is_bore and s.boss_diameter <= 0:
            raise ProbeError("'boss_diameter' must be given (about, for the approach)")
        touch_sides = b.bore_sides if is_bore else b.boss_sides
        touch_sides("X", "x1", s)
        b.move_to("To the centre in X", lambda found: {"X": _middle(found, "x1", 0)})
        touch_sides("Y", "y", s)
        b.move_to("To the centre in Y", lambda found: {"Y": _middle(found, "y", 1)})
        touch_sides("X", "x", s)
        b.move_to("To the centre", lambda found: {"X": _middle(found, "x", 0),
                                                  "Y": _middle(found, "y", 1)})  # fmt: skip
        tip = s.tip_diameter if is_bore else -s.tip_diameter

        def centre(found: Found) -> dict[str, Any]:
            width_x = found["x_plus"][0] - found["x_minus"][0] + tip
            width_y = found["y_plus"][1] - found["y_minus"][1] + tip
            axes = {"X": _middle(found, "x", 0), "Y": _middle(found, "y", 1)}
            return {"kind": kind, "axes": axes, "diameter": round((width_x + width_y) / 2, 6)}

        return ProbePlan(kind, b.steps, centre)
    if kind == "tool_length":
        if tool_sensor is None:
            raise ProbeError("no tool setter: give [TOOLSENSOR] X Y Z MAXPROBE in the INI")
        sensor = tool_sensor
        search = abs(sensor["maxprobe"])
        # up (never down) to the setter's height, over it, then down to that height
        b.move_to("Up", lambda found: {"Z": max(found["start"][2], sensor["z"])})
        b.machine_move("Over the tool setter", X=sensor["x"], Y=sensor["y"])
        b.machine_move("Down to the tool setter's height", Z=sensor["z"])
        s_tool = Settings(fast_feed=sensor["search_vel"], slow_feed=sensor["probe_vel"],
                          search=search, retract=min(2.0, search / 4))  # fmt: skip
        b.touch("tool", "Z", -1, s_tool, search)
        b.machine_move("Up to the tool setter's height", Z=sensor["z"])

        def length(found: Found) -> dict[str, Any]:
            return {"kind": "tool_length", "touch_z": found["tool"][2]}

        return ProbePlan(kind, b.steps, length)
    raise ProbeError(f"unknown probing helper {kind!r}")


def confirm_lines(
    result: dict[str, Any],
    choice: dict[str, Any],
    stat: Any,
    scale: float,
    reference_z: float | None,
) -> list[str]:
    """The MDI lines that set what the operator confirmed: for a position result, the
    ``values`` the probed axes should read in coordinate system ``system`` (G10 L2, from the
    probed machine position, the G92 and tool offsets of now); for a tool length, tool
    ``tool``'s Z offset (G10 L1)."""
    if result["kind"] == "tool_length":
        if reference_z is None:
            raise ProbeError("no reference measured yet: measure the reference tool first")
        tool = choice.get("tool")
        if not isinstance(tool, int) or tool <= 0:
            raise ProbeError("'tool' must be a tool number")
        length = result["touch_z"] - reference_z
        return [f"G10 L1 P{tool} Z{length * scale:.6f}"]
    system = choice.get("system", "G54")
    if system not in SYSTEMS:
        raise ProbeError(f"'system' must be one of {', '.join(SYSTEMS)}")
    values = choice.get("values", {})
    if not isinstance(values, dict):
        raise ProbeError("'values' must map axes to numbers")
    words = []
    for axis, probed in result["axes"].items():
        wanted = values.get(axis, 0.0)
        if isinstance(wanted, bool) or not isinstance(wanted, int | float):
            raise ProbeError(f"'{axis}' must be a number")
        index = AXES.index(axis)
        offset = probed - stat.g92_offset[index] - stat.tool_offset[index] - wanted
        words.append(f"{axis}{offset * scale:.6f}")
    return [f"G10 L2 P{SYSTEMS.index(system) + 1} {' '.join(words)}"]


def run_plan(
    plan: ProbePlan,
    mdi: Callable[[str], None],
    status: Callable[[], Any],
    report: Callable[[int], None],
) -> dict[str, Any]:
    """Run ``plan``: each step's line through ``mdi`` (which raises when the controller
    refuses it, or a G38.2 finds nothing), ``report(step index)`` before each; ``status()``
    a freshly polled stat. The result of the plan; a failed step's exception."""
    s = status()
    if abs(s.rotation_xy) > 1e-9:
        raise ProbeError("probing helpers need a coordinate system without rotation")
    found: Found = {"start": list(s.position[:3])}
    for index, step in enumerate(plan.steps):
        report(index)
        if step.note is not None:
            found[step.note] = list(s.position[:3])
        mdi(step.mdi(found, s))
        s = status()
        if step.measure is not None:
            if not s.probe_tripped:
                raise ProbeError(f"{step.text}: the probe did not touch")
            found[step.measure] = list(s.probed_position[:3])
    if plan.is_incremental:
        mdi("G91")
    return plan.result(found)
