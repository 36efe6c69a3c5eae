"""Realtime components against the behaviour their LinuxCNC man pages document."""

from __future__ import annotations

import math

import pytest

from hal.core import HalError
from tests.hal.comp_harness import Bench, bench


@pytest.mark.parametrize(
    ("module", "table"),
    [
        ("and2", [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 1)]),
        ("or2", [(0, 0, 0), (0, 1, 1), (1, 0, 1), (1, 1, 1)]),
        ("xor2", [(0, 0, 0), (0, 1, 1), (1, 0, 1), (1, 1, 0)]),
    ],
)
def test_two_input_gates(module: str, table: list[tuple[int, int, int]]) -> None:
    with bench(module) as b:
        for in0, in1, out in table:
            b.inst.in0, b.inst.in1 = in0, in1
            b.run()
            assert b.inst.out == bool(out)


def test_not_and_names_and_count() -> None:
    with bench("not", "names=inv-a,inv-b") as b:
        assert [i.name for i in b.instances] == ["inv-a", "inv-b"]
        b.run()
        assert b.value("inv-a.out") == 1


def test_count_and_names_are_exclusive_and_unknown_args_refused() -> None:
    with pytest.raises(HalError, match="mutually exclusive"), bench("and2", "count=1 names=a"):
        pass
    with pytest.raises(HalError, match="unknown argument 'bogus'"), bench("and2", "bogus=1"):
        pass


def test_mux2_mux4_select8() -> None:
    with bench("mux2") as b:
        b.inst.in0, b.inst.in1 = 1.5, 2.5
        b.run()
        assert b.inst.out == 1.5
        b.inst.sel = True
        b.run()
        assert b.inst.out == 2.5
    with bench("mux4") as b:
        for i in range(4):
            b.inst.in_[i] = 10.0 + i
        b.inst.sel0, b.inst.sel1 = True, True
        b.run()
        assert b.inst.out == 13.0
    with bench("select8") as b:
        b.inst.sel = 3
        b.run()
        assert [b.inst.out[i] for i in range(8)] == [i == 3 for i in range(8)]
        b.inst.enable = False
        b.run()
        assert not any(b.inst.out[i] for i in range(8))


def test_arithmetic_components() -> None:
    with bench("scale") as b:
        b.inst.in_, b.inst.gain, b.inst.offset = 2.0, 3.0, 1.0
        b.run()
        assert b.inst.out == 7.0
    with bench("sum2") as b:
        b.inst.in0, b.inst.in1 = 1.0, 2.0
        b.inst.gain1, b.inst.offset = 10.0, 0.5
        b.run()
        assert b.inst.out == 21.5
    with bench("mult2") as b:
        b.inst.in0, b.inst.in1 = 3.0, -2.0
        b.run()
        assert b.inst.out == -6.0
    with bench("div2") as b:
        b.inst.in0, b.inst.in1 = 3.0, 2.0
        b.run()
        assert b.inst.out == 1.5
        b.inst.in1, b.inst.deadband = 0.0, 0.5
        b.run()
        assert b.inst.out == 6.0  # divided by +deadband, as LinuxCNC 2.9 does
        b.inst.in1 = -0.1
        b.run()
        assert b.inst.out == -6.0
    with bench("abs") as b:
        b.inst.in_ = -2.0
        b.run()
        assert (b.inst.out, b.inst.sign, b.inst.is_negative, b.inst.is_positive) == (
            2.0,
            True,
            True,
            False,
        )
    with bench("hypot") as b:
        b.inst.in0, b.inst.in1, b.inst.in2 = 2.0, 3.0, 6.0
        b.run()
        assert b.inst.out == 7.0


