"""motmod in a real realtime host: HAL file, NML commands, joint pins, status (MOT-008..018)."""

from __future__ import annotations

import math
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from hal.core import Hal
from hal.rtapi_app import Host
from nml import emc
from nml.channels import EMC_ERROR, MOTION_COMMAND, MOTION_STATUS, Nml, load_config
from nml.message import RCS_STATUS
from tests.hal.halrun_util import run_cnc

MOTION_HAL = """\
loadrt trivkins coordinates=XYZ
loadrt motmod servo_period_nsec=1000000 num_joints=3 num_dio=2 num_aio=1
addf motion-command-handler servo-thread
addf motion-controller servo-thread
net j0 joint.0.motor-pos-cmd => joint.0.motor-pos-fb
net j1 joint.1.motor-pos-cmd => joint.1.motor-pos-fb
net j2 joint.2.motor-pos-cmd => joint.2.motor-pos-fb
start
"""


class Task:
    """The test plays task: it sends motion commands and waits for their echo."""

    def __init__(self) -> None:
        config = load_config()
        self.master = Nml(config, "cnc", [MOTION_COMMAND, MOTION_STATUS, EMC_ERROR])
        self.task = Nml(config, "emc", [MOTION_COMMAND, MOTION_STATUS])
        self.ui = Nml(config, "xemc", [EMC_ERROR])

    def send(self, cmd: emc.NMLmsg, timeout: float = 10) -> emc.EMC_MOTION_STAT:
        serial = self.task[MOTION_COMMAND].write(cmd)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            stat = self.task[MOTION_STATUS].blocking_read(1)
            if (
                stat is not None
                and stat.echo_serial_number == serial
                and stat.status
                in (
                    RCS_STATUS.DONE,
                    RCS_STATUS.ERROR,
                )
            ):
                return stat
        raise AssertionError(f"no answer to {cmd.NAME}")

    def wait_for(self, condition, timeout: float = 20) -> emc.EMC_MOTION_STAT:
        """The status once ``condition`` holds (it may hold already: motion writes its
        status only when something changes)."""
        latest = self.task[MOTION_STATUS].peek()
        if latest is not None and condition(latest):
            return latest
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            stat = self.task[MOTION_STATUS].blocking_read(1)
            if stat is not None and condition(stat):
                return stat
        raise AssertionError("condition not reached")

    def errors(self) -> list[str]:
        found = []
        while (msg := self.ui[EMC_ERROR].read()) is not None:
            found.append(msg.error)
        return found

    def close(self) -> None:
        for nml in (self.ui, self.task, self.master):
            nml.close()


@pytest.fixture
def machine(procs, tmp_path: Path) -> Iterator[Task]:
    yield from _machine(procs, tmp_path)


@pytest.fixture
def machine_with_z_offsets(procs, tmp_path: Path, monkeypatch) -> Iterator[Task]:
    """The machine, with external offsets on Z ([AXIS_Z]OFFSET_AV_RATIO)."""
    ini = tmp_path / "machine.ini"
    ini.write_text("[AXIS_Z]\nOFFSET_AV_RATIO = 0.2\n")
    monkeypatch.setenv("CNC_INI_FILE", str(ini))
    yield from _machine(procs, tmp_path)


def _machine(procs, tmp_path: Path) -> Iterator[Task]:
    task = Task()
    host = procs.python("-m", "hal.rtapi_app", "--no-rt")
    try:
        assert host.stdout.readline().strip() == "rtapi_app: ready"
        hal_file = tmp_path / "motion.hal"
        hal_file.write_text(MOTION_HAL)
        loaded = run_cnc("halcmd", "-f", str(hal_file))
        assert loaded.returncode == 0, loaded.stderr
        yield task
    finally:
        run_cnc("halcmd", "unload", "all")
        host.send_signal(signal.SIGTERM)
        host.wait(timeout=10)
        task.close()


