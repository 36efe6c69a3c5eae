"""The default coordinated-mode trajectory planner (MOT-017, MOT-037..041, MOT-053..057).

Moves (LINE, CIRCLE, PROBE) are queued in the cartesian frame. Each move becomes one or
more path pieces (``geometry``); under G64 the corner between two lines is replaced by a
tangent arc that stays within the P tolerance, so the path has no velocity jumps and its
speed is limited only by the axis limits (speed cap and tangential acceleration per piece).
Corners where an arc meets a line or another arc in one XYZ plane are blended the same way,
the arc trimmed like a line (``_blend_curved``); other real corners are passed at rest.

Lookahead: a backward pass over the pieces queued since the last one raises the planned
exit speeds of the pieces before them as far as braking allows (the queue tail always
ends at rest); it stops as soon as a speed does not change, so its cost is the braking
distance, not the queue, and it is spread over a few servo periods while the machine is
far from the pieces it changes (``_backward_pass``). A period that crosses from one piece
into the next can only use the lower of their accelerations, so the first and last
stretch of each piece is planned with that (``Piece.window``): plan and servo period agree
exactly.

Servo period (``step``): the path speed follows the cap with bounded acceleration and
brakes onto the planned curve of the pieces this period may reach, onto feed changes
ahead (feed differs per move and overrides change at any time) and onto requested stops
(pause, step, abort, probe trip). Integration is trapezoidal, so the discrete braking
distance equals the planned one and stops land exactly on their point.

Spindle (MOT-065): the caller gives the spindle's state every period (``spindle_revs``,
``spindle_rps``, ``is_spindle_at_speed``). A move queued after a spindle start waits at
its start until the spindle is at speed. Moves queued under ``set_spindle_sync`` follow
the spindle: in velocity mode (G95) their feed is ``feed_per_rev * spindle_rps``; in
position mode (G33) their path position follows the revolutions at ``feed_per_rev`` per
revolution, the first move of a chain waiting at rest for the encoder's index pulse
(``is_waiting_for_index``, then ``index_found``). Rigid tapping (G33.1, ``add_rigid_tap``)
is a move of its own, run by ``motion.tp.spindlesync``.
"""

from __future__ import annotations

import enum
import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from motion.free import braking_speed, check_finite, check_positive
from motion.tp.geometry import (
    EPS,
    XYZ,
    ArcPiece,
    LinePiece,
    Piece,
    blend_arc,
    circle_piece,
    cross3,
    flat_normal_share,
    norm,
)
from motion.tp.spindlesync import RigidTap, follow_speed
from nml.axes import NUM_AXES
from nml.pose import Pose

# Part of the acceleration budget a curved piece may use for centripetal acceleration.
NORMAL_FRACTION = 0.5
# Per-axis velocity change allowed at an unblended kink, as a fraction of max_acc * period.
KINK_FRACTION = 0.45
# Fraction of the axis acceleration limits the planner plans with.
ACC_MARGIN = 0.995
# A blend must be estimated at least this much faster than a stop (fraction of the stop's
# time loss) to be chosen.
BLEND_GAIN = 0.85
# Pieces queued before the lookahead's backward pass starts (see _backward_pass).
REPLAN_BATCH = 64
# Pieces the backward pass plans per servo period while no stale plan is within reach: a
# pass re-plans the whole braking ramp at the queue's end (about a hundred pieces on a
# dense program), so it is spread over a few periods instead of taking one at once.
PASS_PIECES_PER_PERIOD = 40
# Pieces done that are dropped from the queue at once: freeing a piece and its vectors
# costs about half a microsecond, so hundreds at once would make one period slow.
DONE_PIECES_KEPT = 32
# Moves and pieces of a dropped queue (abort) freed per period, for the same reason: a full
# queue of a dense program holds thousands, milliseconds' worth of freeing.
FREED_PER_PERIOD = 64
# Largest blend deviation as a fraction of the shorter line (G64 without P).
TOLERANCE_FRACTION = 0.25
# Largest per-axis change of the unit tangent passed without stopping (about 3 degrees).
KINK_MAX_JUMP = 0.05
# G61 (exact path) passes a joint without stopping only when it is tangent as LinuxCNC's
# planner judges it: turning the full speed's direction within one period needs at most this
# fraction of each axis's acceleration (its default tangent kink ratio).
TANGENT_KINK_RATIO = 0.1
# Angle below which two lines count as collinear (no blend needed).
COLLINEAR_ANGLE = 1e-7
# Turns sharper than this (almost a reversal) are not blended: the joint stops instead.
MAX_BLEND_TURN = math.pi - 1e-3
# Trims tried when blending a corner with an arc (see _blend_curved).
CURVED_BLEND_TRIES = 8


class TermCond(enum.IntEnum):
    """End-of-move behaviour (LinuxCNC TC_TERM_COND_*)."""

    STOP = 1  # G61.1 (exact stop): come to rest at the end of the move
    EXACT = 2  # G61 (exact path): as STOP, except that tangent joints pass at speed
    BLEND = 3  # G64: blend corners within the tolerance


class SyncMode(enum.IntEnum):
    """How a move follows the spindle (EMC_TRAJ_SET_SPINDLESYNC)."""

    NONE = 0
    VELOCITY = 1  # G95: feed = feed_per_rev * spindle speed
    POSITION = 2  # G33: path position follows the spindle revolutions


_POSITION = int(SyncMode.POSITION)
# The end conditions as module names: looking a member up on its enum class costs about
# a tenth of a microsecond, several times per queued move.
_STOP, _EXACT, _BLEND = TermCond.STOP, TermCond.EXACT, TermCond.BLEND


class ProbeType(enum.IntEnum):
    """Which probe edge ends a probe move (G38.2/3: contact, G38.4/5: loss of contact)."""

    TOWARD = 2
    AWAY = 4


@dataclass(slots=True, eq=False)
class Move:
    """One queued command; the pieces point back to it."""

    motion_id: int
    vel: float
    is_rapid: bool
    term: TermCond
    tolerance: float
    end_s: float = 0.0  # cumulative path position of the move's end
    probe: ProbeType | None = None
    is_error_without_trip: bool = True  # probe moves: G38.2/G38.4 (True), G38.3/G38.5
    line: LinePiece | None = None  # the move's line piece when it is a line (for blending)
    arc: ArcPiece | None = None  # the move's arc piece when it is a circle (for blending)
    end_pos: np.ndarray | None = None  # where the move ends (status dtg)
    sync: SyncMode = SyncMode.NONE
    feed_per_rev: float = 0.0  # path length per spindle revolution (sync moves)
    is_waiting_for_at_speed: bool = False  # starts once the spindle is at speed
    is_waiting_for_index: bool = False  # first move of a G33 chain: starts at the index
    rigid_tap: RigidTap | None = None
    indexer_joint: int = -1  # a locking indexer's move: starts and ends at rest (motion/indexer.py)
    tag: bytes = b""  # the interpreter's state at the move (a StateTag), reported while it runs