def test_ddt_integ_lowpass() -> None:
    with bench("ddt") as b:
        b.inst.in_ = 0.001
        b.run()
        assert b.inst.out == pytest.approx(1.0)  # 0.001 per 1 ms period
        b.run()
        assert b.inst.out == 0.0
    with bench("integ") as b:
        b.inst.in_, b.inst.gain = 2.0, 1.0
        b.run(500)
        assert b.inst.out == pytest.approx(1.0)
        b.inst.max = 0.5
        b.run()
        assert b.inst.out == 0.5
        b.inst.reset = True
        b.run()
        assert b.inst.out == 0.0
    with bench("lowpass") as b:
        b.inst.in_, b.inst.gain = 1.0, 0.5
        b.run(2)
        assert b.inst.out == 0.75
        b.inst.load, b.inst.in_ = True, 4.0
        b.run()
        assert b.inst.out == 4.0


def test_limit1_limit2_limit3() -> None:
    with bench("limit1") as b:
        b.inst.min, b.inst.max, b.inst.in_ = -1.0, 1.0, 5.0
        b.run()
        assert b.inst.out == 1.0
    with bench("limit2") as b:
        b.inst.maxv, b.inst.in_ = 10.0, 1.0  # 10 units/s -> 0.01 per ms
        b.run()
        assert b.inst.out == pytest.approx(0.01)
        b.run(200)
        assert b.inst.out == 1.0
    with bench("limit3") as b:
        b.inst.maxv, b.inst.maxa, b.inst.in_ = 10.0, 100.0, 1.0
        outs, vels = [], []
        for _ in range(400):
            b.run()
            outs.append(b.inst.out)
        vels = [(y - x) / 0.001 for x, y in zip([0.0, *outs], outs, strict=False)]
        accels = [(w - v) / 0.001 for v, w in zip([0.0, *vels], vels, strict=False)]
        assert outs[-1] == pytest.approx(1.0)
        assert max(outs) <= 1.0 + 1e-9
        assert max(abs(v) for v in vels) <= 10.0 + 1e-6
        assert max(abs(a) for a in accels) <= 100.0 + 1e-6


def test_comparators() -> None:
    with bench("comp") as b:
        b.inst.hyst = 0.2
        b.inst.in1 = 0.1  # the band is inclusive
        b.run()
        assert not b.inst.out and b.inst.equal
        b.inst.in1 = 0.2
        b.run()
        assert b.inst.out and not b.inst.equal
        b.inst.in1 = -0.05  # within the hysteresis band: keeps its state
        b.run()
        assert b.inst.out
    with bench("wcomp") as b:
        b.inst.min, b.inst.max, b.inst.in_ = 0.0, 1.0, 0.5
        b.run()
        assert (b.inst.out, b.inst.under, b.inst.over) == (True, False, False)
        b.inst.in_ = 1.0
        b.run()
        assert (b.inst.out, b.inst.under, b.inst.over) == (False, False, True)
    with bench("near") as b:
        b.inst.in1, b.inst.in2, b.inst.scale = 10.0, 11.0, 1.2
        b.run()
        assert b.inst.out
        b.inst.scale, b.inst.difference = 1.0, 0.5
        b.run()
        assert not b.inst.out


def test_edge_oneshot_flipflop_toggle() -> None:
    with bench("edge") as b:
        b.inst.in_edge = False  # rising
        b.run()
        b.inst.in_ = True
        b.run()
        assert b.inst.out and not b.inst.out_invert
        b.run()
        assert not b.inst.out
    with bench("oneshot") as b:
        b.inst.width = 0.0035
        b.inst.in_ = True
        outs = []
        for _ in range(6):
            b.run()
            outs.append(b.inst.out)
        assert outs == [True, True, True, True, False, False]
    with bench("flipflop") as b:
        b.inst.data = True
        b.run()
        assert not b.inst.out
        b.inst.clk = True
        b.run()
        assert b.inst.out and not b.inst.out_not
        b.inst.reset = True
        b.run()
        assert not b.inst.out
    with bench("toggle") as b:
        b.inst.in_ = True
        b.run(5)
        assert b.inst.out
        b.inst.in_ = False
        b.run(5)
        b.inst.in_ = True
        b.run(5)
        assert not b.inst.out


