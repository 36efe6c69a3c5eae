"""Spindle-synchronised motion on a whole machine (MOT-062, MOT-065): ``cnc run`` with
task's test mill plus configs/sim/sim_spindle.hal, driven through ``import cnc``.

While a G33 thread runs, the test reads the spindle's revolution count and Z from HAL and
checks that Z follows the revolutions at the pitch from the index pulse; a G95 move must
feed at the feed per revolution times the measured spindle speed; M19 orients the spindle.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

import cnc
from hal.core import Hal
from tests.task.test_machine import MACHINE, Machine, launched

SIM = Path(__file__).parents[2] / "configs" / "sim"
G33_LINE = 4  # of the program below


@pytest.fixture
def machine(procs, tmp_path: Path) -> Iterator[Machine]:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    shutil.copy(SIM / "sim_spindle.hal", folder)
    ini = folder / "mill.ini"
    halfiles = "HALFILE = mill.hal\nHALFILE = sim_spindle.hal"
    ini.write_text(ini.read_text().replace("HALFILE = mill.hal", halfiles))
    with launched(procs, folder) as machine:
        yield machine


class Pins:
    """Reads HAL pins of the running machine."""

    def __init__(self) -> None:
        self.hal = Hal(is_creating=False)

    def get(self, name: str) -> float:
        found = self.hal.find_pin(name)
        assert found is not None, name
        return self.hal.pin_value(found[1])

    def close(self) -> None:
        self.hal.close()


def run_program(machine: Machine, text: str, sample) -> None:
    """Run ``text`` as a program, calling ``sample()`` until it has finished."""
    program = machine.folder / "part.ngc"
    program.write_text(text)
    machine.ready_to_move()
    c = machine.command
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.interp_state != cnc.INTERP_IDLE, timeout=5)

    def is_finished(s) -> bool:
        sample()
        return s.interp_state == cnc.INTERP_IDLE and s.inpos and s.queue == 0

    machine.until(is_finished, timeout=60)


def test_g33_thread_follows_the_spindle_and_g95_feeds_per_revolution(machine: Machine) -> None:
    pitch, z_start = 1.5, 5.0
    pins = Pins()
    thread_errors: list[float] = []
    g95_speeds: list[float] = []

    def sample() -> None:
        revs = pins.get("spindle.0.revs")
        z = pins.get("axis.z.pos-cmd")
        x = pins.get("axis.x.pos-cmd")
        vel = pins.get("motion.current-vel")
        line = pins.get("motion.program-line")
        if pins.get("spindle.0.revs") != revs:
            return  # a servo period passed between the reads
        if line == G33_LINE and -8.0 < z < z_start - 2.0:  # threading, past the catch-up
            # motion uses the count of the period before: one period of spindle travel
            thread_errors.append(abs(z - (z_start - revs * pitch)))
        if 1.0 < x < 4.0:
            g95_speeds.append(vel)

    try:
        run_program(
            machine,
            "G21 G90 G17\n"
            f"G0 X0 Y0 Z{z_start}\n"
            "M3 S600\n"  # 10 revolutions per second
            f"G33 Z-10 K{pitch}\n"
            "G0 Z10\n"
            "G95 G1 X5 F0.5\n"  # 0.5 mm per revolution: 5 mm/s
            "G94\n"
            # task sends spindle commands without waiting for motion (LinuxCNC's task
            # waits): the dwells make it wait, so that M5 does not stop the G95 move and
            # M2's spindle stop does not cancel M19 before it is done
            "G4 P0\n"
            "M5\n"
            "M19 R90 Q5\n"
            "G4 P0\n"
            "M2\n",
            sample,
        )
        s = machine.stat
        assert machine.messages(0.05) == []
        assert s.position[:3] == pytest.approx((5.0, 0.0, 10.0))
        assert len(thread_errors) > 20 and max(thread_errors) < 0.05
        assert g95_speeds and max(g95_speeds) == pytest.approx(5.0, rel=0.01)
        # M19 R90 left the spindle a quarter turn past its index (M2 then stopped it)
        assert pins.get("spindle.0.revs") % 1.0 == pytest.approx(0.25, abs=1e-3)
        assert not pins.get("spindle.0.locked")  # M2 turned the spindle off: unlocked
        assert pins.get("spindle.0.index-enable") == 0  # the index pulse was taken
    finally:
        pins.close()
