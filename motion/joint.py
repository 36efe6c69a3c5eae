"""The joint record (ARCH-022) and its per-period bookkeeping (MOT-001..008, MOT-072..074).

All data of one joint live in one ``Joint``: its free-mode planner, the position forms
(2) coarse_pos, (3) pos_cmd, (4) motor_pos_cmd, (5) motor_pos_fb, (6) pos_fb, the home
offset (``motor_offset``), backlash and leadscrew compensation, the following error and
the HAL-facing switch bits that homing reads.

Each servo period the motion component does, per joint:

1. ``update_feedback(motor_pos_fb)``: pos_fb = motor_pos_fb - offset - compensation (MOT-007),
   and the following error: the command of the last period, which this feedback answers,
   minus the feedback (as LinuxCNC's motion, before it computes the new command);
2. homing (``motion.homing``) and the planners set ``pos_cmd`` (free mode: ``planner.step``);
3. ``update_command(dt)``: motor_pos_cmd = pos_cmd + compensation + offset (MOT-005);
4. ``is_following_error()``: fault when the error exceeds the speed-scaled limit (MOT-074).
"""

from __future__ import annotations

import itertools
import math
import os
from bisect import bisect_right
from dataclasses import dataclass

from motion.free import FreePlanner, check_finite


class CompFileError(ValueError):
    """A malformed leadscrew compensation file; the message has file:line."""


@dataclass(frozen=True, slots=True)
class CompEntry:
    nominal: float
    forward: float  # correction when moving in the positive direction
    reverse: float  # correction when moving in the negative direction


class CompTable:
    """Leadscrew error compensation (MOT-073): LinuxCNC's file of ``nominal forward
    reverse`` triples, one per line, nominal strictly increasing. With ``COMP_FILE_TYPE``
    0 the forward/reverse values are the positions to command to reach ``nominal`` in
    that direction; with type 1 they are the corrections themselves. Between entries the
    correction is interpolated linearly; outside them it stays at the end values."""

    def __init__(self, entries: list[CompEntry]) -> None:
        for a, b in itertools.pairwise(entries):
            if b.nominal <= a.nominal:
                raise ValueError("compensation nominal positions must increase")
        self.entries = entries
        self._nominals = [e.nominal for e in entries]

    @classmethod
    def load(cls, path: str | os.PathLike[str], file_type: int = 0) -> CompTable:
        if file_type not in (0, 1):
            raise CompFileError(f"{path}: COMP_FILE_TYPE must be 0 or 1, got {file_type}")
        entries: list[CompEntry] = []
        try:
            lines = open(path, encoding="utf-8").read().splitlines()  # noqa: SIM115
        except OSError as exc:
            raise CompFileError(f"{path}: cannot read compensation file: {exc.strerror}") from exc
        for number, raw in enumerate(lines, start=1):
            text = raw.strip()
            if not text or text[0] in "#;":
                continue
            fields = text.split()
            try:
                nominal, forward, reverse = (float(f) for f in fields)
            except ValueError:
                raise CompFileError(
                    f"{path}:{number}: expected three numbers 'nominal forward reverse'"
                ) from None
            if not all(math.isfinite(v) for v in (nominal, forward, reverse)):
                raise CompFileError(f"{path}:{number}: values must be finite")
            if entries and nominal <= entries[-1].nominal:
                raise CompFileError(f"{path}:{number}: nominal positions must increase")
            if file_type == 0:
                forward, reverse = forward - nominal, reverse - nominal
            entries.append(CompEntry(nominal, forward, reverse))
        return cls(entries)

    def correction(self, pos: float, is_forward: bool) -> float:
        entries = self.entries
        if not entries:
            return 0.0
        i = bisect_right(self._nominals, pos)
        if i == 0:
            e = entries[0]
            return e.forward if is_forward else e.reverse
        if i == len(entries):
            e = entries[-1]
            return e.forward if is_forward else e.reverse
        a, b = entries[i - 1], entries[i]
        t = (pos - a.nominal) / (b.nominal - a.nominal)
        lo, hi = (a.forward, b.forward) if is_forward else (a.reverse, b.reverse)
        return lo + t * (hi - lo)