def test_timedelay_and_debounce() -> None:
    with bench("timedelay") as b:
        b.inst.on_delay, b.inst.in_ = 0.005, True
        b.run(4)
        assert not b.inst.out
        b.run(1)
        assert b.inst.out
    with bench("debounce", "cfg=2,1") as b:
        assert b.value("debounce.0.delay") == 5
        first = b.instances[0]
        first.delay = 3
        first.in_[1] = True
        b.run(3)  # the counter reaches 3...
        assert not first.out[1]
        b.run(1)  # ...and the next period sets the output
        assert first.out[1] and not first.out[0]
        assert b.hal.find_pin("debounce.1.0.in") is not None


def test_siggen_waveforms() -> None:
    with bench("siggen") as b:
        sig = b.inst
        sig.frequency, sig.amplitude, sig.offset = 1.0, 2.0, 1.0
        sig.reset = True
        b.run()
        assert (sig.sine, sig.sawtooth) == (pytest.approx(1.0), 1.0)
        assert (sig.square, sig.triangle) == (-1.0, -1.0)
        assert sig.cosine == pytest.approx(-1.0)
        sig.reset = False
        b.run(250)  # a quarter cycle after mid-cycle
        assert sig.sine == pytest.approx(1.0 - 2.0)
        assert sig.cosine == pytest.approx(1.0, abs=1e-6)
        assert sig.triangle == pytest.approx(1.0, abs=1e-9)
        assert sig.sawtooth == pytest.approx(2.0)
        assert sig.square == 3.0 and sig.clock
        b.run(500)
        assert sig.square == -1.0 and not sig.clock
        sig.frequency = 2000.0  # above half the 1 kHz thread rate
        b.run()
        assert sig.frequency == 500.0


def test_pid_proportional_integral_feedforward_and_limits() -> None:
    with bench("pid", "num_chan=1") as b:
        pid = b.inst
        pid.Pgain, pid.enable, pid.error_previous_target = 2.0, True, False
        pid.command, pid.feedback = 1.0, 0.25
        b.run()
        assert pid.error == 0.75
        assert pid.output == pytest.approx(1.5 + 0.0)  # FF1=0, Igain=0, Dgain=0
        pid.Igain = 10.0
        b.run(100)
        assert pid.output == pytest.approx(1.5 + 10.0 * 0.75 * 0.101, rel=1e-6)
        pid.maxoutput = 1.0
        b.run()
        assert pid.output == 1.0 and pid.saturated
        pid.enable = False
        b.run()
        assert pid.output == 0.0
    with bench("pid") as b:
        assert len(b.instances) == 3  # LinuxCNC's default


def test_conv_components_range_and_clamp() -> None:
    with bench("conv_float_s32") as b:
        b.inst.in_ = 3.7
        b.run()
        assert b.inst.out == 3 and not b.inst.out_of_range
        b.inst.in_, b.inst.clamp = 1e12, True
        b.run()
        assert b.inst.out == 2**31 - 1 and b.inst.out_of_range
    with bench("conv_s32_u32") as b:
        b.inst.in_, b.inst.clamp = -5, True
        b.run()
        assert b.inst.out == 0 and b.inst.out_of_range
    with bench("conv_bit_float") as b:
        b.inst.in_ = True
        b.run()
        assert b.inst.out == 1.0


def test_sim_home_switch_hysteresis_and_index() -> None:
    with bench("sim_home_switch") as b:
        sw = b.inst
        sw.home_pos, sw.hysteresis = 1.0, 0.1
        sw.cur_pos = 1.0
        b.run()
        assert sw.home_sw
        sw.cur_pos = 0.95  # inside the hysteresis: still on
        b.run()
        assert sw.home_sw
        sw.cur_pos = 0.85
        b.run()
        assert not sw.home_sw
        sw.index_enable, sw.index_delay_ms = True, 3.0
        b.run(3)  # the delay starts counting the period after index-enable rose
        assert sw.index_enable
        b.run(1)
        assert not sw.index_enable


