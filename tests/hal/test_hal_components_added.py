"""Components added for LinuxCNC's sample configs and tests: what their man pages document
and LinuxCNC's loading rules, beyond the period-by-period comparison with LinuxCNC in
test_hal_oracle.py (lcnc_oracle_new1..3)."""

from __future__ import annotations

import pytest

from hal.core import HalError
from tests.hal.comp_harness import bench


def test_personality_sizes_and_makes_pins() -> None:
    with bench("logic", "names=l1,l2 personality=0x102,0x203") as b:
        names = set(b.hal.meta["pins"])
        assert {"l1.in-00", "l1.in-01", "l1.and"} <= names and "l1.or" not in names
        assert {"l2.in-02", "l2.or"} <= names and "l2.and" not in names
        l1 = b.instances[0]
        l1.in_[0], l1.in_[1] = True, True
        b.run()
        assert l1.and_ is True
    with (
        pytest.raises(HalError, match="Requested size 17 exceeds max size 16"),
        bench("logic", "personality=0x111"),
    ):
        pass


def test_lincurve_keeps_2_to_16_points_and_does_not_extrapolate() -> None:
    with bench("lincurve", "personality=1") as b:
        curve = b.inst
        assert len(curve.x_val) == 2
        curve.x_val[0], curve.x_val[1] = 0.0, 10.0
        curve.y_val[0], curve.y_val[1] = 5.0, 25.0
        for x, y in ((-3.0, 5.0), (2.5, 10.0), (99.0, 25.0)):
            curve.in_ = x
            b.run()
            assert curve.out == y == curve.out_io


def test_singletons_and_module_functions_have_linuxcncs_names() -> None:
    with bench("charge_pump") as b:
        assert b.inst.name == "charge-pump" and "charge-pump" in b.host.functs
    with bench("weighted_sum", "wsum_sizes=3,2") as b:
        assert sorted(b.host.functs) == ["process_wsums"]
        summer = b.instances[0]
        assert [summer.weight[i] for i in range(3)] == [1, 2, 4]
        summer.bit_in[0], summer.bit_in[2], summer.offset = True, True, 10
        b.run()
        assert summer.sum_ == 15
    with bench("encoder_ratio", "names=er0") as b:
        assert sorted(b.host.functs) == ["encoder-ratio.sample", "encoder-ratio.update"]


def test_linuxcncs_counts_and_their_limits() -> None:
    with bench("encoder", "num_chan=0") as b:  # 0: the default, 3 for encoder
        assert len(b.instances) == 3
    with bench("or2", "names=") as b:  # an empty names= is the default count too
        assert [i.name for i in b.instances] == ["or2.0"]
    for module, args in (("encoder_ratio", "num_chan=9"), ("pid", "num_chan=17")):
        with pytest.raises(HalError, match="invalid num_chan"), bench(module, args):
            pass
    with pytest.raises(HalError, match="invalid num_chan: 0"), bench("counter", "num_chan=0"):
        pass


def test_mux_generic_sizes_types_and_debounce() -> None:
    with bench("mux_generic", "config=bs4,ff5,su6") as b:
        pins = set(b.hal.meta["pins"])
        assert {"mux-gen.00.sel-bit-00", "mux-gen.00.sel-bit-01", "mux-gen.00.out-s32"} <= pins
        assert "mux-gen.01.sel-bit-01" in pins  # (5 = 101b: LinuxCNC's rule gives 2 bits)
        assert not any(p.startswith("mux-gen.02.sel-bit") for p in pins)
        b.hal.write_slot(3, b.hal.find_pin("mux-gen.02.in-s32-01")[1]["slot"], -5)
        b.hal.write_slot(4, b.hal.find_pin("mux-gen.02.sel-int")[1]["slot"], 1)
        b.run(functs=["mux-gen.02"])
        assert b.value("mux-gen.02.out-u32") == 0  # a negative s32 is 0 as u32
    for config, cause in (("f1", "one-element"), ("x4", "invalid character"), ("fff2", "too many")):
        with pytest.raises(HalError, match=cause), bench("mux_generic", f"config={config}"):
            pass


def test_pwmgen_pins_follow_the_output_type() -> None:
    with bench("pwmgen", "output_type=0,1,2") as b:
        pins = set(b.hal.meta["pins"])
        assert "pwmgen.0.pwm" in pins and "pwmgen.0.dir" not in pins
        assert {"pwmgen.1.pwm", "pwmgen.1.dir"} <= pins
        assert {"pwmgen.2.up", "pwmgen.2.down"} <= pins and "pwmgen.2.pwm" not in pins


def test_carousel_counts_target_and_a_gray_code_of_zero() -> None:
    """2.9's carousel (newer than the installed LinuxCNC the oracle ran): counts-target for
    a position-mode drive, and all-zero Gray code meaning the last pocket."""
    with bench("carousel", "pockets=8") as b:
        carousel = b.inst
        b.run()
        assert carousel.current_position == 8
        carousel.pocket_number, carousel.enable, carousel.fwd_dc = 3, True, 1.0
        b.run()
        assert carousel.motor_fwd and carousel.counts_target == 300.0  # 8 -> 3 forward
    with bench("carousel", "pockets=6 encoding=counts") as b:
        carousel = b.inst
        carousel.enable = True
        b.run(2)  # a period to see it is not homed, one to start homing
        assert carousel.homing and carousel.index_enable and carousel.motor_fwd


def test_moveoff_goes_back_along_its_waypoints() -> None:
    with bench("moveoff", "personality=1") as b:
        move = b.inst
        move.power_on = move.move_enable = move.apply_offsets = True
        move.waypoint_sample_secs = 0.0
        move.offset_in[0] = 1.0
        functs = ["moveoff.0.read-inputs", "moveoff.0.write-outputs"]
        b.run(2000, functs=functs)
        assert move.offset_current[0] == pytest.approx(1.0)
        assert move.offset_applied and move.waypoint_ct > 10
        move.pos[0] = 5.0
        b.run(functs=functs)
        assert move.pos_plusoffset[0] == pytest.approx(6.0)
        move.apply_offsets = False
        b.run(functs=functs)
        assert move.warning
        b.run(3000, functs=functs)
        assert not move.offset_applied and move.offset_current[0] == pytest.approx(0, abs=1e-3)
        assert move.waypoint_ct == 0


def test_sim_matrix_kb_reports_the_first_change() -> None:
    with bench("sim_matrix_kb") as b:
        kb = b.inst
        kb.c03[5] = True
        b.run()
        assert kb.out == 0xC0 | (5 * 8 + 3)
        b.run()
        assert kb.out == 0x40  # still down, nothing new
        kb.c03[5] = False
        b.run()
        assert kb.out == 0x80 | (5 * 8 + 3)
        b.run()
        assert kb.out == 0
