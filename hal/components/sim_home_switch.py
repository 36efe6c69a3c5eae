"""sim_home_switch: a simulated home switch for sim configs.

``home-sw`` turns on when ``cur-pos`` reaches ``home-pos`` (from either side) and turns off
only after moving ``hysteresis`` back. ``index-enable`` (io) is cleared ``index-delay-ms``
after it is set, as an index pulse would.
"""

from hal.api import RtComponent, funct, pin


class SimHomeSwitch(RtComponent):
    cur_pos = pin("float in")
    home_pos = pin("float in", default=1.0)
    hysteresis = pin("float in", default=0.1)
    home_sw = pin("bit out")
    index_enable = pin("bit io")
    index_delay_ms = pin("float in", default=10.0)

    def setup(self) -> None:
        self.index_timer_ms = 0.0
        self.was_index_enabled = False

    @funct()
    def update(self, period: int) -> None:
        pos, home, hyst = self.cur_pos, self.home_pos, self.hysteresis
        if home >= 0:  # switch on the positive side: on at home-pos, off hyst below it
            if pos >= home:
                self.home_sw = True
            elif pos <= home - hyst:
                self.home_sw = False
        elif pos <= home:  # switch on the negative side
            self.home_sw = True
        elif pos >= home + hyst:
            self.home_sw = False
        if self.index_timer_ms > 0:
            self.index_timer_ms -= period * 1e-6
            if self.index_timer_ms <= 0:
                self.index_timer_ms = 0.0
                self.index_enable = False
                return
        is_index_enabled = self.index_enable
        if is_index_enabled and not self.was_index_enabled:
            self.index_timer_ms = self.index_delay_ms
        self.was_index_enabled = is_index_enabled


COMPONENT = SimHomeSwitch
