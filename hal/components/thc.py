"""thc: torch height control for plasma (one instance, ``thc``), by correcting the Z motor
position command.

``volts`` = (``encoder-vel`` - ``scale-offset``) * ``vel-scale`` (not below 0). While
``enable``: ``vel-status`` is true when ``current-vel`` is above 0 and within
``velocity-tol`` percent below ``requested-vel``; with the torch on, the arc OK and at
speed, the offset moves by ``correction-vel`` each period toward ``volts-requested``
(outside ``voltage-tol``); with the torch off, the offset is taken back as Z rises. Then
``z-pos-out`` = ``z-pos-in`` + offset; disabled it is ``z-pos-in``. ``z-fb-out`` is always
``z-pos-in``. (Its state is kept in single precision, as LinuxCNC's.)
"""

from hal.api import RtComponent, funct, param, pin
from hal.components._cmath import to_f32


class Thc(RtComponent):
    is_singleton = True
    encoder_vel = pin("float in")
    current_vel = pin("float in")
    requested_vel = pin("float in")
    volts_requested = pin("float in")
    vel_tol = pin("float in")
    torch_on = pin("bit in")
    arc_ok = pin("bit in")
    enable = pin("bit in")
    z_pos_in = pin("float in")
    z_pos_out = pin("float out")
    z_fb_out = pin("float out")
    volts = pin("float out")
    vel_status = pin("bit out")
    offset_value = pin("float out")
    vel_scale = param("float rw")
    scale_offset = param("float rw")
    velocity_tol = param("float rw")
    voltage_tol = param("float rw")
    correction_vel = param("float rw")

    def setup(self) -> None:
        self.offset = 0.0  # (single precision)
        self.last_z_in = 0.0  # (single precision)

    @funct()
    def update(self, period: int) -> None:
        volts = max((self.encoder_vel - self.scale_offset) * self.vel_scale, 0.0)
        self.volts = volts
        self.offset_value = self.offset
        z_in = self.z_pos_in
        if self.enable:
            requested = self.requested_vel
            min_velocity = to_f32(requested - requested * (self.velocity_tol * 0.01))
            current = self.current_vel
            is_at_speed = current > 0 and current >= min_velocity
            self.vel_status = is_at_speed
            torch_on = self.torch_on
            if torch_on and self.arc_ok and is_at_speed:
                wanted, tolerance, step = (
                    self.volts_requested,
                    self.voltage_tol,
                    self.correction_vel,
                )
                if volts + tolerance > wanted:
                    self.offset = to_f32(self.offset - step)
                if volts - tolerance < wanted:
                    self.offset = to_f32(self.offset + step)
                self.last_z_in = 0.0
            if not torch_on:  # take the offset back as the torch rises
                rise = to_f32(z_in - self.last_z_in)
                offset = self.offset
                if rise > 0 and offset != 0:
                    if offset > 0:
                        offset = to_f32(offset - rise) if offset > rise else 0.0
                    if offset < 0:
                        offset = to_f32(offset + rise) if offset < rise else 0.0
                    self.offset = offset
                self.last_z_in = to_f32(z_in)
            self.z_pos_out = z_in + self.offset
        else:
            self.z_pos_out = z_in
        self.z_fb_out = z_in


COMPONENT = Thc
