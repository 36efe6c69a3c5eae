"""encoder_ratio: an electronic gear. It counts a master and a slave quadrature encoder
(``encoder-ratio.sample``, in a fast thread) and gives the slave's position error in slave
revolutions (``encoder-ratio.update``): while ``enable`` is true the master's counts,
scaled by ``master-teeth``/``slave-teeth`` and the two PPRs, are subtracted, so a PID loop
on ``error`` makes the slave follow the master; while false, ``error`` is just the slave's
position. ``loadrt encoder_ratio [num_chan=N | names=...]``, at most 8 pairs.
"""

from __future__ import annotations

from hal.api import RtComponent, module_funct, pin
from hal.components._cmath import wrap_s32

U32 = 0xFFFFFFFF
# quadrature decoder: (state | A | B << 1) -> next state, with bit 6 a count up, bit 7 a
# count down; a glitch on one input counts up and back, both at once count nothing
_LOOKUP = (0x00, 0x44, 0x88, 0x0C, 0x80, 0x04, 0x08, 0x4C,
           0x40, 0x04, 0x08, 0x8C, 0x00, 0x84, 0x48, 0x0C)  # fmt: skip
UP, DOWN = 0x40, 0x80


class EncoderRatio(RtComponent):
    count_option = "num_chan"
    max_count = 8
    master_A = pin("bit in", "master-A")
    master_B = pin("bit in", "master-B")
    slave_A = pin("bit in", "slave-A")
    slave_B = pin("bit in", "slave-B")
    enable = pin("bit in")
    error = pin("float out")
    master_ppr = pin("u32 io")
    slave_ppr = pin("u32 io")
    master_teeth = pin("u32 io")
    slave_teeth = pin("u32 io")

    def setup(self) -> None:
        self.master_state = self.slave_state = 0
        self.raw_error = 0
        self.master_increment = self.slave_increment = 0
        self.output_scale = 1.0

    @module_funct("sample", has_fp=False)
    @classmethod
    def sample(cls, instances: list[EncoderRatio], period: int) -> None:
        for pair in instances:
            state = _LOOKUP[(pair.master_state & 0x0C) | pair.master_A | pair.master_B << 1]
            if pair.enable:
                if state & UP:
                    pair.raw_error = wrap_s32(pair.raw_error - pair.master_increment)
                elif state & DOWN:
                    pair.raw_error = wrap_s32(pair.raw_error + pair.master_increment)
            pair.master_state = state
            state = _LOOKUP[(pair.slave_state & 0x0C) | pair.slave_A | pair.slave_B << 1]
            if state & UP:
                pair.raw_error = wrap_s32(pair.raw_error + pair.slave_increment)
            elif state & DOWN:
                pair.raw_error = wrap_s32(pair.raw_error - pair.slave_increment)
            pair.slave_state = state

    @module_funct("update")
    @classmethod
    def update(cls, instances: list[EncoderRatio], period: int) -> None:
        for pair in instances:
            if pair.output_scale > 0:
                pair.error = pair.raw_error / pair.output_scale
            # the scale factors follow the pins (C's unsigned 32-bit products)
            pair.master_increment = wrap_s32(pair.master_teeth * pair.slave_ppr)
            pair.slave_increment = wrap_s32(pair.slave_teeth * pair.master_ppr)
            pair.output_scale = float((pair.master_ppr * pair.slave_ppr * pair.slave_teeth) & U32)


COMPONENT = EncoderRatio
