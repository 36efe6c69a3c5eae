"""encoder: software quadrature counter (``loadrt encoder num_chan=N`` or count=/names=).

``encoder.update-counters`` (no floating point, base thread) samples phase-A/B/Z each period.
In ``x4-mode`` every quadrature edge counts (forward is 00 -> A -> AB -> B -> 00), otherwise
only the 00 <-> A edge, once per cycle; a jump of both phases at once is a glitch and does
not count. In ``counter-mode`` each rising edge of phase-A counts up and phase-B is
ignored. A rising phase-Z, once ``index-enable`` has been seen by ``capture-position``,
zeroes the count and clears ``index-enable``; ``reset`` zeroes it too (``rawcounts``
never resets). ``latch-input`` edges (as ``latch-rising``/``latch-falling`` allow) store
``counts-latched``.

``encoder.capture-position`` (servo thread) publishes counts, position = counts /
position-scale, velocity from the time between counts (units/s, falling towards 0 while no
count comes, 0 after 1/``min-speed-estimate`` s), velocity-rpm and position-interpolated.
"""

from __future__ import annotations

from hal.api import RtComponent, module_funct, pin

# quadrature phases (A, B) -> place on the cycle 00 -> A -> AB -> B
_ORDER = {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}


class _Events:
    """What update-counters saw since the last capture-position (swapped out whole, so a
    capture in another thread never sees half an update)."""

    __slots__ = ("index_count", "latch_count", "raw_count", "timestamp")

    def __init__(self) -> None:
        self.raw_count: int | None = None  # raw count at the last count edge, if any
        self.timestamp = 0
        self.index_count: int | None = None
        self.latch_count: int | None = None


class Encoder(RtComponent):
    count_option = "num_chan"
    default_count = 3
    max_count = 8
    counter_mode = pin("bit io")
    counts = pin("s32 out")
    counts_latched = pin("s32 out")
    index_enable = pin("bit io")
    latch_falling = pin("bit in", default=1)
    latch_input = pin("bit in")
    latch_rising = pin("bit in", default=1)
    min_speed_estimate = pin("float in", default=1.0)
    missing_teeth = pin("s32 in")
    phase_A = pin("bit in")
    phase_B = pin("bit in")
    phase_Z = pin("bit in")
    position = pin("float out")
    position_interpolated = pin("float out")
    position_latched = pin("float out")
    position_scale = pin("float io", default=1.0)
    rawcounts = pin("s32 out")
    reset = pin("bit in")
    velocity = pin("float out")
    velocity_rpm = pin("float out")
    x4_mode = pin("bit io", default=1)

    def setup(self) -> None:
        # update-counters side
        self.place = 0  # last quadrature place (see _ORDER)
        self.old_a = False
        self.old_z = False
        self.old_latch = False
        self.is_index_armed = False
        self.timebase = 0  # ns of update-counters calls so far
        self.events = _Events()
        # capture-position side
        self.raw_count = 0
        self.index_count = 0
        self.latch_count = 0
        self.timestamp = 0
        self.counts_since_timeout = 0

    # ------------------------------------------------------------ base thread
    def count_edges(self, period: int) -> None:
        events = self.events
        a, b = self.phase_A, self.phase_B
        step = 0
        if self.counter_mode:
            step = 1 if a and not self.old_a else 0
        else:
            place = _ORDER[(1 if a else 0, 1 if b else 0)]
            move = (place - self.place) % 4  # 1: forward, 3: backward, 2: glitch
            if self.x4_mode:
                step = 1 if move == 1 else -1 if move == 3 else 0
            elif move == 1 and place == 1:
                step = 1
            elif move == 3 and place == 0:
                step = -1
            self.place = place
        self.old_a = a
        if step:
            self.rawcounts = self.rawcounts + step
            events.raw_count = self.rawcounts
            events.timestamp = self.timebase
        z = self.phase_Z
        if z and not self.old_z and self.is_index_armed:
            events.index_count = self.rawcounts
            self.is_index_armed = False
        self.old_z = z
        latch = self.latch_input
        if latch != self.old_latch and (self.latch_rising if latch else self.latch_falling):
            events.latch_count = self.rawcounts
        self.old_latch = latch
        self.timebase += period

    # ------------------------------------------------------------ servo thread
    def capture(self) -> None:
        events, self.events = self.events, _Events()
        if events.index_count is not None:
            self.index_count = events.index_count
            self.index_enable = False
        if events.latch_count is not None:
            self.latch_count = events.latch_count
        self.is_index_armed = self.index_enable
        scale = self.position_scale
        if -1e-20 < scale < 1e-20:
            self.position_scale = scale = 1.0
        per_count = 1.0 / scale
        if self.min_speed_estimate == 0:
            self.min_speed_estimate = 1.0
        if self.reset:
            self.raw_count = self.rawcounts
            self.index_count = self.raw_count
        if events.raw_count is not None:
            delta_time = events.timestamp - self.timestamp
            delta_counts = events.raw_count - self.raw_count
            self.raw_count = events.raw_count
            self.timestamp = events.timestamp
            if self.counts_since_timeout < 2:
                self.counts_since_timeout += 1
            elif delta_time:
                self.velocity = delta_counts * per_count / (delta_time * 1e-9)
        elif self.counts_since_timeout:
            since = self.timebase - self.timestamp
            if since and since < 1e9 / (self.min_speed_estimate * per_count):
                # no count yet: the speed is at most one count over the time waited
                bound = abs(per_count / (since * 1e-9))
                self.velocity = min(max(self.velocity, -bound), bound)
            else:
                self.counts_since_timeout = 0
                self.velocity = 0.0
        else:
            self.velocity = 0.0
        self.velocity_rpm = self.velocity * 60.0
        counts = self.raw_count - self.index_count
        self.counts = counts
        self.counts_latched = self.latch_count - self.index_count
        self.position = self.counts * per_count
        self.position_latched = self.counts_latched * per_count
        since = self.timebase - self.timestamp
        self.position_interpolated = self.position + self.velocity * since * 1e-9

    @module_funct("update-counters", has_fp=False)
    @classmethod
    def update_counters(cls, instances: list[Encoder], period: int) -> None:
        for inst in instances:
            inst.count_edges(period)

    @module_funct("capture-position")
    @classmethod
    def capture_position(cls, instances: list[Encoder], period: int) -> None:
        for inst in instances:
            inst.capture()


COMPONENT = Encoder
