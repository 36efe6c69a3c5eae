"""Following the spindle: the tracking law of spindle-synchronised motion and the rigid
tapping cycle (G33, G33.1; MOT-065).

A synchronised move has a target path position given by the spindle's revolutions
(``revs * feed_per_rev``). ``follow_speed`` gives the next speed: the spindle's own speed
(feed forward) plus a correction that closes the position error as fast as the
acceleration allows without overshooting, within one period's velocity change.

A rigid tap (``RigidTap``) runs along its line in a coordinate ``u`` (0 at the start,
``depth`` at the programmed end), following the spindle all the way, as LinuxCNC does:

- TAPPING: in, until the target reaches the depth; then the spindle is reversed
  (``reversal`` = -retract scale);
- REVERSING: the spindle slows down, so the tool still goes a little deeper (overrun);
  once the spindle turns the other way the target comes back:
- RETRACTING: out, until the target is back at the start; the spindle is turned forward
  again (``reversal`` = 1);
- FINAL_REVERSAL: the spindle slows down again, taking the tool a little above the start;
  once it turns forward the tool no longer follows it:
- FINAL_PLACEMENT: a plain move back to the start point, where the cycle ends at rest.
"""

from __future__ import annotations

import enum
import math

# distance (path units) under which the final placement counts as arrived
ARRIVAL = 1e-9


def follow_speed(error: float, v_feed: float, v: float, acc: float, dt: float) -> float:
    """Next signed speed that follows a target ``error`` ahead (where the target is at the
    end of this period) moving at ``v_feed``, changing the current speed ``v`` by at most
    ``acc * dt``. The correction closes what is left after this period at ``v_feed``."""
    left = error - v_feed * dt
    distance = abs(left)
    correction = min(math.sqrt(acc * distance), distance / (2.0 * dt))
    v_des = v_feed + math.copysign(correction, left)
    adt = acc * dt
    return min(max(v_des, v - adt), v + adt)


class TapState(enum.IntEnum):
    TAPPING = 0
    REVERSING = 1
    RETRACTING = 2
    FINAL_REVERSAL = 3
    FINAL_PLACEMENT = 4


class RigidTap:
    """One G33.1 cycle along a line of length ``depth``; ``step`` once per period."""

    def __init__(self, depth: float, feed_per_rev: float, retract_scale: float) -> None:
        self.depth = depth
        self.feed_per_rev = feed_per_rev
        self.retract_scale = retract_scale
        self.state = TapState.TAPPING
        self.u = 0.0  # position along the line
        self.vel = 0.0
        self.reversal = 1.0  # factor on the spindle speed (negative: reversed)
        self.is_done = False
        self._revs0: float | None = None
        self._last_target = 0.0

    def step(self, revs: float, vmax: float, acc: float, dt: float) -> float:
        """Advance one period with the spindle at ``revs``; returns ``u``."""
        if self._revs0 is None:
            self._revs0 = revs  # rigid tapping needs no index: it starts where it is
        target = (revs - self._revs0) * self.feed_per_rev
        v_feed = (target - self._last_target) / dt
        is_coming_back = target < self._last_target
        self._last_target = target
        state = self.state
        if state == TapState.TAPPING and target >= self.depth:
            self.state, self.reversal = TapState.REVERSING, -self.retract_scale
        elif state == TapState.REVERSING and is_coming_back:
            self.state = TapState.RETRACTING
        elif state == TapState.RETRACTING and target <= 0.0:
            self.state, self.reversal = TapState.FINAL_REVERSAL, 1.0
        elif state == TapState.FINAL_REVERSAL and not is_coming_back:
            self.state = TapState.FINAL_PLACEMENT
        if self.state == TapState.FINAL_PLACEMENT:
            target, v_feed = 0.0, 0.0
        v_new = follow_speed(target - self.u, v_feed, self.vel, acc, dt)
        v_new = min(max(v_new, -vmax), vmax)
        self.u += 0.5 * (self.vel + v_new) * dt
        self.vel = v_new
        is_arrived = abs(self.u) < ARRIVAL and abs(v_new) <= acc * dt
        if self.state == TapState.FINAL_PLACEMENT and is_arrived:
            self.u, self.vel, self.is_done = 0.0, 0.0, True
        return self.u

    def stop(self, acc: float, dt: float) -> float:
        """Abort: decelerate where the tool is; ``is_done`` once at rest."""
        v = self.vel
        v_new = max(v - acc * dt, 0.0) if v > 0 else min(v + acc * dt, 0.0)
        self.u += 0.5 * (v + v_new) * dt
        self.vel = v_new
        self.is_done = v_new == 0.0
        return self.u