def configure(task: Task) -> None:
    for joint in range(3):
        for cmd in (
            emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=joint, limit=-50.0),
            emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=joint, limit=50.0),
            emc.EMC_JOINT_SET_MAX_VELOCITY(joint=joint, vel=30.0),
            emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=joint, acc=500.0),
            emc.EMC_AXIS_SET_MAX_VELOCITY(axis=joint, vel=30.0),
            emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=joint, acc=500.0),
            emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=joint, limit=-50.0),
            emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=joint, limit=50.0),
            emc.EMC_JOINT_SET_HOMING_PARAMS(joint=joint, home_sequence=0),
        ):
            assert task.send(cmd).status == RCS_STATUS.DONE


def pin(name: str) -> float:
    hal = Hal()
    try:
        return hal.pin_value(hal.find_pin(name)[1])
    finally:
        hal.close()


def settled_pin(name: str, expected: float, timeout: float = 5) -> float:
    """The pin's value once it reaches ``expected`` (feedback lags a servo period)."""
    deadline = time.monotonic() + timeout
    value = pin(name)
    while value != pytest.approx(expected) and time.monotonic() < deadline:
        time.sleep(0.005)
        value = pin(name)
    return value


def test_enable_home_and_move_through_real_processes(machine: Task) -> None:
    configure(machine)
    assert machine.send(emc.EMC_TRAJ_ENABLE()).status == RCS_STATUS.DONE
    assert pin("motion.is-all-homed") == 0
    assert machine.send(emc.EMC_JOINT_HOME(joint=-1)).status == RCS_STATUS.DONE
    stat = machine.wait_for(lambda s: all(s.joint[i].homed for i in range(3)) and s.traj.inpos)
    assert stat.traj.enabled
    assert settled_pin("motion.is-all-homed", 1) == 1  # (LinuxCNC 2.9's pin)
    assert machine.send(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD)).status == (
        RCS_STATUS.DONE
    )
    move = emc.EMC_TRAJ_LINEAR_MOVE(type=emc.EMC_MOTION_TYPE.FEED, vel=20.0, ini_maxvel=30.0)
    move.acc = 500.0
    move.end.tran.x, move.end.tran.y, move.end.tran.z = 5.0, -3.0, 1.0
    assert machine.send(move).status == RCS_STATUS.DONE
    stat = machine.wait_for(
        lambda s: s.traj.inpos and s.traj.queue == 0 and s.traj.position.tran.x > 4.9
    )
    assert (stat.traj.position.tran.x, stat.traj.position.tran.y) == pytest.approx((5.0, -3.0))
    assert stat.traj.actualPosition.tran.z == pytest.approx(1.0)
    assert pin("joint.0.motor-pos-cmd") == pytest.approx(5.0)
    assert pin("axis.y.pos-cmd") == pytest.approx(-3.0)
    assert pin("joint.2.amp-enable-out") == 1
    assert pin("motion.coord-mode") == 1


def test_refused_command_answers_error_and_says_why_on_the_error_channel(machine: Task) -> None:
    configure(machine)
    machine.errors()
    move = emc.EMC_TRAJ_LINEAR_MOVE(vel=10.0, ini_maxvel=30.0, acc=500.0)
    assert machine.send(move).status == RCS_STATUS.ERROR  # not enabled, not in coord mode
    assert machine.send(emc.EMC_TRAJ_ENABLE()).status == RCS_STATUS.DONE
    jog = emc.EMC_JOG_INCR(joint_or_axis=7, incr=1.0, vel=5.0, jjogmode=emc.JOG_MODE.JOINT)
    assert machine.send(jog).status == RCS_STATUS.ERROR
    deadline = time.monotonic() + 10
    errors: list[str] = []
    while len(errors) < 2 and time.monotonic() < deadline:
        errors += machine.errors()
        time.sleep(0.01)
    assert errors == [
        "moves need coordinated mode",
        "EMC_JOG_INCR: joint 7 does not exist (0..2)",
    ]


