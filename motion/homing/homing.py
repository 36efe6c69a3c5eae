"""The default homing module (MOT-043/044): a state machine per joint, sequenced.

Configuration per joint comes from LinuxCNC's ``[JOINT_n]`` keys (``HomingConfig``). The
joint's inputs are plain attributes of its ``motion.joint.Joint`` record, set by the
caller from the HAL pins: ``is_home_switch_on`` (``joint.N.home-sw-in``),
``is_index_enabled`` (``joint.N.index-enable``, cleared by the encoder driver on the index
pulse), ``is_on_pos_limit``/``is_on_neg_limit`` (``pos-lim-sw-in``/``neg-lim-sw-in``),
``is_unlocked`` (``joint.N.is-unlocked``). Homing drives the joint's free planner
(``joint.planner``) and sets ``is_homing``, ``is_homed``, ``is_index_enabled`` and
``is_unlock_requested`` (``joint.N.unlock``).

A joint's sequence, in LinuxCNC's terms:

- both HOME_SEARCH_VEL and HOME_LATCH_VEL 0: the current position becomes HOME_OFFSET;
- HOME_SEARCH_VEL 0, HOME_LATCH_VEL and HOME_USE_INDEX set: move at the latch velocity
  to the next index pulse;
- otherwise: back off the switch if it is already closed, search for it at
  HOME_SEARCH_VEL, then latch: with the latch velocity of the same sign, back off and
  approach again slowly until the switch closes (rising edge); of the opposite sign, move
  slowly off the switch until it opens (falling edge); then with HOME_USE_INDEX continue
  to the index pulse. The latch point becomes HOME_OFFSET;
- HOME_ABSOLUTE_ENCODER 1 or 2: the encoder position plus HOME_OFFSET is the position
  at once (2: without the final move);
- finally move to HOME at HOME_FINAL_VEL (or the joint's max velocity when not positive),
  and with LOCKING_INDEXER lock the joint again.

Moves start after the joint has stood still for ``SETTLE_TIME``. A search that ends
without finding its edge, a limit switch (unless HOME_IGNORE_LIMITS) or a closed shared
switch at the start (HOME_IS_SHARED) abort homing with an error. Home-all runs the
sequences 0, 1, 2, ... in order; joints sharing a sequence number home together, and a
negative number synchronises their final moves (gantries): homing one such joint homes
its whole group.

The motion component calls ``step(dt)`` every servo period after updating the joints'
feedback and before stepping their free planners.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from motion.joint import Joint

SETTLE_TIME = 0.1  # s a joint stands still before each search move (LinuxCNC's HOME_DELAY)


class HomeState(enum.Enum):
    IDLE = "idle"
    UNLOCK_WAIT = "unlock_wait"
    INITIAL_BACKOFF = "initial_backoff"
    INITIAL_SEARCH = "initial_search"
    FINAL_BACKOFF = "final_backoff"
    RISE_SEARCH = "rise_search"
    FALL_SEARCH = "fall_search"
    INDEX_SEARCH = "index_search"
    FINAL_MOVE = "final_move"
    LOCK_WAIT = "lock_wait"


@dataclass(slots=True)
class HomingConfig:
    """One joint's homing keys (``[JOINT_n]``); see the module docstring."""

    home: float = 0.0
    home_offset: float = 0.0
    search_vel: float = 0.0
    latch_vel: float = 0.0
    final_vel: float = -1.0
    use_index: bool = False
    ignore_limits: bool = False
    is_shared: bool = False
    sequence: int | None = None  # None: not part of home-all
    absolute_encoder: int = 0
    volatile_home: bool = False
    locking_indexer: bool = False

    def __post_init__(self) -> None:
        for name in ("home", "home_offset", "search_vel", "latch_vel", "final_vel"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name.upper()} must be a finite number")
        if self.absolute_encoder not in (0, 1, 2):
            raise ValueError(
                f"HOME_ABSOLUTE_ENCODER must be 0, 1 or 2, not {self.absolute_encoder}"
            )
        if self.search_vel != 0 and self.latch_vel == 0:
            raise ValueError("HOME_SEARCH_VEL needs a non-zero HOME_LATCH_VEL")
        if self.search_vel == 0 and self.latch_vel != 0 and not self.use_index:
            raise ValueError("HOME_LATCH_VEL without HOME_SEARCH_VEL needs HOME_USE_INDEX")

    @classmethod
    def from_ini(cls, ini: object, joint: int) -> HomingConfig:
        """Read ``[JOINT_<joint>]`` of a ``cnc.ini.IniFile``."""
        section = f"JOINT_{joint}"

        def number(key: str, default: float) -> float:
            return ini.get_float(section, key, default)  # type: ignore[attr-defined]

        def flag(key: str) -> bool:
            return ini.get_bool(section, key, False)  # type: ignore[attr-defined]

        sequence_text = ini.find(section, "HOME_SEQUENCE", None)  # type: ignore[attr-defined]
        return cls(
            home=number("HOME", 0.0),
            home_offset=number("HOME_OFFSET", 0.0),
            search_vel=number("HOME_SEARCH_VEL", 0.0),
            latch_vel=number("HOME_LATCH_VEL", 0.0),
            final_vel=number("HOME_FINAL_VEL", -1.0),
            use_index=flag("HOME_USE_INDEX"),
            ignore_limits=flag("HOME_IGNORE_LIMITS"),
            is_shared=flag("HOME_IS_SHARED"),
            sequence=None if sequence_text is None else int(sequence_text),
            absolute_encoder=int(number("HOME_ABSOLUTE_ENCODER", 0)),
            volatile_home=flag("VOLATILE_HOME"),
            locking_indexer=flag("LOCKING_INDEXER"),
        )


