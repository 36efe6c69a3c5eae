"""Motion's part in the machine's safety (nml/safety.py): the last line of defence.

Every servo period motion beats its heartbeat and looks at the safety board's E-stop and
abort requests, so they take effect within a period whatever task, iocontrol or a user
interface is doing:

- an immediate E-stop turns motion off at once and stops the spindles;
- a braking E-stop (a supervised process was lost) aborts along the path and stops the
  spindles; once motion is at rest (or after BRAKE_TIMEOUT_S) it turns off and asks for
  the immediate E-stop, which turns iocontrol's outputs off;
- an abort decelerates everything, as task's abort does, spindles included.

Every LOST_SCAN_PERIODS it looks for supervised processes that stopped beating (task
included: motion stops the machine when task stops talking to it), and every
LEASE_CHECK_PERIODS it stops continuous jogs whose requester went quiet.
"""

from __future__ import annotations

from motion.controller import MotionController
from nml.safety import BRAKE_TIMEOUT_S, SafetyBoard, SafetyLink, now_ns

LEASE_CHECK_PERIODS = 10
DEFAULT_UNLEASED_JOG_S = 0.5  # a continuous jog nobody keeps alive (pid 0) runs this long
DEFAULT_HEARTBEAT_TIMEOUT_S = 0.5  # [EMCMOT]HEARTBEAT_TIMEOUT: motion's own


class MotionSafety:
    def __init__(
        self, board: SafetyBoard, controller: MotionController, period_s: float, timeout_s: float
    ) -> None:
        self.board = board
        self.controller = controller
        self.period_s = period_s
        self.heartbeat_timeout_s = timeout_s
        # registered at the first period: before the threads start (HAL files still being
        # read), motion runs nothing and must not be taken for lost
        self.link: SafetyLink | None = None
        self.brake_deadline = 0  # monotonic ns; 0: not braking
        self.periods = 0
        self.messages: list[str] = []  # for the operator (motmod writes them)

    @classmethod
    def open(
        cls, controller: MotionController, period_s: float, heartbeat_timeout_s: float
    ) -> MotionSafety | None:
        board = SafetyBoard.attach()
        return None if board is None else cls(board, controller, period_s, heartbeat_timeout_s)

    def period(self) -> None:
        """Once a servo period, before the controller's update."""
        if self.link is None:
            heartbeat = self.board.register("motion", self.heartbeat_timeout_s, is_supervised=True)
            self.link = SafetyLink(self.board, heartbeat, is_reporter=True)
        tick = self.link.tick()
        controller = self.controller
        for lost in tick.lost:
            self.messages.append(f"E-stop: {lost.reason}")
        if tick.estop is not None:
            if tick.estop.is_braking and controller.is_enabled:
                controller.abort_all()
                self.brake_deadline = now_ns() + int(BRAKE_TIMEOUT_S * 1e9)
            else:
                self.brake_deadline = 0
                controller.estop()
        if tick.abort is not None:
            controller.abort_all()
        if self.brake_deadline:
            self._brake()
        self.periods += 1
        if self.periods % LEASE_CHECK_PERIODS == 0 and controller.jog_leases:
            self._check_jog_leases()

    def _brake(self) -> None:
        controller = self.controller
        if controller.is_enabled and not controller.is_in_position:
            if now_ns() < self.brake_deadline:
                return
            self.messages.append(f"motion: not at rest {BRAKE_TIMEOUT_S:g} s after E-stop")
        self.brake_deadline = 0
        controller.estop()
        self.board.request_estop("motion at rest after a braking E-stop")

    def _check_jog_leases(self) -> None:
        controller = self.controller
        now = now_ns()
        for key, lease in list(controller.jog_leases.items()):
            if not controller.jog_planner(key).is_active:
                del controller.jog_leases[key]  # it ended by itself (a limit, a stop)
            elif lease.pid:
                if not self.board.slot_is_alive(lease.slot, lease.pid, now):
                    controller.stop_jog(
                        key,
                        f"{lease.name}: continuous jog stopped: the program that started it "
                        f"(pid {lease.pid}) stopped keeping it alive",
                    )
            else:
                if lease.periods_left < 0:
                    lease.periods_left = int(DEFAULT_UNLEASED_JOG_S / self.period_s)
                lease.periods_left -= LEASE_CHECK_PERIODS
                if lease.periods_left <= 0:
                    controller.stop_jog(
                        key,
                        f"{lease.name}: continuous jog stopped: nobody keeps it alive "
                        "(send it again to go on)",
                    )

    def close(self) -> None:
        if self.link is not None:
            self.link.close()
        else:
            self.board.close()
