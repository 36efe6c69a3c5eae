"""siggen: sine, cosine, triangle, sawtooth and square waves plus a clock bit.

``loadrt siggen [num_chan=N | count=N | names=...]``. One cycle lasts 1/``frequency``
seconds (at most half the thread rate); outputs swing from -amplitude to +amplitude around
``offset``. Square (and ``clock``) is high in the second half of each cycle, while the
triangle and cosine ramp up and the sine is negative; ``reset`` holds everything at the
middle of a cycle (sine and sawtooth 0, square, cosine and triangle at -amplitude).
"""

import math

from hal.api import RtComponent, funct, pin

# LinuxCNC's siggen uses pi rounded to 8 digits; using the same value keeps recorded
# waveforms identical (sine is -4.6e-8, not 0, at half a cycle)
LINUXCNC_PI = 3.1415927


class Siggen(RtComponent):
    count_option = "num_chan"
    max_count = 16
    square = pin("float out")
    sawtooth = pin("float out")
    triangle = pin("float out")
    sine = pin("float out")
    cosine = pin("float out")
    clock = pin("bit out")
    frequency = pin("float in", default=1.0)
    amplitude = pin("float in", default=1.0)
    offset = pin("float in")
    reset = pin("bit in")

    def setup(self) -> None:
        self.phase = 0.0  # fraction of the current cycle, 0 <= phase < 1

    @funct("update")
    def update(self, period: int) -> None:
        dt = period * 1e-9
        step = self.frequency * dt
        if step > 0.5:  # keep below the Nyquist limit, and show it on the pin
            self.frequency = 0.5 / dt
            step = 0.5
        # reset parks the phase at mid-cycle: sine 0, cosine/square/triangle at -amplitude
        phase = 0.5 if self.reset else self.phase + step
        if phase >= 1.0:
            phase -= 1.0
        self.phase = phase
        amp, offset = self.amplitude, self.offset
        is_high = phase > 0.5
        self.clock = is_high
        square = 1.0 if is_high else -1.0
        saw = 2.0 * phase - 1.0
        self.square = square * amp + offset
        self.sawtooth = saw * amp + offset
        self.triangle = (2.0 * saw * square - 1.0) * amp + offset
        angle = 2.0 * LINUXCNC_PI * phase
        self.sine = math.sin(angle) * amp + offset
        self.cosine = math.cos(angle) * amp + offset


COMPONENT = Siggen
