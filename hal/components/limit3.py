"""limit3: follow ``in`` within position [min, max], velocity ``maxv`` and acceleration ``maxa``.

Each period the output picks a goal: the input (predicted to where its velocity can be
matched), or the min/max limit when heading into it. It then accelerates at ``maxa``
towards the goal, brakes at ``maxa`` when it would overshoot, and eases onto the goal over
``smooth-steps`` periods once it can reach it, so it locks onto a moving input instead of
oscillating around it (LinuxCNC's limit3 behaviour, period for period). ``load`` makes the
output jump to the (clamped) input; with ``enable`` false it returns to 0 under the same
limits; with ``maxa`` <= 0 the output holds still.
"""

from hal.api import RtComponent, funct, pin

EPSILON = 1e-9  # tolerance for rounding in the comparisons below


class Limit3(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    load = pin("bit in")
    enable = pin("bit in", default=1)
    min = pin("float in", default=-1e20)
    max = pin("float in", default=1e20)
    maxv = pin("float in", default=1e20)
    maxa = pin("float in", default=1e20)
    smooth_steps = pin("u32 in", default=2)

    def setup(self) -> None:
        self.in_old = 0.0  # input of the previous period
        self.out_old = 0.0  # output of the previous period

    def _move(self, out: float, target: float, new_out: float) -> None:
        self.out_old = out
        self.out = new_out
        self.in_old = target

    @funct()
    def update(self, period: int) -> None:
        dt = period * 1e-9
        target = self.in_ if self.enable else 0.0
        low, high = self.min, self.max
        out = self.out
        if self.load:
            clamped = min(high, max(low, target))
            self._move(out, clamped, clamped)
            return
        maxv, maxa = self.maxv, self.maxa
        if maxa <= 0.0 or maxv < 0.0:  # nothing may move: hold the output
            return self._move(out, target, out)
        in_vel = (target - self.in_old) / dt
        out_vel = (out - self.out_old) / dt
        # the reachable velocities and positions for this period
        vel_low = max(out_vel - maxa * dt, -maxv)
        vel_high = min(out_vel + maxa * dt, maxv)
        pos_low = out + vel_low * dt
        pos_high = out + vel_high * dt

        def is_reachable(position: float) -> bool:
            return pos_low <= position <= pos_high

        # where we would stop, braking from the next period on
        stop_high = out + vel_high / 2 * (abs(vel_high / maxa) + dt)
        stop_low = out + vel_low / 2 * (abs(vel_low / maxa) + dt)
        # time to match the input's velocity (we run one period behind it), and where
        # output and input are by then
        match_high = abs((in_vel - vel_high) / maxa) - dt
        match_low = abs((in_vel - vel_low) / maxa) - dt
        out_at_match_high = pos_high + (vel_high + in_vel) / 2 * match_high
        out_at_match_low = pos_low + (vel_low + in_vel) / 2 * match_low
        in_at_match_high = target + in_vel * match_high
        in_at_match_low = target + in_vel * match_low

        # choose the goal: a limit we are heading into, or the input
        vel_diff = -out_vel
        reach_low, reach_high = stop_low, stop_high
        if stop_high > high + EPSILON and not is_reachable(high):
            goal_low = goal_high = goal_now = goal_before = high
        elif stop_low < low - EPSILON and not is_reachable(low):
            goal_low = goal_high = goal_now = goal_before = low
        elif target >= high and in_at_match_high > out_at_match_high:
            goal_low = goal_high = goal_now = goal_before = high
        elif target <= low and in_at_match_low < out_at_match_low:
            goal_low = goal_high = goal_now = goal_before = low
        else:
            goal_low, goal_high = in_at_match_low, in_at_match_high
            goal_now, goal_before = target, self.in_old
            vel_diff = out_vel - in_vel
            reach_low, reach_high = out_at_match_low, out_at_match_high

        # time to the goal at constant acceleration
        gap = out - goal_before
        time_left = 0.0 if abs(vel_diff) < EPSILON else gap / (vel_diff / 2)
        if is_reachable(goal_now) and abs(time_left) <= dt:
            return self._move(out, target, goal_now)
        if reach_high < goal_high + EPSILON:  # full acceleration still falls short
            return self._move(out, target, pos_high)
        if reach_low > goal_low - EPSILON:
            return self._move(out, target, pos_low)
        if abs(time_left) < dt * self.smooth_steps:
            # land softly: uniform acceleration over a whole number of periods
            sign = 1 if time_left >= 0 else -1
            periods = int((time_left - EPSILON * sign) / dt + sign)
            accel = vel_diff / (periods * dt)
            step = (out_vel + accel * dt) * dt
            return self._move(out, target, min(pos_high, max(pos_low, out + step)))
        if goal_high + EPSILON < reach_high and goal_before > out:  # overshoot upwards
            return self._move(out, target, pos_low)
        if goal_low - EPSILON > reach_low and goal_before < out:  # overshoot downwards
            return self._move(out, target, pos_high)
        return self._move(out, target, (pos_low + pos_high) / 2)  # coast


COMPONENT = Limit3