class TrajectoryPlanner:
    """Coordinated-mode planner; drive it with ``step()`` once per servo period.

    Limits: ``axis_max_vel``/``axis_max_acc`` are 9 values (X..W, ``[AXIS_L]``; use ``inf``
    for absent axes), ``max_vel``/``max_acc`` the ``[TRAJ]`` limits of the path.
    """

    def __init__(
        self,
        axis_max_vel: Sequence[float],
        axis_max_acc: Sequence[float],
        cycle_time: float = 0.001,
        max_vel: float = math.inf,
        max_acc: float = math.inf,
        queue_size: int = 2000,
        max_feed_scale: float = 1.0,
    ) -> None:
        self.set_limits(axis_max_vel, axis_max_acc, max_vel, max_acc)
        self.cycle_time = check_positive("cycle time", cycle_time)
        if queue_size < 2:
            raise ValueError(f"queue size must be at least 2, got {queue_size}")
        self.queue_size = queue_size
        # lookahead plans corner and braking speeds for feed overrides up to this one
        # ([DISPLAY]MAX_FEED_OVERRIDE); above it, overrides act between those points only
        self.max_feed_scale = check_positive("max feed scale", max_feed_scale)
        self.feed_scale = 1.0
        self.rapid_scale = 1.0
        self.probe_input = False  # set by the caller every period
        self.motion_id = 0
        self.tag = b""  # the state tag of the move being carried out (of the last one, at rest)
        self.probe_tripped = False
        self.probe_pos = np.zeros(NUM_AXES)
        self.error: str | None = None  # taken by the caller with take_error()
        # spindle inputs, set by the caller every period: revolutions (counted in the
        # programmed direction, reset to 0 by the index pulse), speed and at-speed
        self.spindle_revs = 0.0
        self.spindle_rps = 0.0
        self.is_spindle_at_speed = True
        self.is_start_held = False  # no move starts from rest while set (M19 wait)
        self._sync = (SyncMode.NONE, 0.0)  # for the moves queued next
        self._is_at_speed_wait_pending = False
        self._moves: deque[Move] = deque()
        self._pieces: list[Piece] = []
        # queues dropped by _reset_queue, freed FREED_PER_PERIOD items a period by step
        self._dropped: list[deque[Move] | list[Piece]] = []
        self._reset_queue(np.zeros(NUM_AXES))

    # ------------------------------------------------------------------ configuration
    def set_limits(
        self,
        axis_max_vel: Sequence[float],
        axis_max_acc: Sequence[float],
        max_vel: float = math.inf,
        max_acc: float = math.inf,
    ) -> None:
        vel = np.array(axis_max_vel, dtype=float)
        acc = np.array(axis_max_acc, dtype=float)
        if vel.shape != (NUM_AXES,) or acc.shape != (NUM_AXES,):
            raise ValueError(f"axis limits need {NUM_AXES} values each (X Y Z A B C U V W)")
        if np.isnan(vel).any() or np.isnan(acc).any() or (vel <= 0).any() or (acc <= 0).any():
            raise ValueError("axis velocity and acceleration limits must be positive numbers")
        if math.isnan(max_vel) or math.isnan(max_acc) or max_vel <= 0 or max_acc <= 0:
            raise ValueError("trajectory velocity and acceleration limits must be positive")
        self.axis_max_vel, self.axis_max_acc = vel, acc
        # plan slightly inside the acceleration limits: a period that straddles two pieces
        # mixes their accelerations (see step)
        plan_acc = acc * ACC_MARGIN
        self._plan_acc = plan_acc.tolist()  # (plain floats: read per axis, per move)
        # what Piece.apply_limits takes for every piece, as plain floats (0: unlimited axis)
        self._piece_axis_limits = (self._plan_acc, (1.0 / vel).tolist(), (1.0 / plan_acc).tolist())
        self.max_vel, self.max_acc = float(max_vel), float(max_acc)

    def _reset_queue(self, pos: np.ndarray) -> None:
        """Empty queue, at rest at ``pos``; probe results and the last motion id stay."""
        if self._moves or self._pieces:
            self._dropped += [self._pieces, self._moves]  # the moves are freed first
        self._pieces = []
        self._head = 0  # index of the piece being executed
        self._moves = deque()
        self._feed_points: deque[tuple[float, Move]] = deque()  # feed changes ahead
        self._end = pos.copy()  # where the next queued move starts
        self._s = 0.0  # position within the current piece
        self.pos = pos.copy()
        self.vel = 0.0
        self._is_stopping = False
        self._is_aborting = False
        self._step_end: float | None = None  # cumulative position where STEP stops
        self._first_dirty: int | None = None  # first piece whose plan is out of date
        # the backward pass under way (see _backward_pass): the next piece it plans (None:
        # no pass under way), the highest entry speed of the piece after that one, and the
        # first piece whose plan was out of date when it started
        self._pass_next: int | None = None
        self._pass_entry = 0.0
        self._pass_first_changed = 0
        self._reach = 0.0  # braking distance from the fastest queued piece, with margin
        self._probe_armed = False
        self.is_paused = False
        self.distance_to_go = 0.0
        self._sync_target = 0.0  # G33: where the spindle says the path should be
        self._last_revs = self.spindle_revs
        # outputs for the caller: what the planner waits for, and the factor the spindle
        # speed is multiplied by while a rigid tap reverses it
        self.is_waiting_for_at_speed = False
        self.is_waiting_for_index = False
        self.spindle_reversal = 1.0

    def set_position(self, pose: Pose | Sequence[float]) -> None:
        """Start from ``pose`` with an empty queue (entering coord mode, MOT-029)."""
        pos = np.array(list(pose), dtype=float)
        if pos.shape != (NUM_AXES,) or not np.isfinite(pos).all():
            raise ValueError(f"position needs {NUM_AXES} finite values")
        self._reset_queue(pos)

    # ------------------------------------------------------------------ status
    @property
    def queue_depth(self) -> int:
        return len(self._moves)

    @property
    def free_slots(self) -> int:
        return self.queue_size - len(self._moves)

    @property
    def current_move(self) -> Move | None:
        """The move being executed (None when the queue is empty)."""
        return self._moves[0] if self._moves else None

    @property
    def is_full(self) -> bool:
        return len(self._moves) >= self.queue_size

    @property
    def is_done(self) -> bool:
        """Queue empty and at rest."""
        return not self._moves and self.vel == 0.0

    @property
    def end_position(self) -> list[float]:
        """Where the queued moves end (where the next move starts)."""
        return self._end.tolist()

    @property
    def pose(self) -> Pose:
        return Pose(*self.pos.tolist())

    @property
    def dtg(self) -> np.ndarray:
        """Per-axis distance from here to the end of the current move (zeros if none)."""
        move = self.current_move
        if move is None or move.end_pos is None:
            return np.zeros(NUM_AXES)
        return move.end_pos - self.pos

    @property
    def active_queue(self) -> int:
        """Moves being executed at once: 0 idle, 1, or 2 while blending into the next."""
        if not self._moves:
            return 0
        last = self._moves[0].end_s
        pieces = self._pieces
        for index in range(self._head, len(pieces)):  # (no slice: it would copy the queue)
            piece = pieces[index]
            if piece.s0 + piece.length >= last - 1e-12:
                return 2 if piece.v_exit > 0.0 and len(self._moves) > 1 else 1
        return 1

    def set_feed_scale(self, scale: float) -> None:
        """Feed override (MOT-040/041); applies at once, with bounded acceleration."""
        self.feed_scale = _check_scale(scale)

    def set_rapid_scale(self, scale: float) -> None:
        self.rapid_scale = _check_scale(scale)

    def set_spindle_sync(self, feed_per_rev: float, is_velocity_mode: bool) -> None:
        """EMC_TRAJ_SET_SPINDLESYNC: the feed moves queued next follow the spindle at
        ``feed_per_rev`` path units per revolution (0: no longer synchronised)."""
        feed_per_rev = check_finite("feed per revolution", feed_per_rev)
        if feed_per_rev < 0:
            raise ValueError(f"feed per revolution must be >= 0, got {feed_per_rev}")
        if feed_per_rev == 0:
            self._sync = (SyncMode.NONE, 0.0)
        else:
            mode = SyncMode.VELOCITY if is_velocity_mode else SyncMode.POSITION
            self._sync = (mode, feed_per_rev)

    def wait_for_spindle_at_speed(self) -> None:
        """The next feed move starts only once the spindle is at speed (spindle on with
        wait_for_spindle_at_speed, MOT-065)."""
        self._is_at_speed_wait_pending = True

    def index_found(self) -> None:
        """The encoder saw the index pulse (and reset its count): a G33 chain starts."""
        if not self.is_waiting_for_index:
            return
        self.is_waiting_for_index = False
        self._last_revs = 0.0
        self._sync_target = self._pieces[self._head].s0 + self._s
        self._moves[0].is_waiting_for_index = False

    # ------------------------------------------------------------------ queueing
    def add_line(
        self,
        end: Sequence[float],
        vel: float,
        ini_maxvel: float,
        acc: float,
        motion_id: int = 0,
        term: TermCond = TermCond.BLEND,
        tolerance: float = 0.0,
        is_rapid: bool = False,
        probe: ProbeType | None = None,
        indexer_joint: int = -1,
        tag: bytes = b"",
    ) -> None:
        """Queue a straight move to ``end`` (SET_LINE, MOT-053); ``indexer_joint``: the
        locking indexer joint it turns (the move starts from rest, see motion/indexer.py);
        ``tag``: what ``self.tag`` reports while the move runs (every add_* takes one)."""
        end_v = self._check_target(end)
        move = self._new_move(motion_id, vel, ini_maxvel, acc, term, tolerance, is_rapid, probe)
        move.indexer_joint = indexer_joint
        move.tag = tag
        piece = LinePiece(move, self._end, end_v)
        if piece.length <= EPS:
            return  # nothing to do: LinuxCNC drops zero-length moves too
        move.line = piece
        self._append(move, piece, ini_maxvel, acc)

    def add_rigid_tap(
        self,
        end: Sequence[float],
        ini_maxvel: float,
        acc: float,
        motion_id: int = 0,
        retract_scale: float = 1.0,
        tag: bytes = b"",
    ) -> None:
        """Queue a rigid tap (G33.1, EMC_TRAJ_RIGID_TAP): in to ``end`` following the
        spindle at the synchronisation's feed per revolution, spindle reversed (its speed
        times ``retract_scale``), out again to where it started, which is where the next
        move starts. Needs position synchronisation (set_spindle_sync)."""
        mode, feed_per_rev = self._sync
        if mode != SyncMode.POSITION:
            raise ValueError("rigid tapping needs spindle position synchronisation (G33.1)")
        retract_scale = check_positive("rigid tap retract scale", retract_scale)
        end_v = self._check_target(end)
        start = self._end.copy()
        term = TermCond.STOP
        move = self._new_move(motion_id, ini_maxvel, ini_maxvel, acc, term, 0.0, False, None)
        move.tag = tag
        piece = LinePiece(move, start, end_v)
        if piece.length <= EPS:
            return
        self._append(move, piece, ini_maxvel, acc)
        move.rigid_tap = RigidTap(piece.length, feed_per_rev, retract_scale)
        move.is_waiting_for_at_speed = True
        move.is_waiting_for_index = False
        move.end_pos = start.copy()
        self._end = start

    def add_probe(
        self,
        end: Sequence[float],
        vel: float,
        ini_maxvel: float,
        acc: float,
        motion_id: int = 0,
        probe: ProbeType = ProbeType.TOWARD,
        is_error_without_trip: bool = True,
        tag: bytes = b"",
    ) -> None:
        """Queue a probe move (PROBE, MOT-056): it stops on the probe edge, records the
        position and empties the queue. The tripped flag is cleared here (MOT-057).
        Reaching the end without a trip is an error (G38.2/G38.4) unless
        ``is_error_without_trip`` is false (G38.3/G38.5)."""
        self.probe_tripped = False
        self.add_line(end, vel, ini_maxvel, acc, motion_id, TermCond.STOP, probe=probe, tag=tag)
        if self._moves and self._moves[-1].probe is not None:
            self._moves[-1].is_error_without_trip = is_error_without_trip

    def add_circle(
        self,
        end: Sequence[float],
        centre: Sequence[float],
        normal: Sequence[float],
        turns: int,
        vel: float,
        ini_maxvel: float,
        acc: float,
        motion_id: int = 0,
        term: TermCond = TermCond.BLEND,
        tolerance: float = 0.0,
        tag: bytes = b"",
    ) -> None:
        """Queue an arc or helix (SET_CIRCLE, MOT-054): counter-clockwise about ``normal``
        through ``centre`` (XYZ), plus ``turns`` full turns; A B C U V W move linearly."""
        end_v = self._check_target(end)
        centre_v = np.array(centre, dtype=float)
        normal_v = np.array(normal, dtype=float)
        if centre_v.shape != (3,) or normal_v.shape != (3,):
            raise ValueError("circle centre and normal need 3 values (X Y Z)")
        if not all(map(math.isfinite, centre_v.tolist() + normal_v.tolist())):
            raise ValueError("circle centre and normal must be finite")
        if int(turns) != turns or turns < 0:
            raise ValueError(f"circle turns must be a whole number >= 0, got {turns}")
        move = self._new_move(motion_id, vel, ini_maxvel, acc, term, tolerance, False, None)
        move.tag = tag
        piece = circle_piece(move, self._end, end_v, centre_v, normal_v, int(turns))
        move.arc = piece
        self._append(move, piece, ini_maxvel, acc)

    def _check_target(self, end: Sequence[float]) -> np.ndarray:
        if self.is_full:
            raise OverflowError("trajectory queue is full")
        end_v = np.array(end if isinstance(end, list) else list(end), dtype=float)
        if end_v.shape != (NUM_AXES,):
            raise ValueError(f"target needs {NUM_AXES} values (X Y Z A B C U V W)")
        # (math on the nine floats: numpy's all() is a Python-level call, several times
        # slower for nine values)
        if not all(map(math.isfinite, end_v.tolist())):
            raise ValueError(f"target is not finite: {end_v.tolist()}")
        return end_v

    def _new_move(self, motion_id, vel, ini_maxvel, acc, term, tolerance, is_rapid, probe) -> Move:
        check_positive("velocity", vel)
        check_positive("max velocity", ini_maxvel)
        check_positive("acceleration", acc)
        tolerance = check_finite("blend tolerance", tolerance)
        if tolerance < 0:
            raise ValueError(f"blend tolerance must be >= 0, got {tolerance}")
        if type(term) is not TermCond:  # (the enum call costs half a microsecond)
            term = TermCond(term)
        move = Move(int(motion_id), float(vel), bool(is_rapid), term, tolerance, probe=probe)
        if is_rapid:
            return move
        move.sync, move.feed_per_rev = self._sync
        if move.sync:  # (not SyncMode.NONE)
            move.vel = float(ini_maxvel)  # the spindle sets the speed, within the limits
        move.is_waiting_for_at_speed = self._is_at_speed_wait_pending
        self._is_at_speed_wait_pending = False
        if move.sync == _POSITION:
            prev = self._moves[-1] if self._moves else None
            is_chained = prev is not None and prev.sync == SyncMode.POSITION
            is_chained = is_chained and prev.rigid_tap is None
            # a chain of synchronised moves starts at the index, with the spindle at speed
            move.is_waiting_for_index = not is_chained
            move.is_waiting_for_at_speed |= not is_chained
        return move

    def _piece_limits(self, piece: Piece, ini_maxvel: float, acc: float) -> None:
        """Speed cap and acceleration of a piece; its planning speed is the cap or the
        move's velocity at the highest feed override, whichever is lower."""
        piece.apply_limits(
            *self._piece_axis_limits,
            min(ini_maxvel, self.max_vel),
            min(acc, self.max_acc) * ACC_MARGIN,
            NORMAL_FRACTION,
        )
        move = piece.move
        highest = move.vel * (1.0 if move.is_rapid else self.max_feed_scale)
        piece.vplan = min(piece.vcap, highest)

    def _append(self, move: Move, piece: Piece, ini_maxvel: float, acc: float) -> None:
        end = piece.end if isinstance(piece, LinePiece) else piece.point(piece.length)
        # finite targets can still make a path beyond floating point (a centre at 1e300,
        # a line from -1e308 to 1e308): refused before anything is queued
        if not all(map(math.isfinite, [piece.length, *end.tolist()])):
            raise ValueError("the path is out of range (its length or end is not finite)")
        self._piece_limits(piece, ini_maxvel, acc)
        first_changed = len(self._pieces)
        prev_move = self._moves[-1] if self._moves else None
        tail = self._pieces[-1] if len(self._pieces) > self._head else None
        if tail is not None and prev_move is not None:
            first_changed = self._join(prev_move, tail, move, piece)
        last = self._pieces[-1] if self._pieces else None
        piece.s0 = last.s0 + last.length if last is not None else 0.0
        first_changed = min(first_changed, self._link(piece))  # the queue ends at rest
        move.end_s = piece.s0 + piece.length
        if prev_move is None or _feed_key(prev_move) != _feed_key(move):
            self._feed_points.append((piece.s0, move))
        self._moves.append(move)
        self._end = end
        move.end_pos = end.copy()
        if self._first_dirty is None or first_changed < self._first_dirty:
            self._first_dirty = first_changed
        dt = self.cycle_time
        self._reach = max(self._reach, piece.vplan**2 / piece.acc + 20.0 * piece.vplan * dt)

    def _join(self, prev_move: Move, tail: Piece, move: Move, piece: Piece) -> int:
        """Set the junction between the queue tail and a new piece: a blend arc under G64
        when both are lines, else a speed limit at the corner. Returns the index of the
        first piece whose planning data changed."""
        index = len(self._pieces) - 1
        prev_term = prev_move.term
        if prev_term is _STOP or prev_move.probe is not None:
            return index  # exact stop: exit stays 0
        if move.is_waiting_for_at_speed or move.is_waiting_for_index or move.indexer_joint >= 0:
            return index  # the move starts at rest (it may have to wait)
        is_threading = prev_move.sync == _POSITION or move.sync == _POSITION
        if is_threading and prev_move.sync != move.sync:
            return index  # a G33 chain ends at rest: no blend into unsynchronised motion
        arc = None
        # each move's own line or arc (not a blend arc), so a piece is trimmed only once
        is_own = (tail is prev_move.line or tail is prev_move.arc) and (
            piece is move.line or piece is move.arc
        )
        if prev_term is _BLEND and is_own:
            if (
                isinstance(tail, LinePiece)
                and isinstance(piece, LinePiece)
                and tail.is_single_group()
                and piece.is_single_group()
            ):
                arc = self._blend(prev_move, tail, piece)
            elif _is_corner(tail, piece):
                arc = self._blend_curved(prev_move, tail, piece)
            if arc is not None:
                arc.s0 = tail.s0 + tail.length
                tail.exit_max = min(tail.vplan, arc.vplan)
                arc.exit_max = min(arc.vplan, piece.vplan)
                index = min(index, self._link(arc))
                prev_move.end_s = arc.s0 + arc.length
                return index
        if prev_term is _EXACT and not self._is_tangent(tail, piece):
            return index  # G61 stops at every corner, however slight
        tail.exit_max = self._kink_speed(tail, piece)
        if tail.is_kink_end:  # the period crossing the joint keeps 1 - KINK_FRACTION
            tail.acc_tail = min(tail.acc_tail, tail.acc * (1.0 - KINK_FRACTION))
            piece.acc_head = min(piece.acc_head, piece.acc * (1.0 - KINK_FRACTION))
        return index

    def _blend(self, move: Move, line1: LinePiece, line2: LinePiece) -> ArcPiece | None:
        """Replace the corner between two lines by a tangent arc, or None if not possible."""
        # (ndarray.dot: the same BLAS sum as ``@``, so the same bits, at half the cost)
        cos_turn = float(line1.direction.dot(line2.direction))
        turn = math.acos(max(-1.0, min(1.0, cos_turn)))
        if turn < COLLINEAR_ANGLE or turn > MAX_BLEND_TURN:
            return None  # collinear: nothing to blend; reversal: stop at the corner
        # an arc may use up to half of each line, so that neighbouring arcs never overlap
        avail = min(0.5 * line1.full_length, line1.length, 0.5 * line2.length)
        is_running = bool(self._pieces) and line1 is self._pieces[self._head]
        if is_running:  # not the part this period is about to travel
            avail = min(avail, line1.length - self._s - 2 * self.vel * self.cycle_time)
        if avail <= 1e-9:
            return None
        # the arc's distance from the corner stays within G64 P, and within a quarter of
        # either line's length when P is absent or larger (as LinuxCNC does)
        tolerance = TOLERANCE_FRACTION * min(line1.full_length, line2.full_length)
        if move.tolerance > 0:
            tolerance = min(tolerance, move.tolerance)
        tan_half = math.tan(0.5 * turn)
        cos_half = math.cos(0.5 * turn)
        radius = min(avail / tan_half, tolerance * cos_half / (1.0 - cos_half))
        # cruising speeds of the two lines; the arc runs at the first move's feed
        v1 = min(line1.vplan, move.vel)
        v2 = min(line2.vplan, line2.move.vel)
        w_full = min(v1, v2)
        # Beyond the radius that allows w_full, a larger arc only adds time when it is
        # longer to run at w_full than the two cuts at their own speeds (a sharp corner
        # or different feeds); then the arc stays at that radius, closest to the corner.
        if turn / w_full > tan_half * (1.0 / v1 + 1.0 / v2):
            # the lowest acceleration along the arc's plane: per axis, its limit over the
            # axis's share of the plane (the unit vectors u1 and inward span it)
            sin_turn = math.sin(turn)
            plane_acc = math.inf
            u1, u2 = line1.direction.tolist(), line2.direction.tolist()
            for a1, a2, axis_acc in zip(u1, u2, self._plan_acc, strict=True):
                inward = (a2 - cos_turn * a1) / sin_turn
                plane = math.sqrt(a1 * a1 + inward * inward)
                if plane > EPS:
                    plane_acc = min(plane_acc, axis_acc / plane)
            normal_acc = flat_normal_share(NORMAL_FRACTION) * plane_acc  # (a flat arc)
            radius = min(radius, w_full * w_full / normal_acc)
        d = radius * tan_half
        if d <= 1e-9:
            return None
        arc = blend_arc(move, line1.end, line1.direction, line2.direction, radius, turn)
        return self._take_blend(arc, line1, line2, d, d, v1, v2, is_running)

    def _blend_curved(self, move: Move, p1: Piece, p2: Piece) -> ArcPiece | None:
        """Blend a G64 corner where an arc meets a line or another arc (flat circles and
        lines in one XYZ plane): trim both pieces near the corner and join the trimmed
        ends by a tangent arc, the corner staying within the tolerance; or None.

        The trims ``d1``/``d2`` are chosen so that the tangents at the new ends meet at
        the same distance from both ends: then one circular arc is tangent to both. The
        first guess is the line-line blend of the corner's tangents; it shrinks until the
        arc keeps to the tolerance."""
        t1, t2 = _unit(p1.tangent(p1.length)), _unit(p2.tangent(0.0))
        turn = math.acos(max(-1.0, min(1.0, float(t1.dot(t2)))))
        if not COLLINEAR_ANGLE < turn < MAX_BLEND_TURN or not _is_flat_corner(p1, p2, t1, t2):
            return None
        avail1 = min(0.5 * p1.full_length, p1.length)
        is_running = bool(self._pieces) and p1 is self._pieces[self._head]
        if is_running:
            avail1 = min(avail1, p1.length - self._s - 2 * self.vel * self.cycle_time)
        avail2 = 0.5 * p2.length
        for p in (p1, p2):  # an arc gives at most one radian to a blend
            if isinstance(p, ArcPiece):
                avail1, avail2 = min(avail1, p.r0), min(avail2, p.r0)
        tolerance = TOLERANCE_FRACTION * min(p1.full_length, p2.full_length)
        if move.tolerance > 0:
            tolerance = min(tolerance, move.tolerance)
        half = 0.5 * turn
        d1 = min(avail1, tolerance * math.cos(half) / (1.0 - math.cos(half)) * math.tan(half))
        corner = p1.point(p1.length)[XYZ]
        for _ in range(CURVED_BLEND_TRIES):
            if d1 <= 1e-9:
                return None
            found = _tangent_arc(move, p1, p2, d1, avail2)
            if found is None:
                d1 *= 0.5
                continue
            arc, d2 = found
            deviation = abs(norm(corner - arc.centre[XYZ]) - arc.r0)
            if deviation <= tolerance:
                break
            d1 *= 0.98 * tolerance / deviation  # the deviation grows about as the trim
        else:
            return None
        v1, v2 = min(p1.vplan, move.vel), min(p2.vplan, p2.move.vel)
        return self._take_blend(arc, p1, p2, d1, d2, v1, v2, is_running)

    def _take_blend(
        self,
        arc: ArcPiece,
        p1: Piece,
        p2: Piece,
        d1: float,
        d2: float,
        v1: float,
        v2: float,
        is_running: bool,
    ) -> ArcPiece | None:
        """Trim ``d1`` off the end of ``p1`` and ``d2`` off the start of ``p2`` for
        ``arc`` and return it, if the arc saves time over stopping at the corner (cruising
        speeds ``v1``, ``v2``) and, when ``p1`` is running, it can still brake onto it."""
        acc = min(p1.acc, p2.acc)
        self._piece_limits(arc, min(p1.vplan, p2.vplan), acc)
        if not _is_blend_faster(v1, v2, arc, 0.5 * (d1 + d2), acc):
            return None
        if is_running:  # the runtime must still be able to brake onto the arc's speed
            room = p1.length - d1 - self._s - self.vel * self.cycle_time
            if self.vel * self.vel > arc.vcap**2 + 2 * p1.acc * max(room, 0.0):
                return None
        p1.trim_end(d1)
        p2.trim_start(d2)
        return arc

    def _is_tangent(self, tail: Piece, piece: Piece) -> bool:
        """LinuxCNC's tangency test: at the joint's top speed, the direction change within
        one period needs at most TANGENT_KINK_RATIO of each axis's acceleration."""
        jump = _tangent_jump(tail, piece)
        speed = min(tail.vplan, piece.vplan)
        turning_acc = speed / self.cycle_time + piece.acc
        return all(
            j * turning_acc <= TANGENT_KINK_RATIO * axis_acc
            for j, axis_acc in zip(jump, self._plan_acc, strict=True)
        )

    def _kink_speed(self, tail: Piece, piece: Piece) -> float:
        """Speed at an unblended junction. A corner (direction change above
        ``KINK_MAX_JUMP``) is passed at rest. A nearly tangent joint may be passed at the
        speed whose per-axis velocity jump stays below ``KINK_FRACTION`` of what the axis
        can change in one period; the period that crosses it keeps the rest (see step)."""
        jump = _tangent_jump(tail, piece)
        v = min(tail.vplan, piece.vplan)
        if max(jump) > KINK_MAX_JUMP:
            return 0.0
        dt = self.cycle_time
        for j, axis_acc in zip(jump, self._plan_acc, strict=True):
            if j > 1e-12:  # this axis's velocity jumps: its budget over the jump
                v = min(v, KINK_FRACTION * axis_acc * dt / j)
                tail.is_kink_end = True
        return v

    def _link(self, piece: Piece) -> int:
        """Append ``piece``; returns the index of the first piece whose plan changed.
        Lowers ``acc_tail`` of the pieces from which one period can reach the new piece,
        and the new piece's ``acc_head`` likewise (see ``Piece.window``)."""
        dt = self.cycle_time
        piece.window = (piece.vcap + piece.acc * dt) * dt
        pieces = self._pieces
        first = len(pieces)
        acc, acc_head = piece.acc, piece.acc_head
        gap = 0.0  # from the end of piece j to the start of the new piece
        for j in range(len(pieces) - 1, self._head - 1, -1):
            prev = pieces[j]
            if gap > prev.window:
                break
            if acc < prev.acc_tail:
                prev.acc_tail = acc
                first = j
            if prev.acc < acc_head:
                acc_head = prev.acc
            gap += prev.length
        piece.acc_head = acc_head
        pieces.append(piece)
        return first

    def _backward_pass(self) -> None:
        """Raise planned exit speeds from the tail back while they change (lookahead).

        A pass starts from the queue's end (at rest) and re-plans the braking ramp there,
        whatever number of pieces came since the last one, so passes are batched: one starts
        when ``REPLAN_BATCH`` pieces are waiting, or earlier when the servo period gets
        within braking reach of the first piece whose plan is out of date. A pass plans at
        most ``PASS_PIECES_PER_PERIOD`` pieces per period and goes on in the next ones.

        Meanwhile each piece's plan fits its successor's, so the servo period can follow
        it, except where ``_stale_from`` says; whenever that is within braking reach, the
        planning runs to the end in this period, as one whole pass did."""
        pieces = self._pieces
        here = pieces[self._head].s0 + self._s
        if self._pass_next is None:
            first_dirty = self._first_dirty
            if first_dirty is None:
                return
            is_batch = len(pieces) - first_dirty >= REPLAN_BATCH
            if not is_batch and self._stale_from() - here > self._reach:
                return
            self._start_pass()
        if self._stale_from() - here > self._reach:
            self._continue_pass(PASS_PIECES_PER_PERIOD)
            if self._stale_from() - here > self._reach:
                return
        while self._pass_next is not None or self._first_dirty is not None:
            if self._pass_next is None:
                self._start_pass()
            self._continue_pass(len(pieces))

    def _start_pass(self) -> None:
        self._pass_next = len(self._pieces) - 1
        self._pass_entry = 0.0  # the tail ends at rest
        self._pass_first_changed = self._first_dirty
        self._first_dirty = None

    def _stale_from(self) -> float:
        """Path position of the first piece whose plan may not fit its successor's: one
        changed since the pass under way started, one changed before that the pass has yet
        to re-plan, or the last one it has yet to re-plan when the pass is lowering exits
        (its planned exit above the entry speed the re-planned pieces now allow). Pieces
        the pass has yet to reach otherwise keep a plan that brakes onto a queue end nearer
        than the new one: their exits are no higher than the new plan's, so they fit."""
        pieces = self._pieces
        first = len(pieces)
        if self._first_dirty is not None:
            first = self._first_dirty
        pass_next = self._pass_next
        if pass_next is not None:
            if pass_next >= self._pass_first_changed:
                first = min(first, self._pass_first_changed)
            elif pieces[pass_next].v_exit > self._pass_entry:
                first = min(first, pass_next)
        if first >= len(pieces):
            return math.inf
        return pieces[max(first, self._head)].s0

    def _continue_pass(self, budget: int) -> None:
        """Plan up to ``budget`` pieces of the pass under way, from ``_pass_next`` back."""
        pieces = self._pieces
        first_changed = self._pass_first_changed
        v_next_entry = self._pass_entry
        lowest = max(self._pass_next - budget + 1, self._head)
        sqrt = math.sqrt
        for i in range(self._pass_next, lowest - 1, -1):
            p = pieces[i]
            v_exit = p.exit_max if p.exit_max < v_next_entry else v_next_entry
            if i < first_changed and v_exit == p.v_exit:
                self._pass_next = None  # the rest of the plan stands
                return
            p.v_exit = v_exit
            # the piece's zones (see Piece.window), inline: this loop is the planner's hottest
            length, window, acc = p.length, p.window, p.acc
            if length < 2.0 * window:
                low = min(p.acc_head, acc, p.acc_tail)
                v_next_entry = p.v_mid = p.v_body = sqrt(v_exit * v_exit + 2.0 * low * length)
            else:
                tail_acc = p.acc_tail if p.acc_tail < acc else acc
                head_acc = p.acc_head if p.acc_head < acc else acc
                v_mid = sqrt(v_exit * v_exit + 2.0 * tail_acc * window)
                v_body = sqrt(v_mid * v_mid + 2.0 * acc * (length - 2.0 * window))
                p.v_mid, p.v_body = v_mid, v_body
                v_next_entry = sqrt(v_body * v_body + 2.0 * head_acc * window)
            if v_next_entry > p.vplan:
                v_next_entry = p.vplan
        if lowest <= self._head:
            self._pass_next = None  # planned up to the piece being executed
        else:
            self._pass_next, self._pass_entry = lowest - 1, v_next_entry

    # ------------------------------------------------------------------ commands
    def pause(self) -> None:
        """Feed hold: decelerate along the path and stay there (MOT-037). With nothing
        queued it holds at once (task's M0/M1): moves queued later wait for resume."""
        self._is_stopping = True
        if not self._moves:
            self.is_paused = True

    def resume(self) -> None:
        """Continue exactly from where the pause stopped (MOT-038)."""
        if self._is_aborting:
            return
        self._is_stopping = False
        self._step_end = None
        self.is_paused = False

    def step_once(self) -> None:
        """STEP (MOT-039): run to the end of the current move, then pause again."""
        if not self._moves or self._is_aborting:
            return
        self._step_end = self._moves[0].end_s
        self._is_stopping = False
        self.is_paused = False

    def abort(self) -> None:
        """Decelerate along the path, then drop every queued move (MOT-022). Idempotent."""
        if not self._moves or self.vel == 0.0:
            self._reset_queue(self.pos)
            return
        self._is_stopping = True
        self._is_aborting = True

    def clear_probe_flag(self) -> None:
        """CLEAR_PROBE_FLAG (MOT-057)."""
        self.probe_tripped = False

    def take_error(self) -> str | None:
        """The last error message (a probe that did not trip...), cleared by reading."""
        error, self.error = self.error, None
        return error

    # ------------------------------------------------------------------ servo period
    def step(self) -> np.ndarray:
        """Advance one servo period; returns the commanded 9-axis position."""
        if self._dropped:
            self._free_dropped()
        if not self._moves:
            self.vel = 0.0
            return self.pos
        self._backward_pass()
        dt = self.cycle_time
        pieces = self._pieces
        p = pieces[self._head]
        move = p.move
        if move.probe is not None:
            self._check_probe(move)
            if not self._moves:  # the probe check aborted a move that had not started
                return self.pos
        revs = self.spindle_revs
        revs_delta = revs - self._last_revs
        self._last_revs = revs
        is_held = move.is_waiting_for_at_speed or move.is_waiting_for_index or self.is_start_held
        if is_held and self._is_holding(move):
            return self.pos
        if move.rigid_tap is not None:
            return self._step_rigid_tap(p, move)
        is_threading = move.sync == _POSITION  # (a plain int compare: the hot path)
        if is_threading:
            self._sync_target += revs_delta * move.feed_per_rev
        v = self.vel
        acc = p.acc
        # pause, abort, probe trip: brake along the path; a feed hold waits for the end
        # of a G33 move (stopping there would spoil the thread), as LinuxCNC's does
        if self._is_stopping and not (is_threading and not self._is_aborting):
            v_new = max(v - self._touched_acc(v) * dt, 0.0)
            self._advance(0.5 * (v + v_new) * dt, v_new)
            return self.pos
        s_here = p.s0 + self._s
        if is_threading:  # G33: follow the revolutions, no override
            v_feed = revs_delta * move.feed_per_rev / dt
            v_new = follow_speed(self._sync_target - s_here, v_feed, v, acc, dt)
        elif move.sync:
            v_new = self._feed_speed(move)
        else:
            v_new = move.vel * (self.rapid_scale if move.is_rapid else self.feed_scale)
        if v_new > p.vcap:
            v_new = p.vcap
        # Every piece this period may reach limits the speed with its cap and with its
        # braking curve onto its planned exit. The plan is consistent piece by piece (each
        # exit can be reached from the previous one at that piece's acceleration), so the
        # curves of farther pieces need not be checked.
        reach = s_here + (v + acc * dt) * dt
        a_low = acc  # the lowest acceleration of the pieces touched this period
        is_kink_step = False
        v_top = v_new
        j = self._head
        n_pieces = len(pieces)
        while j < n_pieces:  # (comparisons rather than min(): this loop runs every period)
            q = pieces[j]
            q_end = q.s0 + q.length
            if q.acc < a_low:
                a_low = q.acc
            if q.vcap < v_new:
                v_new = q.vcap
            if q.v_exit < v_top:
                v_braking = _piece_braking(q, q_end - s_here, v, dt)
                if v_braking < v_new:
                    v_new = v_braking
            if q.is_kink_end and q_end < reach:
                is_kink_step = True
            if q_end >= reach or q.v_exit <= 0.0:
                break
            j += 1
        # feed changes ahead (per-move feed and the overrides as they are now)
        feed_points = self._feed_points
        while feed_points and feed_points[0][0] <= s_here:
            feed_points.popleft()
        horizon = v * v / acc + 2.0 * v * dt + 1e-9  # farther changes cannot matter yet
        for s_feed, ahead in feed_points:
            if s_feed - s_here > horizon:
                break
            v_new = min(v_new, braking_speed(s_feed - s_here, v, acc, dt, self._feed_speed(ahead)))
        if self._step_end is not None:
            v_new = min(v_new, braking_speed(self._step_end - s_here, v, acc, dt))
        if is_kink_step:  # the joint's velocity jump takes KINK_FRACTION of the budget
            a_low *= 1.0 - KINK_FRACTION
        v_new = max(min(v_new, v + a_low * dt), v - a_low * dt, 0.0)
        self._advance(0.5 * (v + v_new) * dt, v_new)
        return self.pos

    def _free_dropped(self) -> None:
        """Free up to FREED_PER_PERIOD moves and pieces of the queues dropped."""
        dropped = self._dropped
        for _ in range(FREED_PER_PERIOD):
            items = dropped[-1]
            if items:
                item = items.pop()
                if isinstance(item, Move):
                    _release(item)
            else:
                dropped.pop()
                if not dropped:
                    return

    def _feed_speed(self, move: Move) -> float:
        """The speed a move asks for now: its feed with the override, or from the
        spindle's speed when it is synchronised (G95; G33 without its position tracking)."""
        if not move.sync:
            return move.vel * (self.rapid_scale if move.is_rapid else self.feed_scale)
        speed = move.feed_per_rev * abs(self.spindle_rps)
        return speed if move.sync == _POSITION else speed * self.feed_scale

    def _is_holding(self, move: Move) -> bool:
        """Whether a move that has not started yet waits, at rest at its start, for the
        spindle to be at speed or for the index pulse of a G33 chain; or, while
        ``is_start_held``, any move that would start from rest."""
        if self.is_start_held and self.vel == 0.0 and self._s == 0.0:
            return True
        self.is_waiting_for_at_speed = move.is_waiting_for_at_speed and not (
            self.is_spindle_at_speed
        )
        if self.is_waiting_for_at_speed:
            return True
        move.is_waiting_for_at_speed = False
        if move.is_waiting_for_index and not self._is_aborting:
            self.is_waiting_for_index = True
            return True
        return False

    def _step_rigid_tap(self, p: Piece, move: Move) -> np.ndarray:
        """One period of a rigid tap (it ignores feed hold; abort stops it where it is)."""
        tap = move.rigid_tap
        dt = self.cycle_time
        if self._is_aborting:
            u = tap.stop(p.acc, dt)
        else:
            u = tap.step(self.spindle_revs, p.vcap, p.acc, dt)
        self.spindle_reversal = tap.reversal
        self.pos = p.point(u)
        self.vel = abs(tap.vel)
        self.motion_id = move.motion_id
        self.tag = move.tag
        self.distance_to_go = abs(u) if tap.state else tap.depth - u
        if not tap.is_done:
            return self.pos
        self.vel = 0.0
        if self._is_aborting or self._head + 1 >= len(self._pieces):
            self._finish_move(move)
            self._reset_queue(self.pos)
            return self.pos
        self._finish_move(move)
        self._head += 1
        self._s = 0.0
        return self.pos

    def _touched_acc(self, v: float) -> float:
        """The lowest acceleration of the pieces this period may touch at speed ``v``."""
        pieces = self._pieces
        p = pieces[self._head]
        dt = self.cycle_time
        reach = p.s0 + self._s + (v + p.acc * dt) * dt
        acc = p.acc
        for j in range(self._head + 1, len(pieces)):
            q = pieces[j]
            if q.s0 >= reach:
                break
            acc = min(acc, q.acc)
        return acc

    def _is_stop_point(self, p: Piece) -> bool:
        if p.v_exit <= 0.0:
            return True
        return self._step_end is not None and p.s0 + p.length >= self._step_end - 1e-9

    def _advance(self, ds: float, v_new: float) -> None:
        pieces = self._pieces
        p = pieces[self._head]
        s = self._s + ds
        while True:
            if self._is_stop_point(p) and s >= p.length - 1e-12:
                s, v_new = p.length, 0.0  # arrival at a stop: the last fraction of a period
                break
            if s < p.length:
                break
            s -= p.length
            p = self._next_piece(p)
        if v_new == 0.0 and s >= p.length:
            if self._step_end is not None and p.s0 + p.length >= self._step_end - 1e-9:
                self._step_end = None
                self._is_stopping = True  # STEP done: paused at the end of the move
            if self._head + 1 >= len(pieces):
                self._finish_move(p.move)
                self._reset_queue(p.point(p.length))
                return
            p = self._next_piece(p)  # at rest on a vertex: the next period starts the next piece
            s = 0.0
        self._s = s
        self.vel = v_new
        self.pos = p.point(s)
        self.motion_id = p.move.motion_id
        self.tag = p.move.tag
        self.distance_to_go = max(p.move.end_s - (p.s0 + s), 0.0)
        if v_new == 0.0 and self._is_stopping:
            if self._is_aborting:
                self._reset_queue(self.pos)
            else:
                self.is_paused = True
        if self._head > DONE_PIECES_KEPT:  # drop the pieces done; indices shift down with them
            if self._first_dirty is not None:
                self._first_dirty = max(self._first_dirty - self._head, 0)
            if self._pass_next is not None:
                self._pass_next -= self._head
                if self._pass_next < 0:
                    self._pass_next = None  # the pass has nothing left to plan
                self._pass_first_changed = max(self._pass_first_changed - self._head, 0)
            del pieces[: self._head]
            self._head = 0

    def _next_piece(self, p: Piece) -> Piece:
        nxt = self._pieces[self._head + 1]
        if nxt.move is not p.move:
            self._finish_move(p.move)
        self._head += 1
        return nxt

    def _finish_move(self, move: Move) -> None:
        if self._moves and self._moves[0] is move:
            self._moves.popleft()
            _release(move)
            self._probe_armed = False
            if move.probe is not None and not self.probe_tripped and move.is_error_without_trip:
                self.error = "probe move finished without the probe tripping"

    def _check_probe(self, move: Move) -> None:
        if move.probe is None or self._is_stopping:
            return
        is_contact = bool(self.probe_input)
        wanted = move.probe == ProbeType.TOWARD
        if not self._probe_armed:
            self._probe_armed = True
            if is_contact == wanted:
                self.error = "probe is already in the trip state when the probe move starts"
                self.abort()
            return
        if is_contact == wanted:
            self.probe_tripped = True
            self.probe_pos = self.pos.copy()
            self.abort()