class Joint:
    """One joint's record; see the module docstring for the per-period order."""

    def __init__(
        self,
        max_vel: float,
        max_acc: float,
        min_limit: float = -math.inf,
        max_limit: float = math.inf,
        ferror: float = math.inf,
        min_ferror: float = math.inf,
        backlash: float = 0.0,
        comp: CompTable | None = None,
    ) -> None:
        self.planner = FreePlanner(max_vel, max_acc, min_limit, max_limit)
        self.set_ferror(ferror, min_ferror)
        self.set_backlash(backlash)
        self.comp = comp
        # compensation is slewed by its own small planner so that a direction reversal
        # never steps the motor: at a tenth of the joint's limits (MOT-072)
        self._comp_filter = FreePlanner(0.1 * max_vel, 0.1 * max_acc)
        self.coarse_pos = 0.0  # (2)
        self.pos_cmd = 0.0  # (3)
        self.motor_pos_cmd = 0.0  # (4)
        self.motor_pos_fb = 0.0  # (5)
        self.pos_fb = 0.0  # (6)
        self.motor_offset = 0.0  # home offset: motor position of joint position 0
        self.vel_cmd = 0.0
        self._last_cmd: float | None = None  # pos_cmd of the previous period
        self.ferror = 0.0
        self.ferror_high_mark = 0.0
        self._is_forward = True
        # HAL-facing bits: inputs set by the caller, outputs read by it
        self.is_home_switch_on = False
        self.is_index_enabled = False  # out when homing sets it, cleared by the encoder driver
        self.is_on_pos_limit = False
        self.is_on_neg_limit = False
        self.is_unlocked = False  # locking indexer feedback
        self.is_unlock_requested = False  # locking indexer command
        self.is_homing = False
        self.is_homed = False

    @property
    def max_vel(self) -> float:
        return self.planner.max_vel

    @property
    def min_limit(self) -> float:
        return self.planner.min_limit

    @property
    def max_limit(self) -> float:
        return self.planner.max_limit

    def set_backlash(self, backlash: float) -> None:
        """[JOINT_n]BACKLASH: finite and >= 0 (ValueError saying why otherwise)."""
        backlash = check_finite("backlash", backlash)
        if backlash < 0:
            raise ValueError(f"backlash must be >= 0, got {backlash}")
        self.backlash = backlash

    def set_ferror(self, ferror: float, min_ferror: float) -> None:
        """FERROR is the limit at full speed, MIN_FERROR at rest (MOT-074)."""
        ferror, min_ferror = float(ferror), float(min_ferror)
        if not (ferror > 0 and min_ferror > 0):
            raise ValueError(f"FERROR and MIN_FERROR must be positive, got {ferror}, {min_ferror}")
        self.ferror_limit, self.min_ferror_limit = ferror, min_ferror

    @property
    def compensation(self) -> float:
        """Backlash plus leadscrew correction currently applied (filtered)."""
        return self._comp_filter.pos

    def update_feedback(self, motor_pos_fb: float) -> None:
        """MOT-007: pos_fb = motor_pos_fb - home offset - compensation."""
        self.motor_pos_fb = float(motor_pos_fb)
        self.pos_fb = self.motor_pos_fb - self.motor_offset - self.compensation
        # (a drive that follows its command exactly, a loopback, has no error)
        self.ferror = self.pos_cmd - self.pos_fb
        self.ferror_high_mark = max(self.ferror_high_mark, abs(self.ferror))

    def update_command(self, dt: float) -> None:
        """MOT-005: motor_pos_cmd = pos_cmd + compensation + home offset."""
        last = self.pos_cmd if self._last_cmd is None else self._last_cmd
        self.vel_cmd = (self.pos_cmd - last) / dt
        self._last_cmd = self.pos_cmd
        if self.vel_cmd > 0:
            self._is_forward = True
        elif self.vel_cmd < 0:
            self._is_forward = False
        target = 0.5 * self.backlash if self._is_forward else -0.5 * self.backlash
        if self.comp is not None:
            target += self.comp.correction(self.pos_cmd, self._is_forward)
        if target != self._comp_filter.target or self._comp_filter.is_active:
            self._comp_filter.move_to(target, self._comp_filter.max_vel)
            self._comp_filter.step(dt)
        self.motor_pos_cmd = self.pos_cmd + self.compensation + self.motor_offset

    def following_error_limit(self) -> float:
        """Allowed error at the current commanded speed: MIN_FERROR at rest growing to
        FERROR at max velocity, never below MIN_FERROR."""
        scaled = self.ferror_limit * abs(self.vel_cmd) / self.max_vel
        return max(scaled, self.min_ferror_limit)

    def is_following_error(self) -> bool:
        return abs(self.ferror) > self.following_error_limit()

    def hold_position(self) -> None:
        """Command the position the joint is at (enabling, MOT-030): no jump. Feedback that
        is not a number (a broken drive or encoder) is not a position: the command stays."""
        here = self.pos_fb if math.isfinite(self.pos_fb) else self.pos_cmd
        self.pos_cmd = self.coarse_pos = here
        self.planner.reset(here)
        self._last_cmd = None

    def set_position(self, pos: float) -> None:
        """Declare the current feedback position to be ``pos`` without moving the motor
        (homing): shifts the home offset and every internal position together."""
        shift = check_finite("position", pos) - self.pos_fb
        self.shift(shift)

    def shift(self, shift: float) -> None:
        self.pos_cmd += shift
        self.pos_fb += shift
        self.coarse_pos += shift
        self.planner.pos += shift
        self.planner.target += shift
        self.motor_offset -= shift
        if self._last_cmd is not None:
            self._last_cmd += shift

    def is_on_limit_switch(self) -> bool:
        return self.is_on_pos_limit or self.is_on_neg_limit
