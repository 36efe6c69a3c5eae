"""sim_spindle: a simulated spindle; ``position-fb`` integrates ``velocity-cmd * scale``.

With ``velocity-cmd`` in revolutions per minute, set ``scale`` to 1/60 (sim configs use
0.01666667) to get ``position-fb`` in revolutions. When ``index-enable`` is set, crossing
the next whole revolution clears it and restarts the position from the fraction past the
index, as a real index pulse would (motion's spindle.N.index-enable, G33).

Orientation (M19): while ``orient`` is true and the spindle has (almost) stopped, the
position turns at ``orient-speed`` revolutions per second the short way to
``orient-angle`` degrees past the index; ``is-oriented`` is true once it is there
(motion's spindle.N.orient / orient-angle / is-oriented).
"""

import math

from hal.api import RtComponent, funct, param, pin

# below this commanded speed (rpm) the spindle counts as stopped for orienting
ORIENT_STANDSTILL = 1.0
# an orientation closer than this (revolutions) to the angle counts as reached
ORIENT_TOLERANCE = 1e-4


class SimSpindle(RtComponent):
    velocity_cmd = pin("float in")
    position_fb = pin("float out")
    index_enable = pin("bit io")
    orient = pin("bit in")
    orient_angle = pin("float in")
    is_oriented = pin("bit out")
    scale = param("float rw", default=1.0)
    orient_speed = param("float rw", default=1.0)

    @funct()
    def update(self, period: int) -> None:
        dt = period * 1e-9
        old = self.position_fb
        velocity = self.velocity_cmd
        new = old + velocity * dt * self.scale
        if self.orient and abs(velocity) < ORIENT_STANDSTILL:
            new, self.is_oriented = self._turn_to_angle(old, self.orient_speed * dt)
        else:
            self.is_oriented = False
        if self.index_enable and math.floor(old) != math.floor(new):
            self.index_enable = False
            new -= math.ceil(new) if velocity < 0 else math.floor(new)
        self.position_fb = new

    def _turn_to_angle(self, position: float, max_step: float) -> tuple[float, bool]:
        """One period of orienting: the new position and whether it is at the angle."""
        error = (self.orient_angle / 360.0 - position) % 1.0
        if error > 0.5:
            error -= 1.0  # the short way round
        if abs(error) <= max(max_step, ORIENT_TOLERANCE):
            return position + error, True
        return position + math.copysign(max_step, error), False


COMPONENT = SimSpindle