def test_sim_encoder_drives_encoder() -> None:
    with bench("sim_encoder", "num_chan=1") as sim:
        enc = Bench(sim.hal, "encoder")  # a second module in the same HAL
        sim.inst.speed, sim.inst.ppr = 10.0, 25  # 1000 edges/s
        enc.inst.position_scale = 100.0
        for _ in range(100):  # 100 ms of 20 us base periods and 1 ms servo periods
            sim.run(1, functs=["sim-encoder.update-speed"])
            for _ in range(50):
                sim.run(1, 20_000, functs=["sim-encoder.make-pulses"])
                enc.inst.phase_A, enc.inst.phase_B = sim.inst.phase_A, sim.inst.phase_B
                enc.run(1, 20_000, functs=["encoder.update-counters"])
            enc.run(1, functs=["encoder.capture-position"])
        # 1000 steps/s for 0.1 s, plus the first edge the encoder sees at start (00 -> A)
        assert enc.inst.counts == pytest.approx(101, abs=1)
        assert enc.inst.position == enc.inst.counts / 100
        assert enc.inst.velocity == pytest.approx(10.0, rel=0.1)


def test_encoder_x1_mode_counter_mode_and_index() -> None:
    with bench("encoder", "num_chan=1") as b:
        enc = b.inst
        states = [(0, 0), (1, 0), (1, 1), (0, 1)] * 2 + [(0, 0)]
        for a, bb in states:
            enc.phase_A, enc.phase_B = a, bb
            b.run(functs=["encoder.update-counters"])
        b.run(functs=["encoder.capture-position"])
        assert enc.counts == 8
        enc.x4_mode = False
        for a, bb in states[1:]:
            enc.phase_A, enc.phase_B = a, bb
            b.run(functs=["encoder.update-counters"])
        b.run(functs=["encoder.capture-position"])
        assert enc.counts == 10  # x1: one count per full cycle
        enc.x4_mode = True
        enc.index_enable = True
        b.run(functs=["encoder.capture-position"])  # capture arms the index...
        enc.phase_Z = True
        b.run(functs=["encoder.update-counters", "encoder.capture-position"])
        assert enc.counts == 0 and not enc.index_enable  # ...and the next rising Z zeroes


def test_stepgen_velocity_and_position_modes() -> None:
    with bench("stepgen", "step_type=0,0 ctrl_type=v,p") as b:
        vel, pos = b.instances
        assert b.hal.find_pin("stepgen.0.velocity-cmd") is not None
        assert b.hal.find_pin("stepgen.1.position-cmd") is not None
        for inst in (vel, pos):
            inst.enable = True
            inst.position_scale = 100.0
            inst.steplen = 1
        vel.velocity_cmd = 1.0  # 100 steps/s
        pos.position_cmd = 0.5  # 50 steps
        pos.maxvel, pos.maxaccel = 2.0, 20.0
        steps = 0
        for _ in range(1000):  # 1 s: servo 1 ms, base 10 us (100 per servo period)
            b.run(1, functs=["stepgen.update-freq"])
            for _ in range(100):
                was = vel.step
                b.run(1, 10_000, functs=["stepgen.make-pulses"])
                steps += vel.step and not was
            b.run(1, functs=["stepgen.capture-position"])
        assert vel.counts == pytest.approx(100, abs=1)
        assert steps == vel.counts
        assert vel.position_fb == pytest.approx(1.0, abs=0.01)
        assert pos.counts == 50
        assert pos.position_fb == pytest.approx(0.5, abs=0.005)  # within half a step
        pos.position_cmd = 0.0
        for _ in range(1000):
            b.run(1, functs=["stepgen.update-freq"])
            for _ in range(100):
                b.run(1, 10_000, functs=["stepgen.make-pulses"])
        b.run(1, functs=["stepgen.capture-position"])
        assert pos.counts == 0 and pos.dir