class HomingError(RuntimeError):
    """A homing command that cannot start."""


class _JointHoming:
    """The state machine of one joint."""

    def __init__(self, number: int, joint: Joint, config: HomingConfig) -> None:
        self.number = number
        self.joint = joint
        self.config = config
        self.state = HomeState.IDLE
        self.settle = 0.0  # time the joint has stood still
        self.is_move_started = False  # the move of the current state is running
        self.is_at_final_start = False  # waiting for the group's synchronised final move

    @property
    def is_synchronised(self) -> bool:
        return self.config.sequence is not None and self.config.sequence < 0

    def start(self) -> str | None:
        """Begin homing; returns an error message or None."""
        joint, cfg = self.joint, self.config
        if cfg.is_shared and joint.is_home_switch_on and cfg.absolute_encoder == 0:
            return f"joint {self.number}: cannot home while the shared home switch is closed"
        joint.planner.stop()  # a jog still running decelerates; moves wait until it stood
        joint.is_homing = True
        joint.is_homed = False
        self.settle = 0.0
        self.is_move_started = False
        self.is_at_final_start = False
        if cfg.absolute_encoder:
            # the encoder knows the position: feedback plus HOME_OFFSET
            joint.set_position(joint.motor_pos_fb - joint.compensation + cfg.home_offset)
            self._after_latch_in_place()
            return None
        if cfg.locking_indexer:
            joint.is_unlock_requested = True
        elif cfg.search_vel == 0 and cfg.latch_vel == 0:
            # homing in place: the position is known at once
            joint.set_position(cfg.home_offset)
            self._after_latch_in_place()
            return None
        self.state = HomeState.UNLOCK_WAIT
        return None

    def stop(self) -> None:
        joint = self.joint
        joint.planner.stop()
        joint.is_homing = False
        joint.is_index_enabled = False
        self.state = HomeState.IDLE

    # ------------------------------------------------------------------ helpers
    def _settled(self, dt: float) -> bool:
        """True once the joint has stood still for SETTLE_TIME."""
        if self.joint.planner.is_active:
            self.settle = 0.0
            return False
        self.settle += dt
        return self.settle >= SETTLE_TIME - 1e-12

    def _search_move(self, vel: float) -> None:
        """A long move at ``vel`` (signed) that only a switch or index ends; homing moves
        ignore soft limits since the position is not known yet."""
        joint = self.joint
        span = joint.max_limit - joint.min_limit
        span = span if math.isfinite(span) else 1e6
        joint.planner.move_to(joint.pos_cmd + math.copysign(2.0 * span, vel), abs(vel))
        self.is_move_started = True

    def _enter(self, state: HomeState) -> None:
        self.state = state
        self.settle = 0.0
        self.is_move_started = False

    def _after_latch(self) -> None:
        """The joint's position is known: the final move comes next."""
        cfg = self.config
        if cfg.absolute_encoder == 2:
            self._finish()
        else:
            self._enter(HomeState.FINAL_MOVE)

    def _after_latch_in_place(self) -> None:
        """The position is known without a move (absolute encoder, homing in place): a
        joint already at HOME is homed now, as there is no final move to make
        (LinuxCNC's zero-length final move takes two periods, so a UI's next home
        command, sent as soon as this one is answered, finds it done there too)."""
        if math.isclose(self.joint.pos_cmd, self.config.home, rel_tol=0.0, abs_tol=1e-9):
            self._finish()
        else:
            self._after_latch()

    def _finish(self) -> None:
        joint = self.joint
        joint.is_homing = False
        joint.is_homed = True
        self.state = HomeState.IDLE

    def _moving_check(self) -> str | None:
        """Errors while a homing move runs: a limit switch, or the move ran out."""
        joint = self.joint
        if joint.is_on_limit_switch() and not self.config.ignore_limits:
            return f"joint {self.number}: hit a limit switch while homing ({self.state.value})"
        if self.is_move_started and not joint.planner.is_active:
            return f"joint {self.number}: homing move ended without finding its edge"
        return None

    # ------------------------------------------------------------------ servo period
    def step(self, dt: float, is_group_ready: bool) -> str | None:
        """One period; returns an error message to abort homing, or None."""
        joint, cfg = self.joint, self.config
        state = self.state
        if state == HomeState.UNLOCK_WAIT:
            if cfg.locking_indexer and not joint.is_unlocked:
                return None
            if cfg.search_vel == 0:
                if cfg.latch_vel == 0:  # home at the current position
                    joint.set_position(cfg.home_offset)
                    self._after_latch()
                else:
                    self._enter(HomeState.INDEX_SEARCH)
            else:
                self._enter(HomeState.INITIAL_SEARCH)
            return None
        if state == HomeState.INITIAL_BACKOFF:
            if not self.is_move_started:
                if self._settled(dt):
                    self._search_move(-cfg.search_vel)
                return None
            if not joint.is_home_switch_on:
                joint.planner.stop()
                self._enter(HomeState.INITIAL_SEARCH)
                return None
            return self._moving_check()
        if state == HomeState.INITIAL_SEARCH:
            if not self.is_move_started:
                if self._settled(dt):
                    if joint.is_home_switch_on:
                        self._enter(HomeState.INITIAL_BACKOFF)
                    else:
                        self._search_move(cfg.search_vel)
                return None
            if joint.is_home_switch_on:
                joint.planner.stop()
                # roughly home: the position is now about right (screw comp, limits)
                joint.set_position(cfg.home_offset)
                same_sign = cfg.search_vel * cfg.latch_vel > 0
                self._enter(HomeState.FINAL_BACKOFF if same_sign else HomeState.FALL_SEARCH)
                return None
            return self._moving_check()
        if state == HomeState.FINAL_BACKOFF:
            if not self.is_move_started:
                if self._settled(dt):
                    if not joint.is_home_switch_on:
                        return f"joint {self.number}: home switch opened before the latch move"
                    self._search_move(-cfg.search_vel)
                return None
            if not joint.is_home_switch_on:
                joint.planner.stop()
                self._enter(HomeState.RISE_SEARCH)
                return None
            return self._moving_check()
        if state in (HomeState.RISE_SEARCH, HomeState.FALL_SEARCH):
            is_rising = state == HomeState.RISE_SEARCH
            if not self.is_move_started:
                if self._settled(dt):
                    if joint.is_home_switch_on == is_rising:
                        return f"joint {self.number}: home switch in the wrong state to latch"
                    self._search_move(cfg.latch_vel)
                return None
            if joint.is_home_switch_on == is_rising:  # the latch edge
                if cfg.use_index:
                    joint.is_index_enabled = True
                    self.state = HomeState.INDEX_SEARCH  # keep moving at the latch speed
                    return None
                joint.planner.stop()
                joint.set_position(cfg.home_offset)
                self._after_latch()
                return None
            return self._moving_check()
        if state == HomeState.INDEX_SEARCH:
            if not self.is_move_started:  # index-only homing
                if self._settled(dt):
                    joint.set_position(cfg.home_offset)
                    joint.is_index_enabled = True
                    self._search_move(cfg.latch_vel)
                return None
            if not joint.is_index_enabled:  # the encoder reset its count at the index
                joint.planner.stop()
                joint.motor_offset = -cfg.home_offset
                joint.update_feedback(joint.motor_pos_fb)
                joint.pos_cmd = joint.coarse_pos = joint.pos_fb
                joint.planner.pos = joint.planner.target = joint.pos_fb
                self._after_latch()
                return None
            return self._moving_check()
        if state == HomeState.FINAL_MOVE:
            if not self.is_move_started:
                # LinuxCNC 2.9 starts the final move as soon as the joint stands, without
                # the pause of the other moves: homing in place takes a few periods
                if joint.planner.is_active:
                    return None
                self.is_at_final_start = True
                if self.is_synchronised and not is_group_ready:
                    return None
                self.is_at_final_start = False
                vel = cfg.final_vel if cfg.final_vel > 0 else joint.max_vel
                joint.planner.move_to(cfg.home, min(vel, joint.max_vel))
                self.is_move_started = True
                return None
            if not joint.planner.is_active:
                if cfg.locking_indexer:
                    joint.is_unlock_requested = False
                self._enter(HomeState.LOCK_WAIT)
                return self.step(dt, is_group_ready)
            if joint.is_on_limit_switch() and not cfg.ignore_limits:
                return f"joint {self.number}: hit a limit switch during the final home move"
            return None
        if state == HomeState.LOCK_WAIT:
            if cfg.locking_indexer and joint.is_unlocked:
                return None
            self._finish()
        return None


