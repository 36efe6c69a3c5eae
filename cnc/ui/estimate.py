"""How long a program takes: the program run offline through the project's own interpreter,
task's canon and trajectory planner, at the machine's limits (the INI's).

Unlike an estimate from lengths and feeds, this one sees what the machine will do:
acceleration and braking at every corner, blends within the G64 tolerance, exact stops,
arcs slowed by their radius, rapids at the axis limits. The interpreter (``#<_task>`` = 0,
as a preview's: it never moves the machine) feeds ``task.canon.TaskCanon``, whose messages
are what task would send to motion; the moves among them are queued on a
``motion.tp.TrajectoryPlanner`` made with the limits motion gets, and the planner is
stepped at the servo period ([EMCMOT]SERVO_PERIOD) as motion steps it. Each period's
``motion_id`` (the program line motion reports) gives the time at which each line starts
moving.

A program of very short moves runs at the rate its moves reach the planner, not at the
planner's speed, and the planner's queue stays short, so it looks ahead over little path.
Motion takes commands for a quarter of each servo period (motion/motmod.py), and a move
costs it about 200 µs there (read, decoded, planned, answered: measured on bigprog_50k, in
7,728 of 7,957 periods it took exactly one), so the estimate queues at most
``MOVES_PER_PERIOD``. Task reads the program one line at a time with the same interpreter
as the estimate's, which times itself with ``clock``: no move is queued before task would
have read it.

What the estimate cannot know: G4 dwells are added as programmed; M0/M1 stops, tool
changes, M66 waits and user M codes count nothing (their number is reported); a probe move
runs to its end; spindle-synchronised moves assume the programmed spindle speed; feed and
rapid overrides are at 100 %.

``estimate(program, ini)`` is slow on long programs (the planner runs every servo period
in Python): the web UI calls it in a worker process (``cnc.ui.web.jobs``), never in the
server.
"""

from __future__ import annotations

import math
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cnc.ini import IniFile
from iocontrol.tooltable import ToolTable
from motion.tp import TermCond, TrajectoryPlanner
from nml import emc
from nml.axes import NUM_AXES
from task.canon import CanonSetup, TaskCanon
from task.interp.errors import INTERP_ENDFILE, INTERP_EXIT, InterpError
from task.interp.interp import Interpreter
from task.setup import MachineSetup, load_setup

DEFAULT_SERVO_PERIOD_S = 0.001
PROGRESS_EVERY_S = 0.5  # of machine time between two calls of ``progress``
MOVES_PER_PERIOD = 1  # moves motion queues in one servo period (see above)
_TERM_CONDS = {
    emc.EMC_TRAJ_TERM_COND.STOP: TermCond.STOP,
    emc.EMC_TRAJ_TERM_COND.EXACT: TermCond.EXACT,
    emc.EMC_TRAJ_TERM_COND.BLEND: TermCond.BLEND,
}


@dataclass
class Estimate:
    """The result: ``line_start_s[n]`` is when line ``n``'s motion starts (seconds from
    the program's start; NaN for a line without motion), ``total_s`` the whole run."""

    total_s: float = 0.0
    line_start_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    end_line: int = 0  # the last line the interpreter read (M2, M30 or the file's end)
    dwell_s: float = 0.0  # G4 time included in total_s
    stops: int = 0  # M0, M1 and M60 pauses, not counted
    tool_changes: int = 0  # not counted
    error: dict | None = None  # {"line", "message"}: the interpreter stopped there

    def time_at(self, line: int) -> float:
        """When the machine reaches ``line`` (see ``reached_times``)."""
        return time_at(reached_times(self.line_start_s), line)

    def summary(self) -> dict:
        return {
            "total_s": round(self.total_s, 3),
            "end_line": self.end_line,
            "dwell_s": round(self.dwell_s, 3),
            "stops": self.stops,
            "tool_changes": self.tool_changes,
            "error": self.error,
        }


def reached_times(line_start_s: np.ndarray) -> np.ndarray:
    """For every line, when the machine reaches it: the start of the last line with motion
    at or before it (0 before the first). Made once, so that each look-up is one index."""
    if len(line_start_s) == 0:
        return np.zeros(1)
    return np.maximum.accumulate(np.nan_to_num(line_start_s, nan=0.0))


