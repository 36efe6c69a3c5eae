"""differential: kinematics of a differential transmission (two motors drive roll and
pitch): motor0 = roll + pitch, motor1 = roll - pitch, and back for the feedback."""

from hal.api import RtComponent, funct, pin


class Differential(RtComponent):
    roll_cmd = pin("float in")
    pitch_cmd = pin("float in")
    roll_fb = pin("float out")
    pitch_fb = pin("float out")
    motor0_cmd = pin("float out")
    motor1_cmd = pin("float out")
    motor0_fb = pin("float in")
    motor1_fb = pin("float in")

    @funct()
    def update(self, period: int) -> None:
        roll, pitch = self.roll_cmd, self.pitch_cmd
        self.motor0_cmd = roll + pitch
        self.motor1_cmd = roll - pitch
        fb0, fb1 = self.motor0_fb, self.motor1_fb
        self.roll_fb = (fb0 + fb1) / 2
        self.pitch_fb = (fb0 - fb1) / 2


COMPONENT = Differential