class Homing:
    """Homing of all joints; the default ``homemod`` (ARCH-007)."""

    def __init__(self, joints: Sequence[Joint], configs: Sequence[HomingConfig]) -> None:
        if len(joints) != len(configs):
            raise ValueError(f"{len(joints)} joints but {len(configs)} homing configurations")
        self.joints = list(joints)
        # a negative sequence number makes every joint of that number synchronised,
        # whatever sign the others were given (as LinuxCNC does)
        synchronised = {-c.sequence for c in configs if c.sequence is not None and c.sequence < 0}
        configs = [
            replace(c, sequence=-c.sequence) if c.sequence in synchronised else c for c in configs
        ]
        self._machines = [
            _JointHoming(n, j, c) for n, (j, c) in enumerate(zip(joints, configs, strict=True))
        ]
        self._sequence: list[int] = []  # sequence numbers still to run in home-all
        self._group: set[int] = set()  # joints homing now
        self.error: str | None = None

    # ------------------------------------------------------------------ status
    @property
    def is_homing(self) -> bool:
        return bool(self._group) or bool(self._sequence)

    def is_homed(self, joint: int) -> bool:
        return self.joints[joint].is_homed

    @property
    def is_all_homed(self) -> bool:
        return all(j.is_homed for j in self.joints)

    def state(self, joint: int) -> HomeState:
        return self._machines[joint].state

    def take_error(self) -> str | None:
        error, self.error = self.error, None
        return error

    # ------------------------------------------------------------------ commands
    def home_joint(self, joint: int) -> None:
        """Home one joint (MOT-043); a joint of a synchronised (negative) sequence homes
        its whole group."""
        if not 0 <= joint < len(self.joints):
            raise HomingError(f"no joint {joint}")
        if self.is_homing:
            raise HomingError("homing is already in progress")
        machine = self._machines[joint]
        group = [joint]
        if machine.is_synchronised:
            group = [
                m.number for m in self._machines if m.config.sequence == machine.config.sequence
            ]
        self._start(group)

    def home_all(self) -> None:
        """Home every joint that has a HOME_SEQUENCE, sequence by sequence."""
        if self.is_homing:
            raise HomingError("homing is already in progress")
        numbers = sorted(
            {abs(m.config.sequence) for m in self._machines if m.config.sequence is not None}
        )
        if not numbers:
            raise HomingError("no joint has a HOME_SEQUENCE: home the joints one by one")
        self._sequence = numbers
        self._start_next_sequence()

    def unhome(self, joint: int) -> None:
        """UNHOME: ``joint`` >= 0 one joint, -1 every joint, -2 the VOLATILE_HOME joints."""
        if self.is_homing:
            raise HomingError("cannot unhome while homing")
        if joint == -1:
            targets = range(len(self.joints))
        elif joint == -2:
            targets = [m.number for m in self._machines if m.config.volatile_home]
        elif 0 <= joint < len(self.joints):
            targets = [joint]
        else:
            raise HomingError(f"no joint {joint}")
        for n in targets:
            self.joints[n].is_homed = False

    def abort(self) -> None:
        """Stop homing; the joints being homed are left unhomed."""
        for n in self._group:
            self._machines[n].stop()
            self.joints[n].is_homed = False
        self._group.clear()
        self._sequence.clear()

    def _start(self, group: list[int]) -> None:
        self._group = set(group)
        for n in group:
            error = self._machines[n].start()
            if error is not None:
                self._fail(error)
                return
        if all(self._machines[n].state == HomeState.IDLE for n in group):
            # every joint homed in place at once: on to the next sequence, if any
            self._group.clear()
            if self._sequence:
                self._start_next_sequence()

    def _start_next_sequence(self) -> None:
        number = self._sequence.pop(0)
        group = [
            m.number
            for m in self._machines
            if m.config.sequence is not None and abs(m.config.sequence) == number
        ]
        self._start(group)

    def _fail(self, error: str) -> None:
        self.error = error
        self.abort()

    # ------------------------------------------------------------------ servo period
    def step(self, dt: float) -> None:
        if not self._group:
            return
        machines = self._machines
        # a synchronised group starts its final moves together, once all are ready
        waiting: dict[int | None, bool] = {}
        for n in self._group:
            seq = machines[n].config.sequence
            waiting[seq] = waiting.get(seq, True) and machines[n].is_at_final_start
        for n in sorted(self._group):
            machine = machines[n]
            if machine.state == HomeState.IDLE:
                continue
            error = machine.step(dt, waiting[machine.config.sequence])
            if error is not None:
                self._fail(error)
                return
        if all(machines[n].state == HomeState.IDLE for n in self._group):
            self._group.clear()
            if self._sequence:
                self._start_next_sequence()