def test_joint_jog_moves_the_motor_pin(machine: Task) -> None:
    configure(machine)
    machine.send(emc.EMC_TRAJ_ENABLE())
    jog = emc.EMC_JOG_INCR(joint_or_axis=1, incr=2.5, vel=10.0, jjogmode=emc.JOG_MODE.JOINT)
    assert machine.send(jog).status == RCS_STATUS.DONE
    stat = machine.wait_for(lambda s: s.joint[1].output > 2.49 and s.joint[1].inpos)
    assert stat.joint[1].output == pytest.approx(2.5)
    assert pin("joint.1.motor-pos-cmd") == pytest.approx(2.5)
    assert settled_pin("joint.1.pos-fb", 2.5) == pytest.approx(2.5)


def test_replaceable_modules_are_checked_when_motmod_loads(
    procs, tmp_path: Path, monkeypatch
) -> None:
    """ARCH-008: tp=/hm= (or [TRAJ]TPMOD / [EMCMOT]HOMEMOD) name the modules; an incomplete
    replacement is refused with everything it lacks."""
    (tmp_path / "mytp.py").write_text(
        "class Planner:\n    def add_line(self, *args):\n        pass\n"
    )
    (tmp_path / "goodhoming.py").write_text("from motion.homing.homing import Homing\n")
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    task = Task()
    host = procs.python("-m", "hal.rtapi_app", "--no-rt", env={"PYTHONPATH": f"{tmp_path}"})
    try:
        assert host.stdout.readline().strip() == "rtapi_app: ready"
        assert run_cnc("halcmd", "loadrt", "trivkins", "coordinates=XYZ").returncode == 0
        # as in LinuxCNC, motion's joint count rules: joints the kinematics map beyond it
        # are left out (and a bare trivkins, all nine, makes an XYZ machine with 3)
        fewer = run_cnc("halcmd", "loadrt", "motmod", "num_joints=2")
        assert fewer.returncode == 0, fewer.stderr
        assert run_cnc("halcmd", "unloadrt", "motmod").returncode == 0
        refused = run_cnc("halcmd", "loadrt", "motmod", "tp=mytp")
        assert refused.returncode != 0
        assert "trajectory planner module 'mytp' is incomplete: missing" in refused.stderr
        assert "abort" in refused.stderr and "add_circle" in refused.stderr
        loaded = run_cnc("halcmd", "loadrt", "motmod", "hm=goodhoming")
        assert loaded.returncode == 0, loaded.stderr
    finally:
        run_cnc("halcmd", "unload", "all")
        host.send_signal(signal.SIGTERM)
        host.wait(timeout=10)
        task.close()


def test_mpg_wheel_pins_jog_the_joint(machine: Task) -> None:
    configure(machine)
    machine.send(emc.EMC_TRAJ_ENABLE())
    for name, value in (("jog-scale", "0.1"), ("jog-counts", "7"), ("jog-enable", "1")):
        assert run_cnc("halcmd", "setp", f"joint.0.{name}", value).returncode == 0
    # counts that arrived before the wheel was enabled are dropped (motion(9))
    assert run_cnc("halcmd", "setp", "joint.0.jog-counts", "32").returncode == 0
    assert settled_pin("joint.0.motor-pos-cmd", 2.5) == pytest.approx(2.5)


def test_spindle_and_wheel_pins_have_motion9s_names(machine: Task) -> None:
    spindle = (
        "amp-fault-in at-speed brake forward index-enable inhibit is-oriented locked on orient "
        "orient-angle orient-fault orient-mode reverse revs speed-cmd-rps speed-in speed-out "
        "speed-out-abs speed-out-rps speed-out-rps-abs"
    )
    wheel = "jog-accel-fraction jog-counts jog-enable jog-scale jog-vel-mode"
    names = [f"spindle.0.{n}" for n in spindle.split()]
    names += [f"{part}.{n}" for part in ("joint.2", "axis.x") for n in wheel.split()]
    names += [f"motion.jog-{n}" for n in ("inhibit", "stop", "stop-immediate", "is-active")]
    hal = Hal()
    try:
        assert [n for n in names if hal.find_pin(n) is None] == []
        assert hal.pin_value(hal.find_pin("spindle.0.at-speed")[1]) == 1  # default TRUE
    finally:
        hal.close()


