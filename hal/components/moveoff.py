"""moveoff: offsets added to joint positions while motion is paused or idle (e.g. to move a
tool away from a stopped cut), then removed, retracing the way back.

``loadrt moveoff personality=N`` (joints, default 3, at most 9). Between a joint's
``pos-M``/``fb-M`` and its PID: ``pos-plusoffset-M`` = pos + offset and
``fb-minusoffset-M`` = fb - offset. While ``power-on``, ``move-enable`` and
``apply-offsets`` are all true, each offset follows ``offset-in-M`` within
``offset-min/max-M`` at most at ``offset-vel-M`` and ``offset-accel-M`` (limit3's
planner), and waypoints are recorded (every ``waypoint-sample-secs`` when a joint moved
more than ``waypoint-threshold``; at most 1000, ``waypoint-limit`` then stops it). When one
of them drops, the offsets go back to 0 along the waypoints (straight with
``backtrack-enable`` false), within ``epsilon``. ``offset-applied`` says an offset
remains; ``warning`` that ``apply-offsets`` dropped meanwhile. Functions
``moveoff.N.read-inputs`` and ``moveoff.N.write-outputs``.
"""

from __future__ import annotations

import time
from typing import Any

from hal.api import RtComponent, funct, pin, sized

IDLE, MOVE_AWAY, MOVE_BACK = 0, 1, 2
MAX_WAYPOINTS, TEST_WAYPOINTS = 1000, 50
MIN_EPSILON = 0.0001


def limit3_step(
    wanted: float,
    low: float,
    high: float,
    max_vel: float,
    max_accel: float,
    state: list[float],
    dt: float,
) -> float:
    """One period of limit3's planner; ``state`` is [old in, old out, old velocity]."""
    old_in, old_out, old_v = state
    limited = high if wanted > high else low if wanted < low else wanted
    state[0] = limited
    in_v = (limited - old_in) / dt
    min_v = max(old_v - max_accel * dt, -max_vel)
    max_v = min(old_v + max_accel * dt, max_vel)
    min_out, max_out = old_out + min_v * dt, old_out + max_v * dt
    if min_out <= limited <= max_out and min_v <= in_v <= max_v:
        state[1], state[2] = limited, (limited - old_out) / dt
        return limited
    ramp = max_accel if in_v > old_v else -max_accel
    match_time = (in_v - old_v) / ramp
    average_v = (in_v + old_v + ramp * dt) * 0.5
    error = old_out + average_v * match_time - (old_in + in_v * match_time)
    step = -2.0 * ramp * dt * match_time
    if abs(error + step * 2.0) < abs(error):
        ramp = -ramp
    if ramp < 0.0:
        state[1], state[2] = min_out, min_v
    else:
        state[1], state[2] = max_out, max_v
    return state[1]


def _joints(options: dict[str, Any]) -> int:
    return options["personality"] or 3


