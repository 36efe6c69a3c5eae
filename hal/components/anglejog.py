"""anglejog: jog two axes together along a line at an angle, from an MPG wheel.

While ``enable-in`` is false, ``angle-degrees-in``, ``scale-in`` and ``iscale-factor`` (10
to 100000) are taken; while true, ``counts-in`` moves a vector magnitude of counts * scale
along that angle, with a velocity planned within ``max-vel`` and ``max-accel`` (stopping
without overshoot). The magnitude is given to the two axes' wheel pins as
``coscounts``/``sincounts`` with ``current-scale-out`` as their jog scale, and
``accel-fraction-in`` split into ``cos-``/``sin-accel-fraction``. ``active`` is true while
moving.
"""

import math

from hal.api import RtComponent, funct, pin
from hal.components._cmath import to_s32, wrap_s32

MIN_ISCALE_FACTOR, MAX_ISCALE_FACTOR = 10, 100000


class AngleJog(RtComponent):
    enable_in = pin("bit in")
    counts_in = pin("s32 in")
    angle_degrees_in = pin("float in")
    iscale_factor = pin("s32 in", default=10000)
    scale_in = pin("float in")
    max_vel = pin("float in")
    max_accel = pin("float in")
    accel_fraction_in = pin("float in", default=1.0)
    enable_out = pin("bit out")
    current_scale = pin("float out")
    current_scale_out = pin("float out")
    coscounts = pin("s32 out")
    sincounts = pin("s32 out")
    cos_accel_fraction = pin("float out")
    sin_accel_fraction = pin("float out")
    active = pin("bit out")
    current_angle_degrees = pin("float out")
    current_mag = pin("float out")
    current_vel = pin("float out")

    def setup(self) -> None:
        self.is_first = True
        self.is_waiting_for_counts = False
        self.total_counts = 0
        self.was_enabled = False
        self.old_counts = 0
        self.factor = 0

    def _counts_of(self, magnitude: float, scale: float) -> int:
        return to_s32(magnitude / scale) if scale else to_s32(math.copysign(math.inf, magnitude))

    @funct()
    def update(self, period: int) -> None:
        dt = period * 1e-9
        if self.is_first:
            self.current_angle_degrees = self.angle_degrees_in
            self.current_scale = self.scale_in
            factor = self.iscale_factor
            self.current_scale_out = self.scale_in / factor if factor else math.inf
            self.factor = factor
            self.is_first = False
        is_enabled = self.enable_in
        counts = wrap_s32(self.factor * self.counts_in)
        if is_enabled and not self.was_enabled:  # enabling: count from here
            self.old_counts = counts
            self.is_waiting_for_counts = True
            self.total_counts = self._counts_of(self.current_mag, self.current_scale_out)
        delta = wrap_s32(counts - self.old_counts)
        self.was_enabled = is_enabled
        self.old_counts = counts
        self.enable_out = is_enabled
        if delta:
            self.is_waiting_for_counts = False
        if is_enabled:
            self.total_counts = wrap_s32(self.total_counts + delta)
        magnitude = self.current_mag
        self.active = False
        max_accel = self.max_accel
        max_dv = max_accel * dt
        tiny = max_accel * dt * dt * 0.001
        if is_enabled and not self.is_waiting_for_counts:
            error = self.total_counts * self.current_scale_out - magnitude
            if error > tiny:  # a velocity that stops at the target without overshoot
                wanted = -max_dv + math.sqrt(2.0 * max_accel * error + max_dv * max_dv)
                self.active = True
            elif error < -tiny:
                wanted = max_dv - math.sqrt(-2.0 * max_accel * error + max_dv * max_dv)
                self.active = True
            else:
                wanted = 0.0
        else:
            wanted = 0.0
            if not is_enabled:  # angle and scales change only while disabled
                self._take_settings()
            if self.is_waiting_for_counts:
                return
        max_vel = self.max_vel
        if wanted > max_vel:
            wanted = max_vel
        elif wanted < -max_vel:
            wanted = -max_vel
        velocity = self.current_vel
        if wanted > velocity + max_dv:
            velocity += max_dv
        elif wanted < velocity - max_dv:
            velocity -= max_dv
        else:
            velocity = wanted
        self.current_vel = velocity
        if velocity != 0.0:
            self.active = True
        magnitude += velocity * dt
        self.current_mag = magnitude
        angle = self.current_angle_degrees * math.pi / 180  # (as LinuxCNC rounds it)
        cosine, sine = math.cos(angle), math.sin(angle)
        scale = self.current_scale_out
        self.coscounts = to_s32(magnitude * cosine / scale) if scale else to_s32(math.nan)
        self.sincounts = to_s32(magnitude * sine / scale) if scale else to_s32(math.nan)
        fraction = self.accel_fraction_in
        self.cos_accel_fraction = fraction * cosine
        self.sin_accel_fraction = fraction * sine

    def _take_settings(self) -> None:
        is_new_factor = False
        wanted = self.iscale_factor
        if self.factor != wanted and MIN_ISCALE_FACTOR <= wanted <= MAX_ISCALE_FACTOR:
            self.factor = wanted
            is_new_factor = True
        self.current_angle_degrees = self.angle_degrees_in
        scale = self.scale_in
        if self.current_scale_out != scale or is_new_factor:
            self.current_scale = scale
            self.current_scale_out = scale / self.factor
            self.total_counts = self._counts_of(self.current_mag, self.current_scale_out)


COMPONENT = AngleJog