def test_a_signal_linked_while_running_gets_the_value_of_its_new_writer(machine: Task) -> None:
    """Pins that seldom change are written when they change, and all of them again after a
    HAL edit: a signal whose reader came first (postgui files link such signals while the
    servo thread runs) must still show motion's value."""
    configure(machine)
    assert machine.send(emc.EMC_TRAJ_ENABLE()).status == RCS_STATUS.DONE
    assert settled_pin("motion.motion-enabled", 1) == 1
    for command in (
        "net late-enable => joint.0.home-sw-in",  # the reader first: the signal stays FALSE
        "net late-enable motion.motion-enabled",
        "net late-spindle-brake => joint.1.home-sw-in",
        "net late-spindle-brake spindle.0.brake",
    ):
        linked = run_cnc("halcmd", *command.split())
        assert linked.returncode == 0, linked.stderr
    assert settled_pin("joint.0.home-sw-in", 1) == 1
    assert settled_pin("joint.1.home-sw-in", 1) == 1  # (brake on while the spindle is off)


def homed_in_coord_mode(task: Task) -> None:
    configure(task)
    assert task.send(emc.EMC_TRAJ_ENABLE()).status == RCS_STATUS.DONE
    assert task.send(emc.EMC_JOINT_HOME(joint=-1)).status == RCS_STATUS.DONE
    task.wait_for(lambda s: all(s.joint[i].homed for i in range(3)) and s.traj.inpos)
    coord = emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD)
    assert task.send(coord).status == RCS_STATUS.DONE


def errors_seen(task: Task, count: int, timeout: float = 10) -> list[str]:
    deadline = time.monotonic() + timeout
    errors: list[str] = []
    while len(errors) < count and time.monotonic() < deadline:
        errors += task.errors()
        time.sleep(0.01)
    return errors


def test_an_arc_beyond_floating_point_is_refused_and_motion_goes_on(machine: Task) -> None:
    """Finite fields whose path is not (a centre at 1e300): refused with the reason, and the
    servo thread keeps running (it raised inside the planner's period before)."""
    homed_in_coord_mode(machine)
    machine.errors()
    arc = emc.EMC_TRAJ_CIRCULAR_MOVE(type=emc.EMC_MOTION_TYPE.ARC, vel=10.0, ini_maxvel=30.0)
    arc.acc = 500.0
    arc.end.tran.x = 1.0
    arc.center.x, arc.normal.z = -1e300, 1.0
    assert machine.send(arc).status == RCS_STATUS.ERROR
    assert errors_seen(machine, 1) == [
        "EMC_TRAJ_CIRCULAR_MOVE: the path is out of range (its length or end is not finite)"
    ]
    assert machine.send(emc.EMC_TRAJ_ABORT()).status == RCS_STATUS.DONE
    move = emc.EMC_TRAJ_LINEAR_MOVE(type=emc.EMC_MOTION_TYPE.FEED, vel=20.0, ini_maxvel=30.0)
    move.acc = 500.0
    move.end.tran.x = 2.0
    assert machine.send(move).status == RCS_STATUS.DONE
    stat = machine.wait_for(lambda s: s.traj.inpos and s.traj.position.tran.x > 1.99)
    assert stat.traj.position.tran.x == pytest.approx(2.0)
    assert stat.traj.enabled


