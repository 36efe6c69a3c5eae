"""corexy_by_hal: CoreXY kinematics in HAL, for a trivkins (coordinates=xyz) machine: the
alpha and beta motors' commands from joint 0 and 1's motor-pos-cmd (alpha = (j0 + j1) / 2,
beta = (j0 - j1) / 2), and the joints' motor-pos-fb from the motors' feedback."""

from hal.api import RtComponent, funct, pin


class CoreXYByHal(RtComponent):
    alpha_fb = pin("float in")
    beta_fb = pin("float in")
    j0_motor_pos_cmd = pin("float in")
    j1_motor_pos_cmd = pin("float in")
    j0_motor_pos_fb = pin("float out")
    j1_motor_pos_fb = pin("float out")
    alpha_cmd = pin("float out")
    beta_cmd = pin("float out")

    @funct()
    def update(self, period: int) -> None:
        alpha, beta = self.alpha_fb, self.beta_fb
        self.j0_motor_pos_fb = alpha + beta
        self.j1_motor_pos_fb = alpha - beta
        j0, j1 = self.j0_motor_pos_cmd, self.j1_motor_pos_cmd
        self.alpha_cmd = 0.5 * (j0 + j1)
        self.beta_cmd = 0.5 * (j0 - j1)


COMPONENT = CoreXYByHal
