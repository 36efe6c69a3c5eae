"""sim_spindle: a simulated spindle; ``position-fb`` integrates ``velocity-cmd * scale``.

With ``velocity-cmd`` in revolutions per minute, set ``scale`` to 1/60 (sim configs use
0.01666667) to get ``position-fb`` in revolutions. When ``index-enable`` is set, crossing
the next whole revolution clears it and restarts the position from the fraction past the
index, as a real index pulse would.
"""

import math

from hal.api import RtComponent, funct, param, pin


class SimSpindle(RtComponent):
    velocity_cmd = pin("float in")
    position_fb = pin("float out")
    index_enable = pin("bit io")
    scale = param("float rw", default=1.0)

    @funct()
    def update(self, period: int) -> None:
        old = self.position_fb
        velocity = self.velocity_cmd
        new = old + velocity * period * 1e-9 * self.scale
        if self.index_enable and math.floor(old) != math.floor(new):
            self.index_enable = False
            new -= math.ceil(new) if velocity < 0 else math.floor(new)
        self.position_fb = new


COMPONENT = SimSpindle
