"""multiclick: single-, double-, triple- and quadruple-click detector.

A click is a rising edge of ``in`` (a falling edge with ``invert-input``), the input held at
most ``max-hold-ns``, then released. Clicks belong together while the input stays released
at most ``max-space-ns`` between them. ``single-click`` ... ``quadruple-click`` pulse (for
``output-hold-ns``) as soon as that many clicks are seen; the ``*-click-only`` pins pulse
once the space after the last click has timed out, so no further click is coming (for
halui MDI commands). Holding too long, or a fifth click, ignores the input until it is
released. ``state`` shows the detector's state (0 idle).
"""

from hal.api import RtComponent, funct, param, pin

IDLE, HELD_TOO_LONG = 0, 9  # states 1..8: rising edge / click of the first..fourth click
U32 = 0xFFFFFFFF


class MultiClick(RtComponent):
    in_ = pin("bit in")
    single_click = pin("bit out")
    single_click_only = pin("bit out")
    double_click = pin("bit out")
    double_click_only = pin("bit out")
    triple_click = pin("bit out")
    triple_click_only = pin("bit out")
    quadruple_click = pin("bit out")
    quadruple_click_only = pin("bit out")
    state = pin("s32 out")
    invert_input = param("bit rw")
    max_hold_ns = param("u32 rw", default=250_000_000)
    max_space_ns = param("u32 rw", default=250_000_000)
    output_hold_ns = param("u32 rw", default=100_000_000)

    _CLICKS = ("single_click", "double_click", "triple_click", "quadruple_click")
    _ONLY = tuple(f"{name}_only" for name in _CLICKS)

    def setup(self) -> None:
        self.click_state = IDLE
        self.timer = self.timeout = 0
        # output pin attribute -> ns its pulse still lasts
        self.pulses = dict.fromkeys(self._CLICKS + self._ONLY, 0)

    def _pulse(self, attr: str) -> None:
        setattr(self, attr, True)
        self.pulses[attr] = self.output_hold_ns

    @funct()
    def update(self, period: int) -> None:
        is_in = self.in_ != self.invert_input
        state = self.click_state
        if state != IDLE:
            self.timer = (self.timer + period) & U32
        for attr, left in self.pulses.items():
            if left > 0:
                if left > period:
                    self.pulses[attr] = left - period
                else:
                    self.pulses[attr] = 0
                    setattr(self, attr, False)
        if state == HELD_TOO_LONG:
            if not is_in:
                state = IDLE
        elif state == 8:  # four clicks, the most there are: wait for the input to rest
            if is_in:
                state = HELD_TOO_LONG
        elif state % 2 == 0:  # idle or after a click: a rising edge starts the next
            if is_in:
                state += 1
                self.timer, self.timeout = 0, self.max_hold_ns
        elif not is_in:  # released: a click
            state += 1
            self.timer, self.timeout = 0, self.max_space_ns
            self._pulse(self._CLICKS[state // 2 - 1])
        if state not in (IDLE, HELD_TOO_LONG) and self.timer > self.timeout:
            if is_in:
                state = HELD_TOO_LONG
            else:  # the space after the last click is over
                if state % 2 == 0:
                    self._pulse(self._ONLY[state // 2 - 1])
                state = IDLE
        self.click_state = state
        self.state = state


COMPONENT = MultiClick
