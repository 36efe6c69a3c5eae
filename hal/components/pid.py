"""pid: PID controller with feedforward (LinuxCNC's pin names, gains as pins like 2.9).

``loadrt pid [num_chan=N | count=N | names=...]`` (three loops by default). Per period:
error = command - feedback (the previous period's command when ``error-previous-target``;
the ``error`` pin shows it before limits), then maxerror, deadband, the integral (not while
the output is clamped), errorD = command-deriv - feedback-deriv (both computed when their
pins are not connected), command derivatives, and
``output = bias + P*error + I*errorI + D*errorD + FF0*cmd + FF1*cmdD + FF2*cmdDD + FF3*cmdDDD``
limited to ``maxoutput``. Every ``max*`` limit of 0 means no limit. With ``enable`` false
the integrator is reset and output is 0. The autotune pins exist but autotuning is not
implemented.
"""

from __future__ import annotations

from hal.api import RtComponent, funct, pin


def _limit(value: float, bound: float) -> float:
    if bound > 0.0:
        return min(max(value, -bound), bound)
    return value


class Pid(RtComponent):
    Pgain = pin("float in", default=1.0)
    Igain = pin("float in")
    Dgain = pin("float in")
    FF0 = pin("float in")
    FF1 = pin("float in")
    FF2 = pin("float in")
    FF3 = pin("float in")
    bias = pin("float in")
    command = pin("float in")
    command_deriv = pin("float in")
    feedback = pin("float in")
    feedback_deriv = pin("float in")
    deadband = pin("float in")
    enable = pin("bit in")
    error = pin("float out")
    error_previous_target = pin("bit in", default=1)
    index_enable = pin("bit in")
    maxcmdD = pin("float in")
    maxcmdDD = pin("float in")
    maxcmdDDD = pin("float in")
    maxerror = pin("float in")
    maxerrorD = pin("float in")
    maxerrorI = pin("float in")
    maxoutput = pin("float in")
    output = pin("float out")
    saturated = pin("bit out")
    saturated_count = pin("s32 out")
    saturated_s = pin("float out")
    tune_cycles = pin("u32 io", default=50)
    tune_effort = pin("float io", default=0.5)
    tune_mode = pin("bit in")
    tune_start = pin("bit io")
    tune_type = pin("u32 io")

    count_option = "num_chan"
    default_count = 3
    max_count = 16
    options = {"debug": int}  # (LinuxCNC's extra debugging pins are not made)

    def setup(self, debug: int = 0) -> None:
        self.error_i = 0.0
        self.prev_cmd = 0.0
        self.prev_fb = 0.0
        self.cmd_d = 0.0
        self.cmd_dd = 0.0
        self.was_index_enabled = False
        self.limit_state = 0.0  # +1/-1 while the output is clamped, for anti-windup

    @funct("do-pid-calcs")
    def update(self, period: int) -> None:
        dt = period * 1e-9
        is_enabled = self.enable
        command, feedback = self.command, self.feedback
        is_index_enabled = self.index_enable
        # an index reset (index-enable falling) jumps the positions: skip this period's
        # previous-target error and derivatives rather than produce a spike
        just_indexed = self.was_index_enabled and not is_index_enabled
        if self.error_previous_target and not just_indexed:
            error = self.prev_cmd - feedback
        else:
            error = command - feedback
        self.error = error
        error = _limit(error, self.maxerror)
        deadband = self.deadband
        if error > deadband:
            error -= deadband
        elif error < -deadband:
            error += deadband
        else:
            error = 0.0
        if is_enabled:
            if error * self.limit_state <= 0.0:  # no integrator wind-up while clamped
                self.error_i += error * dt
            self.error_i = _limit(self.error_i, self.maxerrorI)
        else:
            self.error_i = 0.0
        # unconnected derivative pins show the derivatives computed here
        if not just_indexed:
            if not self.is_connected("command_deriv"):
                self.command_deriv = (command - self.prev_cmd) / dt
            if not self.is_connected("feedback_deriv"):
                self.feedback_deriv = (feedback - self.prev_fb) / dt
        command_v = self.command_deriv
        error_d = _limit(command_v - self.feedback_deriv, self.maxerrorD)
        old_cmd_d, old_cmd_dd = self.cmd_d, self.cmd_dd
        self.was_index_enabled = is_index_enabled
        self.prev_cmd, self.prev_fb = command, feedback
        cmd_d = _limit(command_v, self.maxcmdD)
        cmd_dd = _limit((cmd_d - old_cmd_d) / dt, self.maxcmdDD)
        cmd_ddd = _limit((cmd_dd - old_cmd_dd) / dt, self.maxcmdDDD)
        self.cmd_d, self.cmd_dd = cmd_d, cmd_dd
        if is_enabled:
            output = (
                self.bias
                + self.Pgain * error
                + self.Igain * self.error_i
                + self.Dgain * error_d
                + self.FF0 * command
                + self.FF1 * cmd_d
                + self.FF2 * cmd_dd
                + self.FF3 * cmd_ddd
            )
            limit = self.maxoutput
            self.limit_state = 0.0
            if limit != 0.0 and output > limit:
                output, self.limit_state = limit, 1.0
            elif limit != 0.0 and output < -limit:
                output, self.limit_state = -limit, -1.0
        else:
            output, self.limit_state = 0.0, 0.0
        self.output = output
        if self.limit_state:
            self.saturated = True
            self.saturated_s = self.saturated_s + dt
            self.saturated_count = min(self.saturated_count + 1, (1 << 31) - 1)
        else:
            self.saturated = False
            self.saturated_s = 0.0
            self.saturated_count = 0


COMPONENT = Pid