class MoveOff(RtComponent):
    has_personality = True
    power_on = pin("bit in")
    move_enable = pin("bit in")
    apply_offsets = pin("bit in")
    backtrack_enable = pin("bit in", default=1)
    epsilon = pin("float in", default=0.0005)
    waypoint_threshold = pin("float in", default=0.02)
    waypoint_sample_secs = pin("float in", default=0.02)
    warning = pin("bit out")
    offset_applied = pin("bit out")
    waypoint_limit = pin("bit out")
    waypoint_ct = pin("s32 out")
    waypoint_percent_used = pin("s32 out")
    offset_in = pin("float in", "offset-in-{}", count=sized(9, _joints))
    pos = pin("float in", "pos-{}", count=sized(9, _joints))
    fb = pin("float in", "fb-{}", count=sized(9, _joints))
    offset_current = pin("float out", "offset-current-{}", count=sized(9, _joints))
    pos_plusoffset = pin("float out", "pos-plusoffset-{}", count=sized(9, _joints))
    fb_minusoffset = pin("float out", "fb-minusoffset-{}", count=sized(9, _joints))
    offset_vel = pin("float in", "offset-vel-{}", count=sized(9, _joints), default=10.0)
    offset_accel = pin("float in", "offset-accel-{}", count=sized(9, _joints), default=100.0)
    offset_min = pin("float in", "offset-min-{}", count=sized(9, _joints), default=-1e20)
    offset_max = pin("float in", "offset-max-{}", count=sized(9, _joints), default=1e20)
    dbg_waypoint_limit_test = pin("bit in")
    dbg_state = pin("s32 out")

    def setup(self, personality: int = 0) -> None:
        self.joints = personality or 3
        self.state = self.next_state = IDLE
        self.limits = [[0.0, 0.0, 0.0] for _ in range(self.joints)]
        self.goal = [0.0] * self.joints
        self.waypoints: list[list[float]] = []  # recorded offsets
        self.next_index = 0  # where the next waypoint goes; backtracking counts it down
        self.last_waypoint_ns = 0
        self.threshold = self.sample_secs = 0.0
        self.eps = MIN_EPSILON
        self.max_waypoints = MAX_WAYPOINTS
        self.is_moving = False
        self.is_backtracking = True
        self.period = 1_000_000

    def _reset_limits(self) -> None:
        for state in self.limits:
            state[:] = [0.0, 0.0, 0.0]

    @funct("read-inputs")
    def read_inputs(self, period: int) -> None:
        self.period = period
        now = time.monotonic_ns()
        is_all_enabled = self.power_on and self.move_enable and self.apply_offsets
        self.is_backtracking = self.backtrack_enable
        joints = range(self.joints)
        if self.state == IDLE:  # settings change only while idle
            self.threshold = self.waypoint_threshold
            self.sample_secs = self.waypoint_sample_secs
            self.eps = max(self.epsilon, MIN_EPSILON)
            self.max_waypoints = TEST_WAYPOINTS if self.dbg_waypoint_limit_test else MAX_WAYPOINTS
        current = [self.offset_current[j] for j in joints]
        if self.state == IDLE:
            self.next_index = 0
        elif self.state == MOVE_AWAY and not self.waypoint_limit:
            since = (now - self.last_waypoint_ns) / 1e9
            index = self.next_index
            last = self.waypoints[index - 1] if index > 0 else [0.0] * self.joints
            if since >= self.sample_secs and any(
                abs(current[j] - last[j]) > self.threshold for j in joints
            ):
                del self.waypoints[index:]
                self.waypoints.append(current)
                self.last_waypoint_ns = now
                self.next_index = index + 1
                self.waypoint_limit = self.next_index > self.max_waypoints - 1
        state = self.state
        if state == IDLE:
            self.last_waypoint_ns = now
            if is_all_enabled:
                self.next_state = MOVE_AWAY
                self.is_moving = True
                self.goal = [self.offset_in[j] for j in joints]
        elif state == MOVE_AWAY:
            self.is_moving = True
            if is_all_enabled:
                self.goal = [self.offset_in[j] for j in joints]
            elif not self.power_on:
                self._power_lost()
            else:  # go back: to the last waypoint first, or straight home
                self.next_state = MOVE_BACK
                self.goal = [0.0] * self.joints
                if self.is_backtracking and self.next_index > 0:
                    self.goal = list(self.waypoints[self.next_index - 1])
                    self.waypoint_limit = False
                    self.next_index -= 1
        elif state == MOVE_BACK:
            if not self.power_on:
                self._power_lost()
            else:
                self.is_moving = True
                if self.is_backtracking:
                    if self.next_index > 0:
                        # (LinuxCNC's order: at a waypoint the goal becomes the waypoint the
                        # index shows, then the index moves down)
                        if all(abs(current[j] - self.goal[j]) <= self.eps for j in joints):
                            self.goal = list(self.waypoints[self.next_index])
                            self.next_index -= 1
                    else:
                        self.goal = [0.0] * self.joints
                if not self.offset_applied:  # all offsets gone
                    self.next_state = IDLE
                    self.is_moving = False
                    self._reset_limits()
        self.warning = not self.apply_offsets and self.offset_applied

    def _power_lost(self) -> None:
        self._reset_limits()
        self.is_moving = False
        self.offset_applied = False
        self.next_state = IDLE

    @funct("write-outputs")
    def write_outputs(self, period: int) -> None:
        dt = self.period * 1e-9
        is_held = self.waypoint_limit and self.state == MOVE_AWAY
        for j in range(self.joints):
            if self.is_moving:
                if is_held:
                    continue  # no movement at the waypoint limit
                state = self.limits[j]
                before = state[1]
                offset = limit3_step(
                    self.goal[j],
                    self.offset_min[j],
                    self.offset_max[j],
                    self.offset_vel[j],
                    self.offset_accel[j],
                    state,
                    dt,
                )
                self.offset_current[j] = offset
                self.fb_minusoffset[j] = self.fb[j] - offset - (before - offset)
                self.pos_plusoffset[j] = self.pos[j] + offset
            else:
                self.pos_plusoffset[j] = self.pos[j]
                self.offset_current[j] = 0.0
                self.fb_minusoffset[j] = self.fb[j]
        is_applied = any(abs(state[1]) > self.eps for state in self.limits)
        self.offset_applied = is_applied
        if not is_applied:
            self.next_index = 0
            self.waypoint_limit = False
        count = self.next_index
        self.waypoint_ct = count
        self.waypoint_percent_used = 100 * count // self.max_waypoints
        self.dbg_state = self.state
        self.state = self.next_state


COMPONENT = MoveOff