def test_a_drive_sending_nan_feedback_stops_motion_with_its_pin_named(machine: Task) -> None:
    homed_in_coord_mode(machine)
    machine.errors()
    broken = run_cnc("halcmd", "unlinkp", "joint.1.motor-pos-fb")
    assert broken.returncode == 0, broken.stderr
    set_nan = run_cnc("halcmd", "setp", "joint.1.motor-pos-fb", "nan")
    assert set_nan.returncode == 0, set_nan.stderr
    stat = machine.wait_for(lambda s: not s.traj.enabled)
    assert errors_seen(machine, 1) == ["joint 1 position feedback is nan (joint.1.motor-pos-fb)"]
    assert math.isfinite(stat.joint[1].output)  # the command held where it was
    assert math.isfinite(pin("joint.1.motor-pos-cmd"))


def test_an_exception_inside_the_controller_turns_motion_off_and_says_so_once(monkeypatch) -> None:
    """A bug the tests missed must not leave the machine deaf: the host disables a function
    that raises, so motmod catches it, turns motion off and says so (once, though it recurs
    every period), and goes on answering commands."""
    task = Task()  # (the NML buffers' master)
    hal = Hal()
    host = Host(hal, is_rt=False)
    try:
        host.loadrt("trivkins", ["coordinates=XYZ"])
        host.loadrt("motmod", ["servo_period_nsec=1000000", "num_joints=3"])
        host.stop_thread("servo-thread")  # this test runs motion's functions itself
        motmod, period = host.motmod, 1_000_000
        task.task[MOTION_COMMAND].write(emc.EMC_TRAJ_ENABLE())
        motmod.command_handler(period)
        assert motmod.controller.is_enabled

        def broken(*_args: object) -> None:
            raise ZeroDivisionError("float division by zero")

        monkeypatch.setattr(motmod.controller, "update", broken)
        for _ in range(5):
            motmod.controller_period(period)
        assert not motmod.controller.is_enabled
        assert task.errors() == [
            "motion: internal error in a servo period: ZeroDivisionError: float division by "
            "zero; motion is off"
        ]
        monkeypatch.setattr(motmod.controller, "handle", broken)
        serial = task.task[MOTION_COMMAND].write(emc.EMC_TRAJ_ENABLE())
        motmod.command_handler(period)
        motmod.controller_period(period)
        assert motmod.status.echo_serial_number == serial
        assert motmod.status.status == RCS_STATUS.ERROR
        assert task.errors() == [
            "motion: internal error in EMC_TRAJ_ENABLE: ZeroDivisionError: float division by "
            "zero; motion is off"
        ]
    finally:
        host.unload_all()
        hal.destroy()
        task.close()


def test_the_status_carries_the_external_offsets_task_takes_out(
    machine_with_z_offsets: Task,
) -> None:
    machine = machine_with_z_offsets
    configure(machine)
    assert machine.send(emc.EMC_TRAJ_ENABLE()).status == RCS_STATUS.DONE
    assert machine.send(emc.EMC_JOINT_HOME(joint=-1)).status == RCS_STATUS.DONE
    machine.wait_for(lambda s: all(s.joint[i].homed for i in range(3)) and s.traj.inpos)
    coord = emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD)
    assert machine.send(coord).status == RCS_STATUS.DONE
    for name, value in (("enable", "1"), ("scale", "0.5"), ("counts", "-8")):
        assert run_cnc("halcmd", "setp", f"axis.z.eoffset-{name}", value).returncode == 0
    stat = machine.wait_for(
        lambda s: s.external_offsets_applied and s.eoffset_pose.tran.z == pytest.approx(-4.0)
    )
    assert stat.eoffset_pose.values() == pytest.approx((0, 0, -4.0, 0, 0, 0, 0, 0, 0))
    assert stat.traj.position.tran.z == pytest.approx(-4.0)  # (with it: task takes it out)


def test_every_axis_has_its_pins_as_in_linuxcnc(machine: Task) -> None:
    """An XYZ machine still has axis.a.* ... axis.w.* (LinuxCNC 2.9 makes all nine; HAL
    files such as xhc-hb04.tcl set them), idle."""
    for letter in "abcuvw":
        assert pin(f"axis.{letter}.jog-accel-fraction") == 1.0
        assert pin(f"axis.{letter}.pos-cmd") == 0.0