def _piece_braking(q: Piece, dist: float, v: float, dt: float) -> float:
    """Highest next speed that keeps to the curve the lookahead planned for ``q`` (zone
    by zone, see ``Piece.window``), with ``dist`` from here to the end of ``q``.

    The zone we are in is checked against its end speed at its own acceleration, and so
    is the next zone, where this period may end; a zone's curve drawn back into a zone
    of lower acceleration would be stricter than the plan, so no farther zone is used."""
    # (the zones computed here: this runs several times a period)
    length, window, acc = q.length, q.window, q.acc
    if length < 2.0 * window:  # all tail, at the lowest of the three accelerations
        return braking_speed(dist, v, min(q.acc_head, acc, q.acc_tail), dt, q.v_exit)
    head = tail = window
    body = length - 2.0 * window
    acc_tail = min(acc, q.acc_tail)
    if dist <= tail:
        return braking_speed(dist, v, acc_tail, dt, q.v_exit)
    acc_head = min(q.acc_head, acc)
    if body > 0.0 and dist > tail + body:  # in the head zone (or before the piece)
        return min(
            braking_speed(dist - tail - body, v, acc_head, dt, q.v_body),
            braking_speed(dist - tail, v, acc, dt, q.v_mid),
        )
    # the tail's curve (at its lower acceleration) only where this period may end in it:
    # drawn back farther into the body, it would brake for the tail from afar
    if dist - tail <= (v + acc * dt) * dt:
        in_tail_next = braking_speed(dist, v, acc_tail, dt, q.v_exit)
    else:
        in_tail_next = math.inf
    if body > 0.0:  # in the body: its end and the tail's
        return min(braking_speed(dist - tail, v, acc, dt, q.v_mid), in_tail_next)
    if head > 0.0:  # no body: head then tail
        return min(braking_speed(dist - tail, v, acc_head, dt, q.v_body), in_tail_next)
    return in_tail_next