def time_at(reached: np.ndarray, line: int) -> float:
    """``reached`` (from ``reached_times``) at ``line``; lines past the end: the last."""
    return float(reached[min(max(line, 0), len(reached) - 1)])


def line_span(reached: np.ndarray, line: int) -> tuple[float, float]:
    """When the machine reaches ``line`` and when it reaches the next line that moves:
    the time the line takes (both equal for the last one)."""
    start = time_at(reached, line)
    following = int(np.searchsorted(reached, start, side="right"))
    return start, float(reached[following]) if following < len(reached) else start


def canon_setup(machine: MachineSetup) -> CanonSetup:
    """The canon's view of the machine, as task builds it from the same INI."""
    axes = machine.axes
    return CanonSetup(
        linear_units=machine.linear_units,
        axis_mask=machine.axis_mask,
        axis_max_vel=[axes[i].max_vel if i in axes else math.inf for i in range(NUM_AXES)],
        axis_max_acc=[axes[i].max_acc if i in axes else math.inf for i in range(NUM_AXES)],
        max_velocity=machine.max_velocity,
        max_acceleration=machine.max_acceleration,
        random_toolchanger=machine.random_toolchanger,
        tool_change_position=machine.tool_change_position,
        user_m_commands=machine.user_m_commands,
    )


