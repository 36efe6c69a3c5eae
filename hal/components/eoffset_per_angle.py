"""eoffset_per_angle: an external offset (for ``axis.L.eoffset-*``) computed from a rotary
angle, e.g. to cut a polygon or a wave on a lathe-like XZC machine.

``kcounts`` = ``k`` (0 means 10000) times the offset, ``kreciprocal`` = 1/k for
``eoffset-scale``. The offset, from ``radius-ref``, ``rfraction``, ``fmult`` and
``angle`` - ``start-angle`` (degrees), is for ``fnum`` 0 an inside polygon of ``fmult``
sides, 1 an outside polygon, 2 a sinusoid, 3 a square wave (others: 0). It runs while
``enable-in`` is true (after a false-to-true change once the machine is on, ``is-on``);
when it goes false the offset is removed (``clear`` while stopping) until motion says it is
no longer ``active``. A polygon of fewer than 3 sides stops it until re-enabled.
"""

import math

from hal.api import RtComponent, funct, pin
from hal.components._cmath import to_f32, to_s32

OFF, READY, RUNNING, STOPPING, FINISH = range(5)


def _inside_polygon(angle: float, start: float, radius: float, fraction: float, sides: float):
    if sides <= 2:
        return None
    divisor = 360 / sides
    turned = angle + divisor / 2 - start
    return (1 + fraction) * radius / math.cos(
        (divisor / 2 - math.fmod(turned, divisor)) * math.pi / 180
    ) - radius


def _outside_polygon(angle: float, start: float, radius: float, fraction: float, sides: float):
    if sides <= 2:
        return None
    divisor = 360 / sides
    turned = angle + divisor / 2 - start
    return (1 + fraction) * radius * math.cos(math.pi / sides) / math.cos(
        (divisor / 2 - math.fmod(turned, divisor)) * math.pi / 180
    ) - radius


def _sinusoid(angle: float, start: float, radius: float, fraction: float, multiple: float):
    turned = multiple * (angle - start) + -90
    return (0.5 * fraction * radius) * (1 + math.sin(turned * math.pi / 180))


def _square(angle: float, start: float, radius: float, fraction: float, multiple: float):
    turned = multiple * (angle - start) + -90
    value = 1.0 if math.sin(turned * math.pi / 180) >= 0 else -1.0
    return (0.5 * fraction * radius) * (1 + value)


FUNCTIONS = {0: _inside_polygon, 1: _outside_polygon, 2: _sinusoid, 3: _square}


class EoffsetPerAngle(RtComponent):
    active = pin("bit in")
    is_on = pin("bit in")
    enable_in = pin("bit in")
    radius_ref = pin("float in", default=1.0)
    angle = pin("float in")
    start_angle = pin("float in")
    fnum = pin("s32 in")
    rfraction = pin("float in", default=0.1)
    fmult = pin("float in", default=6.0)
    k = pin("u32 in", default=10000)
    is_off = pin("bit out")
    enable_out = pin("bit out")
    clear = pin("bit out")
    kcounts = pin("s32 out")
    kreciprocal = pin("float out")
    eoffset_dbg = pin("float out")
    state_dbg = pin("u32 out")

    def setup(self) -> None:
        self.state = OFF
        self.runs = 0
        self.delay_start = 0
        self.is_error_stop = False

    @funct()
    def update(self, period: int) -> None:
        self.runs += 1
        self.state_dbg = self.state
        factor = self.k or 10000
        self.kreciprocal = to_f32(1.0 / to_f32(float(factor)))
        self.is_off = not self.is_on
        if not self.is_on:  # the offset is zero while the machine is off
            self.is_error_stop = False
            self.enable_out = False
            self.kcounts, self.eoffset_dbg = 0, 0.0
            self.state = OFF
            return
        state = self.state
        if state == OFF:  # wait for enable-in false, so that a rising edge starts
            if not self.enable_in:
                self.is_error_stop = False
                self.kcounts = 0
                self.state = READY
            return
        if state == READY:
            if self.enable_in:
                self.kcounts, self.eoffset_dbg = 0, 0.0
                self.enable_out = False
                self.delay_start = 0
                self.state = RUNNING
            return
        if state == RUNNING:
            if not self.enable_in:
                self.clear = True
                self.kcounts, self.eoffset_dbg = 0, 0.0
                self.state = STOPPING
                self.delay_start = self.runs
                return
            self.enable_out = True
        elif state == STOPPING:
            if not self.active:  # motion has removed the offset
                self.delay_start = self.runs
                self.state = FINISH
            return
        elif state == FINISH:
            if self.runs >= self.delay_start:
                self.enable_out = False
                self.state = OFF if self.is_error_stop else READY
            self.clear = False
            return
        function = FUNCTIONS.get(self.fnum, _inside_polygon)
        offset = function(self.angle, self.start_angle, self.radius_ref, self.rfraction, self.fmult)
        if offset is None:  # bad settings: stop until enabled again
            self.is_error_stop = True
            self.kcounts, self.eoffset_dbg = 0, 0.0
            self.state = STOPPING
            return
        counts = to_s32(factor * offset)
        self.kcounts = counts
        self.eoffset_dbg = counts * self.kreciprocal


COMPONENT = EoffsetPerAngle