def _is_blend_faster(v1: float, v2: float, arc: ArcPiece, cut: float, acc: float) -> bool:
    """Whether passing a corner on ``arc`` costs less time than stopping at it. Losses are
    counted against cruising each line at its speed (``v1`` in, ``v2`` out): a stop loses
    the time to brake to rest and to speed up again; the arc loses the slowdown to its
    own speed and back, plus its length at that speed minus the ``cut`` it saves on each
    line. (A tiny tolerance on a sharp corner makes a slow arc; stopping exactly on the
    corner is then faster.)"""
    w = min(arc.vcap, v1, v2)
    if w <= 0:
        return False
    stop = 0.5 * (v1 + v2) / acc
    slowdown = 0.5 * ((v1 - w) ** 2 / v1 + (v2 - w) ** 2 / v2) / acc
    blend = slowdown + arc.length / w - cut / v1 - cut / v2
    # the estimate ignores the lower acceleration near the arc: demand a clear gain
    return blend < BLEND_GAIN * stop


def _unit(v: np.ndarray) -> np.ndarray:
    return v / norm(v)


def _tangent_jump(tail: Piece, piece: Piece) -> list[float]:
    """Per-axis change of the unit tangent where ``piece`` follows ``tail``."""
    t_out, t_in = piece.tangent(0.0).tolist(), tail.tangent(tail.length).tolist()
    return [abs(b - a) for a, b in zip(t_in, t_out, strict=True)]