def test_sim_spindle_and_timedelta() -> None:
    with bench("sim_spindle") as b:
        b.inst.velocity_cmd, b.inst.scale = 600.0, 1 / 60  # rev/min -> 10 rev/s
        b.run(100)
        assert b.inst.position_fb == pytest.approx(1.0)
        b.inst.index_enable = True
        b.run(150)
        assert not b.inst.index_enable
        assert b.inst.position_fb == pytest.approx(0.5, abs=0.011)
    with bench("timedelta") as b:
        b.run(3)
        assert b.inst.out > 0 and b.inst.max >= b.inst.min > 0
        assert not math.isnan(b.inst.avg_err)


def test_pid_previous_target_derivative_pins_and_deadband() -> None:
    with bench("pid", "num_chan=1") as b:
        pid = b.inst
        pid.enable, pid.Pgain = True, 1.0
        pid.command = 1.0
        b.run()
        assert pid.error == 0.0  # error-previous-target: last period's command (0)
        b.run()
        assert pid.error == 1.0 and pid.output == 1.0
        pid.Pgain, pid.Dgain, pid.deadband = 0.0, 1.0, 0.0
        for step in range(1, 4):
            pid.command = 1.0 + 0.001 * step  # 1 unit/s
            b.run()
        assert pid.command_deriv == pytest.approx(1.0)
        assert pid.feedback_deriv == 0.0
        assert pid.output == pytest.approx(1.0)  # Dgain * (command' - feedback')
        pid.Dgain, pid.Pgain, pid.deadband = 0.0, 1.0, 0.5
        pid.feedback = pid.command - 0.75
        b.run()
        b.run()
        assert pid.error == pytest.approx(0.75) and pid.output == pytest.approx(0.25)


def test_more_documented_edge_cases() -> None:
    with bench("near") as b:
        b.inst.in1, b.inst.in2, b.inst.scale = -10.0, -11.0, 1.2
        b.run()
        assert b.inst.out  # magnitudes compared for negative values
    with bench("timedelay") as b:
        b.inst.on_delay, b.inst.in_ = 0.002, True
        b.run(3)
        assert b.inst.out and b.inst.elapsed == pytest.approx(0.002)
    with bench("edge") as b:
        b.inst.both, b.inst.out_width_ns = True, 2_500_000
        b.run()
        b.inst.in_ = True
        outs = []
        for _ in range(5):
            b.run()
            outs.append(b.inst.out)
        assert outs == [True, True, True, False, False]  # 2.5 ms -> 3 periods
    with bench("oneshot") as b:
        b.inst.width, b.inst.retriggerable, b.inst.falling = 0.0025, False, True
        b.inst.in_ = True
        b.run()
        b.inst.in_ = False  # a falling edge during the pulse: ignored
        outs = []
        for _ in range(4):
            b.run()
            outs.append(b.inst.out)
        assert outs == [True, True, False, False]
    with bench("toggle") as b:
        b.inst.debounce = 0
        b.run()
        assert b.inst.debounce == 2
    with bench("limit3") as b:
        b.inst.maxv, b.inst.maxa, b.inst.in_ = 10.0, 100.0, 1.0
        b.run(500)
        assert b.inst.out == pytest.approx(1.0)
        b.inst.enable = False  # back to 0 under the same limits
        b.run(500)
        assert b.inst.out == pytest.approx(0.0, abs=1e-9)


def test_encoder_counter_mode_counts_rising_edges_of_phase_a() -> None:
    with bench("encoder", "num_chan=1") as b:
        enc = b.inst
        enc.counter_mode = True
        seen = []
        for a, direction in [(1, 0), (0, 0), (1, 0), (0, 1), (1, 1), (0, 1), (1, 1), (1, 1)]:
            enc.phase_A, enc.phase_B = a, direction
            b.run(functs=["encoder.update-counters", "encoder.capture-position"])
            seen.append(enc.counts)
        assert seen == [1, 1, 2, 2, 3, 3, 4, 4]  # phase-B is ignored