class MotionModel:
    """The part of motion an estimate needs: moves onto a planner, stepped until done."""

    def __init__(
        self,
        machine: MachineSetup,
        period: float,
        line_count: int,
        clock: Callable[[], float] | None = None,
    ) -> None:
        axes = machine.axes
        vel = [axes[i].max_vel if i in axes else math.inf for i in range(NUM_AXES)]
        acc = [axes[i].max_acc if i in axes else math.inf for i in range(NUM_AXES)]
        # the planner wants finite limits for absent axes too (they never move)
        vel = [v if math.isfinite(v) else 1e9 for v in vel]
        acc = [a if math.isfinite(a) else 1e9 for a in acc]
        self.tp = TrajectoryPlanner(
            vel, acc, period, max_vel=machine.max_velocity, max_acc=machine.max_acceleration
        )
        self.period = period
        self.steps = 0  # periods stepped: the machine time is steps * period
        self.extra_s = 0.0  # dwells
        self.read_s = 0.0  # machine time at which task has read what was taken so far
        self.is_intake_limited = clock is not None  # (None: the planner's own time)
        self.has_queued = False  # a move was queued
        self.moves_this_period = 0
        self.term, self.tolerance = TermCond.BLEND, 0.0
        self.motion_id = 0  # the line of the moves queued next
        self.spindle_rps = 0.0
        self.line_start_s = np.full(line_count + 2, np.nan)
        self._last_id = -1
        self._next_progress = PROGRESS_EVERY_S
        self.progress: Callable[[float], None] | None = None

    @property
    def time_s(self) -> float:
        return self.steps * self.period + self.extra_s

    # ---------------------------------------------------------------- messages
    def take(self, msg: emc.NMLmsg) -> None:
        """One message of task's canon, as motion (or task, for waits) would act on it."""
        kind = type(msg)
        if kind is emc.EMC_TRAJ_SET_MOTION_ID:
            self.motion_id = msg.id
        elif kind is emc.EMC_TRAJ_SET_TERM_COND:
            self.term = _TERM_CONDS.get(msg.cond, TermCond.BLEND)
            self.tolerance = max(msg.tolerance, 0.0)
        elif kind is emc.EMC_TRAJ_LINEAR_MOVE:
            is_rapid = msg.type == emc.EMC_MOTION_TYPE.TRAVERSE
            self._queue_line(msg, list(msg.end.to_flat()), is_rapid, self.term)
        elif kind is emc.EMC_TRAJ_PROBE:  # runs to its end: the probe never trips here
            self._queue_line(msg, list(msg.pos.to_flat()), False, TermCond.STOP)
        elif kind is emc.EMC_TRAJ_CIRCULAR_MOVE:
            self._queue_circle(msg)
        elif kind is emc.EMC_TRAJ_RIGID_TAP:
            self._rigid_tap(msg)
        elif kind is emc.EMC_TRAJ_SET_SPINDLESYNC:
            self.tp.set_spindle_sync(msg.feed_per_revolution, bool(msg.velocity_mode))
        elif kind is emc.EMC_SPINDLE_ON:
            self.spindle_rps = abs(msg.speed) / 60.0
        elif kind is emc.EMC_SPINDLE_OFF:
            self.spindle_rps = 0.0
        elif kind is emc.EMC_TRAJ_DELAY:
            self.finish()
            self.extra_s += max(msg.delay, 0.0)

    def _id(self, msg: emc.NMLmsg) -> int:
        return msg.id or self.motion_id

    def _queue_line(self, msg: emc.NMLmsg, end: list[float], is_rapid: bool, term) -> None:
        self._add(
            lambda: self.tp.add_line(
                end, msg.vel, msg.ini_maxvel, msg.acc, motion_id=self._id(msg), term=term,
                tolerance=self.tolerance, is_rapid=is_rapid,
            )
        )  # fmt: skip

    def _queue_circle(self, msg: emc.EMC_TRAJ_CIRCULAR_MOVE) -> None:
        # LinuxCNC's turn, as motion reads it: n >= 0 counter-clockwise about the normal
        # plus n full turns; -1, -2 ... clockwise
        normal = (msg.normal.x, msg.normal.y, msg.normal.z)
        turns = msg.turn
        if turns < 0:
            normal = (-normal[0], -normal[1], -normal[2])
            turns = -turns - 1
        self._add(
            lambda: self.tp.add_circle(
                list(msg.end.to_flat()), (msg.center.x, msg.center.y, msg.center.z), normal,
                turns, msg.vel, msg.ini_maxvel, msg.acc, motion_id=self._id(msg),
                term=self.term, tolerance=self.tolerance,
            )
        )  # fmt: skip

    def _rigid_tap(self, msg: emc.EMC_TRAJ_RIGID_TAP) -> None:
        """In and out again at the feed the spindle allows (its reversal not modelled)."""
        start = self.tp.pos.tolist()
        for end in (list(msg.pos.to_flat()), start):
            self._add(
                lambda end=end: self.tp.add_line(
                    end, msg.vel, msg.ini_maxvel, msg.acc, motion_id=self._id(msg),
                    term=TermCond.STOP,
                )
            )  # fmt: skip

    # ---------------------------------------------------------------- time
    def read(self, seconds: float) -> None:
        """Task spent ``seconds`` reading one more line (its moves come after that). Not
        counted before the first move: that is a few ms in task, but the estimate's
        own first lines pay its warm-up (imports, caches) that task paid long before."""
        if self.has_queued:
            self.read_s += seconds

    def _add(self, add: Callable[[], object]) -> None:
        """Queue one move with ``add`` once motion would: after task read it, with room
        in the planner (task reads on only once there is room again), and at most
        MOVES_PER_PERIOD in a period."""
        while self.time_s < self.read_s:
            self._step()
        if self.tp.is_full:
            while self.tp.is_full:
                self._step()
            self.read_s = self.time_s
        if self.is_intake_limited and self.moves_this_period >= MOVES_PER_PERIOD:
            self._step()
        add()
        self.moves_this_period += 1
        self.has_queued = True

    def finish(self) -> None:
        """Step until everything queued is done (a queue buster, or the program's end);
        task reads on from then."""
        while not self.tp.is_done:
            self._step()
        self.read_s = max(self.read_s, self.time_s)

    def _step(self) -> None:
        tp = self.tp
        tp.spindle_rps = self.spindle_rps
        tp.spindle_revs += self.spindle_rps * self.period
        if tp.is_waiting_for_index:
            tp.index_found()
        tp.step()
        self.steps += 1
        self.moves_this_period = 0
        motion_id = tp.motion_id
        if motion_id != self._last_id:
            self._last_id = motion_id
            if 0 < motion_id < len(self.line_start_s) and np.isnan(self.line_start_s[motion_id]):
                self.line_start_s[motion_id] = self.steps * self.period + self.extra_s
        if self.progress is not None and self.steps * self.period >= self._next_progress:
            self._next_progress += PROGRESS_EVERY_S
            self.progress(self.time_s)


