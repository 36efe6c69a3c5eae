"""sphereprobe: a simulated probe touching a hemisphere (positions in encoder counts):
inside the circle of radius ``r`` around (``cx``, ``cy``) the probe trips within the
sphere; outside it, below the centre height ``cz``."""

from hal.api import RtComponent, funct, pin


class SphereProbe(RtComponent):
    px = pin("s32 in")
    py = pin("s32 in")
    pz = pin("s32 in")
    cx = pin("s32 in")
    cy = pin("s32 in")
    cz = pin("s32 in")
    r = pin("s32 in")
    probe_out = pin("bit out")

    @funct()
    def update(self, period: int) -> None:
        dx, dy, dz = self.px - self.cx, self.py - self.cy, self.pz - self.cz
        flat = dx * dx + dy * dy
        radius_squared = self.r * self.r
        if flat > radius_squared:
            self.probe_out = self.pz < self.cz
        else:
            self.probe_out = flat + dz * dz <= radius_squared


COMPONENT = SphereProbe