def _is_corner(tail: Piece, piece: Piece) -> bool:
    """A direction change too large to pass at speed (see _kink_speed)."""
    return max(_tangent_jump(tail, piece)) > KINK_MAX_JUMP


def _is_flat_corner(p1: Piece, p2: Piece, t1: np.ndarray, t2: np.ndarray) -> bool:
    """Whether both pieces lie in the XYZ plane of the corner's tangents ``t1``, ``t2``:
    lines moving XYZ only, flat circles about that plane's normal."""
    normal = _unit(cross3(t1[XYZ], t2[XYZ]))
    for p in (p1, p2):
        if isinstance(p, LinePiece):
            if not p.is_xyz_only():
                return False
        elif isinstance(p, ArcPiece):
            arc_normal = p.plane_normal()
            if arc_normal is None or norm(cross3(arc_normal, normal)) > 1e-9:
                return False
        else:
            return False
    return True


def _tangent_arc(
    move: Move, p1: Piece, p2: Piece, d1: float, d2_max: float
) -> tuple[ArcPiece, float] | None:
    """The arc tangent to ``p1`` at ``d1`` before its end and to ``p2`` at some ``d2``
    after its start, with the ``d2`` (up to ``d2_max``) where the two tangent lines meet
    as far from both points; or None when there is no such ``d2``."""
    start = p1.point(p1.length - d1)
    t1 = _unit(p1.tangent(p1.length - d1))

    def legs(d2: float) -> tuple[float, float, np.ndarray]:
        """How far the tangents' meeting point is from each end, and p2's direction."""
        t2 = _unit(p2.tangent(d2))
        w = p2.point(d2) - start
        c = float(t1.dot(t2))  # (ndarray.dot: as ``@``, at half the cost)
        det = 1.0 - c * c
        if det < 1e-12:  # parallel tangents never meet: treat as trimmed too far
            return 0.0, math.inf, t2
        w1, w2 = float(t1.dot(w)), float(t2.dot(w))
        return (w1 - c * w2) / det, (w2 - c * w1) / det, t2

    lo, hi = 0.0, d2_max
    a, b, _ = legs(lo)
    if a - b <= 0.0:
        return None  # the meeting point is nearer p1's end even without trimming p2
    a, b, _ = legs(hi)
    if a - b >= 0.0:
        return None  # the meeting point is nearer p2's end even at the largest trim
    for _ in range(60):  # bisection on a - b, which falls as d2 grows
        mid = 0.5 * (lo + hi)
        a, b, _ = legs(mid)
        if a - b > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-12 * (1.0 + hi):
            break
    d2 = 0.5 * (lo + hi)
    a, b, t2 = legs(d2)
    if not (a > 1e-9 and b > 1e-9 and abs(a - b) <= 1e-9 * (1.0 + a)):
        return None  # (a - b jumped over 0: the tangents' meeting point went to infinity)
    turn = math.acos(max(-1.0, min(1.0, float(t1.dot(t2)))))
    if not COLLINEAR_ANGLE < turn < MAX_BLEND_TURN:
        return None
    radius = 0.5 * (a + b) / math.tan(0.5 * turn)
    return blend_arc(move, start + t1 * a, t1, t2, radius, turn), d2


def _release(move: Move) -> None:
    """Drop a move's references to its pieces, which point back to it, once it left the
    queue: the realtime host runs without the garbage collector, so that reference cycle
    would keep every move and its pieces in memory (ARCH-017)."""
    move.line = move.arc = None


def _feed_key(move: Move) -> tuple:
    """What makes the feed of two moves differ (a feed change point between them)."""
    return (move.vel, move.is_rapid, move.sync, move.feed_per_rev)


def _check_scale(scale: float) -> float:
    scale = check_finite("scale", scale)
    if scale < 0:
        raise ValueError(f"scale must be >= 0, got {scale}")
    return scale


# the name a replacement planner module exports (motion.tp.load_planner, ARCH-008)
Planner = TrajectoryPlanner