def servo_period(ini: IniFile) -> float:
    """[EMCMOT]SERVO_PERIOD in seconds (the INI gives nanoseconds)."""
    try:
        period = float(ini.find("EMCMOT", "SERVO_PERIOD") or 0) / 1e9
    except ValueError:
        period = 0.0
    return period if period > 0 else DEFAULT_SERVO_PERIOD_S


def estimate(
    program: str,
    ini_path: str,
    *,
    start: list[float] | None = None,
    progress: Callable[[float], None] | None = None,
    clock: Callable[[], float] | None = time.perf_counter,
) -> Estimate:
    """Run ``program`` through interpreter, canon and planner at the limits of the machine
    in ``ini_path``, from machine position ``start`` (9 values; default 0). ``progress``
    is called with the machine time reached every ``PROGRESS_EVERY_S`` of it. What
    ``clock`` (seconds) says reading a line took here, it takes task too, and motion
    queues MOVES_PER_PERIOD (None: moves are there as soon as the planner has room: the
    planner's own time). A bad INI raises ``IniError``; an interpreter error ends the
    estimate there (``error``)."""
    ini = IniFile.load(ini_path)
    machine = load_setup(ini)
    line_count = _count_lines(program)
    model = MotionModel(machine, servo_period(ini), line_count, clock)
    model.progress = progress
    if start is not None:
        model.tp.set_position(list(start) + [0.0] * (NUM_AXES - len(start)))
    tools = ToolTable(machine.random_toolchanger)
    table = ini.find("EMCIO", "TOOL_TABLE")
    if table and Path(machine.resolve(table)).is_file():
        tools.load(machine.resolve(table), strict=False)
    canon = TaskCanon(canon_setup(machine), tools)
    result = Estimate()
    with tempfile.TemporaryDirectory(prefix="cnc-estimate-") as folder:
        # the interpreter saves its parameters: a private copy, never the machine's file
        private = Path(folder) / "estimate.var"
        if machine.parameter_file and Path(machine.parameter_file).is_file():
            shutil.copyfile(machine.parameter_file, private)
        interp = Interpreter(canon, ini=ini, parameter_file=str(private), task=0)
        try:
            interp.init()
            interp.open(program)
            while True:
                began = clock() if clock is not None else 0.0
                if interp.read() == INTERP_ENDFILE:
                    break
                status = interp.execute()
                if clock is not None:
                    model.read(clock() - began)
                _run_messages(canon, model, result)
                if status == INTERP_EXIT:
                    break
        except InterpError as exc:
            result.error = {"line": interp.sequence_number, "message": exc.message}
        finally:
            result.end_line = interp.sequence_number
            interp.close()
    _run_messages(canon, model, result)
    model.finish()
    result.total_s = model.time_s
    result.dwell_s = model.extra_s
    result.line_start_s = model.line_start_s
    return result


_STOPS = (emc.EMC_TASK_PLAN_PAUSE, emc.EMC_TASK_PLAN_OPTIONAL_STOP)
_TOOL_CHANGES = (emc.EMC_TOOL_LOAD,)
# Messages after which task waits for motion to finish (queue busters, waits)
_WAITS = (*_STOPS, *_TOOL_CHANGES, emc.EMC_AUX_INPUT_WAIT, emc.EMC_SYSTEM_CMD)


def _run_messages(canon: TaskCanon, model: MotionModel, result: Estimate) -> None:
    out = canon.out
    while out:
        msg = out.popleft()
        if isinstance(msg, _WAITS):
            model.finish()
            result.stops += isinstance(msg, _STOPS)
            result.tool_changes += isinstance(msg, _TOOL_CHANGES)
        else:
            model.take(msg)


def _count_lines(path: str) -> int:
    count = 0
    with open(path, "rb") as file:
        while chunk := file.read(1 << 20):
            count += chunk.count(b"\n")
    return count + 1
