"""carousel: orient a tool-changer carousel to the pocket asked for.

``loadrt carousel pockets=N[,N] encoding=gray|binary|bcd|single|index|edge|counts
num_sense=N dir=1|2 parity=0|1`` (one instance per ``pockets`` entry, at most 8; a value
not given for an instance keeps the previous instance's, as in LinuxCNC). Position
feedback comes from the ``sense-N`` pins (Gray code, binary or BCD with ``strobe`` and
``parity``; one sensor per pocket; an index plus a pocket pulse counted on one or both
edges; or encoder/stepgen ``counts``, ``scale`` counts per pocket). A rising ``enable``
starts a move to ``pocket-number`` (modulo the pockets): the shorter way round for a
bidirectional carousel (``dir=2``), forward otherwise, with ``motor-fwd``/``motor-rev``
and ``motor-vel`` (``fwd-dc``, ``rev-dc``; ``hold-dc`` at rest) or ``counts-target``.
Once there, an optional reverse pulse (``rev-pulse`` s) locks a ratchet changer, or a
pause (``decel-time``) and slow alignment (``align-dc``) find the pocket edge; then
``ready``. Index, edge and counts modes home first (forward to the index). ``jog-fwd``
and ``jog-rev`` move one pocket. Parameters ``state``, ``homing``, ``timer``, ``target``,
``motor-dir`` and ``debounce`` (periods the position must stay) show and tune it.
"""

from __future__ import annotations

import math
from typing import Any

from hal.api import RtComponent, funct, param, pin
from hal.components._cmath import c_div, c_mod, to_f32, to_s32
from hal.core import HalError

MAX_INSTANCES = 8
ENCODINGS = {
    "gray": "G",
    "binary": "B",
    "bcd": "D",
    "single": "S",
    "index": "I",
    "edge": "E",
    "counts": "C",
}
HOMING_CODES = ("I", "E", "C")


class _Shared:
    """What LinuxCNC's carousel keeps once for all instances."""

    def __init__(self) -> None:
        self.debounce_left = 0
        self.is_error_said = False


def _numbers(module: str, args: dict[str, str], key: str, default: int) -> list[int]:
    """A module array of ints, unset entries ``default``."""
    try:
        given = [int(word, 0) for word in args.get(key, "").split(",") if word]
    except ValueError:
        raise HalError(f"{module}: {key} must be numbers") from None
    return (given + [default] * MAX_INSTANCES)[:MAX_INSTANCES]


class Carousel(RtComponent):
    pocket_number = pin("s32 in")
    enable = pin("bit in")
    active = pin("bit out")
    ready = pin("bit out")
    strobe = pin("bit in", default=1)
    parity_ = pin("bit in")
    sense = pin("bit in", "sense-{}", count="sense")
    rev_pulse = pin("float in")
    fwd_dc = pin("float in")
    rev_dc = pin("float in")
    hold_dc = pin("float in")
    align_dc = pin("float in")
    decel_time = pin("float in")
    counts = pin("s32 in")
    scale = pin("s32 in", default=100)
    width = pin("s32 in", default=10)
    home_offset = pin("s32 in")
    index_enable = pin("bit io")
    jog_fwd = pin("bit in")
    jog_rev = pin("bit in")
    motor_fwd = pin("bit out")
    motor_rev = pin("bit out")
    parity_error = pin("bit out")
    current_position = pin("s32 out")
    motor_vel = pin("float out")
    homed = pin("bit out")
    unhome = pin("bit in")
    counts_target = pin("float out")
    state = param("s32 ro")
    homing = param("bit ro")
    timer = param("float ro")
    motor_dir = param("s32 ro")
    counts_offset = param("s32 ro")
    debounce = param("u32 rw")
    target = param("s32 ro")
    base_counts = param("s32 ro")

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        known = {"pockets", "encoding", "dir", "num_sense", "parity"}
        if set(args) - known:
            raise HalError(f"{module}: unknown argument '{sorted(set(args) - known)[0]}'")
        pockets = _numbers(module, args, "pockets", 0)
        if "pockets" not in args:
            pockets[0] = -1
        count = next((i for i, p in enumerate(pockets) if p == 0), MAX_INSTANCES) or 1
        encodings = [word for word in args.get("encoding", "").split(",")]
        directions = _numbers(module, args, "dir", 0)
        senses = _numbers(module, args, "num_sense", 0)
        parities = _numbers(module, args, "parity", 0)
        if "parity" not in args:
            parities[0] = -1
        shared = _Shared()
        # each instance starts from the previous one's settings (LinuxCNC's defaults)
        setting = {"pockets": 8, "code": "G", "dir": 2, "sense": 4, "parity": 0}
        wanted = []
        for i in range(count):
            if pockets[i] > 0:
                setting["pockets"] = pockets[i]
            word = encodings[i] if i < len(encodings) else ""
            for name, code in ENCODINGS.items():
                if word.startswith(name):
                    setting["code"] = code
            if directions[i] > 0:
                setting["dir"] = 2 if directions[i] > 1 else 1
            if parities[i] != -1:
                setting["parity"] = parities[i]
            if setting["code"] == "I":
                setting["sense"] = 2
            elif senses[i] > 0:
                setting["sense"] = senses[i]
            sense = setting["sense"]
            if setting["code"] == "S" and sense < setting["pockets"]:
                sense = setting["pockets"]
            if sense > 32:
                raise HalError(f"Requested size {sense} exceeds max size 32")
            wanted.append((f"carousel.{i}", {**setting, "sense": sense, "shared": shared}))
        return wanted

    def setup(
        self,
        pockets: int = 8,
        code: str = "G",
        dir: int = 2,
        sense: int = 4,
        parity: int = 0,
        shared: _Shared | None = None,
    ) -> None:
        self.pockets, self.code, self.direction = pockets, code, dir
        self.sense_count, self.parity_kind = sense, parity
        self.shared = shared or _Shared()
        self.old_index = False
        self.old_unhome = False

    def _sensor(self, index: int) -> int:
        return int(self.sense[index]) if 0 <= index < self.sense_count else 0

    def _feedback(self) -> tuple[int, int, bool]:
        """(position the sensors show, their parity, the alignment sensor)."""
        code, count = self.code, self.sense_count
        position, parity, align = 0, 0, False
        if code in ("G", "B"):
            align = self.strobe
            for i in range(count):
                bit = self._sensor(i)
                position += bit << i
                parity ^= bit
            if code == "G":
                mask = position >> 1
                while mask:
                    position ^= mask
                    mask >>= 1
                if position == 0:
                    position = self.pockets  # all zeros is the last pocket, not pocket 0
        elif code == "D":
            align = self.strobe
            weight, i = 1, 0
            while i < count:
                digit, end = 0, i + 4
                while i < end and i < count:
                    bit = self._sensor(i)
                    digit += bit << (i % 4)
                    parity ^= bit
                    i += 1
                position += digit * weight
                weight *= 10
        elif code == "S":
            i = count - 1
            while i > 0 and not self._sensor(i):
                i -= 1
            if self._sensor(i):
                position = i + 1
            align = bool(self._sensor(self.current_position - 1))
        elif code in ("I", "E"):
            position = self.current_position
            index = bool(self._sensor(1))
            if code == "I":
                align = index
                is_counting = self.homed and self.state in (2, 20)
                is_edge = index and not self.old_index
            else:
                align = True  # (not supported: the pin just changes)
                is_counting = self.homed
                is_edge = index != self.old_index
            if is_counting:
                if is_edge:
                    position = self._step(position)
                self.old_index = index
        elif code == "C":
            position = self.current_position
            if self.homed:
                half, scale = c_div(self.width, 2), self.scale
                moved = self.counts - self.base_counts
                nearest = to_f32(to_f32(float(moved)) + half)  # (C computes in float here)
                pockets_moved = to_f32(nearest / scale) if scale else math.nan
                pocket = to_s32(
                    math.floor(pockets_moved) if math.isfinite(pockets_moved) else pockets_moved
                )
                if pocket * scale - half <= moved <= pocket * scale + half:
                    position = 1 + c_mod(pocket, self.pockets)
                    if position < 1:
                        position += self.pockets
                remainder = c_mod(moved, scale) if scale else 0
                align = -2 <= remainder <= 2
        return position, parity, align

    def _step(self, position: int) -> int:
        """The next pocket in the direction the motor turns (index and edge modes)."""
        if self.motor_fwd:
            position += 1
            if position > self.pockets:
                position -= self.pockets
        if self.motor_rev:
            position -= 1
            if position < 1:
                position += self.pockets
        return position

    def _run(self, forward: bool) -> None:
        self.motor_fwd, self.motor_rev = forward, not forward
        self.motor_vel = self.fwd_dc if forward else self.rev_dc
        self.motor_dir = 1 if forward else -1

    def _stop(self) -> None:
        self.motor_fwd = self.motor_rev = False
        self.motor_vel = self.hold_dc
        self.active = False

    @funct()
    def update(self, period: int) -> None:
        position, parity, self.align = self._feedback()
        if self.strobe:
            self.current_position = position
            self.parity_error = parity != (self.parity_kind ^ self.parity_)
        pockets = self.pockets
        self.pocket = min(max(c_mod(self.pocket_number - 1, pockets) + 1, 1), pockets)
        unhome = self.unhome
        if unhome and not self.old_unhome:
            self.homed = False
        self.old_unhome = unhome
        self.dt = period * 1e-9
        state = self.state
        while True:  # a state's handler returns True to go on to the next, as C falls through
            handler = self._HANDLERS.get(state)
            if handler is None or not handler(self):
                return
            state = self.state

    def _at_rest(self) -> bool:
        self.motor_dir = 0
        is_jog = self.jog_fwd or (self.jog_rev and self.direction == 2)
        if is_jog:
            if self.code in HOMING_CODES and not self.homed:
                self.state = 10
                return False
            jog = int(self.jog_fwd) - int(self.jog_rev)
            here = self.current_position
            target = here + jog
            self.counts_target = self.counts_target + self.scale * (target - here)
            if target > self.pockets:
                target = 1
            if target < 1:
                target = self.pockets
            self.target = target
            if self.jog_fwd:
                self._run(forward=True)
            if self.jog_rev:
                self._run(forward=False)
            self.active = True
            self.state = 20
            return False
        self.motor_vel = self.hold_dc
        if not self.enable:
            return False
        self.active = True
        if self.code in HOMING_CODES and not self.homed:
            self.state = 10
            return False
        self.state = 1
        self.ready = False
        return True

    def _choose_direction(self) -> bool:
        pocket, here, pockets, scale = self.pocket, self.current_position, self.pockets, self.scale
        if not 1 <= pocket <= pockets:
            self.state = 0
            return False
        target = self.counts_target
        if self.direction == 2:
            half = c_div(pockets, 2)
            if here < pocket:
                is_forward = not pocket - here > half
                turns = pocket - here - (0 if is_forward else pockets)
            else:
                is_forward = here - pocket > half
                turns = pocket - here + (pockets if is_forward else 0)
            self._run(forward=is_forward)
            self.counts_target = target + turns * scale
        else:
            target += (pocket - here) * scale
            if target < self.counts:
                target += scale * pockets
            self.counts_target = target
            self._run(forward=True)
        self.state = 2
        return True

    def _moving(self) -> bool:
        shared = self.shared
        if self.current_position != self.pocket and self.enable:
            shared.debounce_left = self.debounce
            return False
        shared.debounce_left -= 1
        if shared.debounce_left + 1 > 0:
            return False
        if self.rev_pulse > 0:
            self.motor_fwd, self.motor_rev = False, True
            self.motor_vel = self.rev_dc
            self.timer = self.rev_pulse
            self.state = 3
        elif self.decel_time > 0:  # stop, then align
            self.motor_vel = 0.0
            self.timer = self.decel_time
            self.state = 5
        else:
            self._stop()
            if self.enable and self.current_position == self.pocket:
                self.ready = True
            self.state = 9
        return False

    def _reverse_pulse(self) -> bool:
        self.timer = self.timer - self.dt
        if self.timer > 0:
            return False
        self.state = 9
        self._stop()
        if self.enable:
            self.ready = True
        return False

    def _settling(self) -> bool:
        self.timer = self.timer - self.dt
        if self.timer > 0:
            return False
        if self.align_dc == 0:
            self.state = 8
            return False
        self.motor_vel = -self.align_dc
        self.state = 6 if self.motor_dir == 1 else 7
        return False

    def _back_to_marker(self) -> bool:
        if self.align:
            self.state = 7
        return False

    def _off_marker(self) -> bool:
        if not self.align:
            self.motor_vel = self.align_dc
            self.state = 8
        return False

    def _onto_marker(self) -> bool:
        if not self.align:
            return False
        self._stop()
        if self.enable and self.current_position == self.pocket:
            self.ready = True
        self.state = 9
        return False

    def _done(self) -> bool:
        if not self.ready and not self.shared.is_error_said:
            self.shared.is_error_said = True  # (LinuxCNC logs: failed the final alignment)
        if self.enable:
            return False
        self.shared.is_error_said = False
        self.state = 0
        return False

    def _start_homing(self) -> bool:
        self.homed = False
        self.homing = True
        self._run(forward=True)
        self.index_enable = True
        self.counts_target = self.counts_target + self.scale * self.pockets
        self.old_index = True  # the home sensor must go from 0 to 1
        self.state = 11
        return True

    def _homing(self) -> bool:
        index = self._sensor(0) if self.code == "C" else self._sensor(0) and self._sensor(1)
        if not self.index_enable or (not self.old_index and index):
            self.current_position = 1
            self.homed = True
            self.homing = False
            self.active = False
            self.motor_fwd = self.motor_rev = False
            self.motor_vel = 0.0
            self.base_counts = self.counts - self.home_offset
            self.counts_target = self.base_counts
            if self.align_dc == 0:
                self.state = 0
            else:
                self.timer = self.decel_time
                self.state = 5
        self.old_index = bool(index)
        return False

    def _jogging(self) -> bool:
        shared = self.shared
        if self.current_position != self.target:
            shared.debounce_left = self.debounce
            return False
        shared.debounce_left -= 1
        if shared.debounce_left + 1 > 0:
            return False
        if self.align_dc != 0 and not self.align:
            return False
        self._stop()
        if self.jog_fwd or self.jog_rev:
            return False  # the button must be released before the next jog
        if self.align_dc != 0:
            self.motor_vel = -self.align_dc
            self.timer = self.decel_time
            self.state = 5
        else:
            self.state = 0
        return False

    _HANDLERS = {
        0: _at_rest,
        1: _choose_direction,
        2: _moving,
        3: _reverse_pulse,
        5: _settling,
        6: _back_to_marker,
        7: _off_marker,
        8: _onto_marker,
        9: _done,
        10: _start_homing,
        11: _homing,
        20: _jogging,
    }


COMPONENT = Carousel
