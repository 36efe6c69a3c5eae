"""The ready-to-run simulated machines of configs/sim/ (CFG-*, issue 6 "Configs").

Every INI file parses and has what the launcher reads, with joints and axes consistent with
its kinematics; its tool table, parameter file and example programs load; and its HAL files
run in a real realtime host (with ``[SECTION]KEY`` taken from the INI file, iocontrol's pins
present as when the launcher runs them), leaving the nets a LinuxCNC user expects.
"""

from __future__ import annotations

import math
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from cnc.ini import IniFile
from hal.api import component
from hal.core import HAL_IN, Hal
from hal.halcmd import HalCmd, run_ini_halfiles
from hal.hallib import find_halfile
from iocontrol.controller import PINS as IOCONTROL_PINS
from iocontrol.tooltable import ToolTable
from nml import emc
from nml.channels import (
    EMC_ERROR,
    MOTION_COMMAND,
    MOTION_STATUS,
    TOOL_COMMAND,
    TOOL_STATUS,
    Nml,
    load_config,
)
from nml.message import RCS_STATUS
from tests.hal.halrun_util import REPO, run_cnc

SIM = REPO / "configs" / "sim"
CONFIGS = ["mill", "mill_switches", "mill_inch", "lathe", "gantry", "corexy", "random_tc"]
# machines with simulated hardware (a Mesa card, a VFD): tests/hw/test_mesa_sim_e2e.py
HARDWARE_SIMS = ["mesa_7i96s"]
# a machine for motion's features (locking indexer, extra joint, external offsets), its own
# end-to-end test: tests/configs/test_features_e2e.py
FEATURE_SIMS = ["features"]
MILL_PROGRAMS = ["pocket.ngc", "drill.ngc", "toolchange.ngc"]
PROGRAMS = {name: MILL_PROGRAMS for name in CONFIGS} | {"lathe": ["lathe_turn.ngc"]}
# LinuxCNC's persistent parameters: G28 and G30 homes, G92, the nine coordinate systems.
REQUIRED_PARAMETERS = [*range(5161, 5170), *range(5181, 5190), *range(5210, 5221)] + [
    n for base in range(5221, 5390, 20) for n in range(base, base + 10)
]
# Those holding lengths: X Y Z and U V W of G28, G30, G92 and each coordinate system.
LENGTH_PARAMETERS = {
    base + offset
    for base in (5161, 5181, 5211, *range(5221, 5390, 20))
    for offset in (0, 1, 2, 6, 7, 8)
}
NML_BUFFERS = (MOTION_COMMAND, MOTION_STATUS, EMC_ERROR, TOOL_COMMAND, TOOL_STATUS)
WAIT_S = 10.0  # how long a HAL value may take to follow (generous: loaded CI machines)


def load(name: str) -> IniFile:
    return IniFile.load(SIM / f"{name}.ini")


def letters(ini: IniFile) -> str:
    return (ini.find("TRAJ", "COORDINATES") or "").replace(" ", "").upper()


def joints(ini: IniFile) -> int:
    value = ini.get_int("KINS", "JOINTS")
    assert value is not None
    return value


def joint_float(ini: IniFile, joint: int, key: str) -> float:
    value = ini.get_float(f"JOINT_{joint}", key)
    assert value is not None, f"[JOINT_{joint}]{key} missing"
    return value


# --------------------------------------------------------------------------- the INI files
def test_the_sim_folder_holds_the_advertised_machines() -> None:
    advertised = CONFIGS + HARDWARE_SIMS + FEATURE_SIMS
    assert sorted(p.stem for p in SIM.glob("*.ini")) == sorted(advertised)
    readme = (SIM / "README.md").read_text()
    for name in advertised:
        assert f"{name}.ini" in readme


@pytest.mark.parametrize("name", CONFIGS)
def test_ini_has_every_key_the_launcher_reads(name: str) -> None:
    ini = load(name)
    for section, key in [
        ("EMC", "MACHINE"),
        ("KINS", "KINEMATICS"),
        ("KINS", "JOINTS"),
        ("EMCMOT", "EMCMOT"),
        ("EMCMOT", "SERVO_PERIOD"),
        ("EMCMOT", "BASE_PERIOD"),
        ("EMCIO", "EMCIO"),
        ("EMCIO", "TOOL_TABLE"),
        ("EMCIO", "CYCLE_TIME"),
        ("TASK", "TASK"),
        ("TASK", "CYCLE_TIME"),
        ("RS274NGC", "PARAMETER_FILE"),
        ("RS274NGC", "SUBROUTINE_PATH"),
        ("TRAJ", "COORDINATES"),
        ("TRAJ", "LINEAR_UNITS"),
        ("TRAJ", "ANGULAR_UNITS"),
        ("TRAJ", "SPINDLES"),
        ("TRAJ", "MAX_LINEAR_VELOCITY"),
        ("DISPLAY", "DISPLAY"),
        ("DISPLAY", "PROGRAM_PREFIX"),
    ]:
        assert ini.find(section, key), f"{name}.ini: [{section}]{key} missing or empty"
    assert ini.find("EMCMOT", "EMCMOT") == "motmod"
    assert ini.find("EMCIO", "EMCIO") == "io"
    assert ini.find("DISPLAY", "DISPLAY") == "top"
    assert ini.find("TRAJ", "LINEAR_UNITS") in ("mm", "inch")
    assert ini.get_int("EMCMOT", "SERVO_PERIOD") == 1_000_000
    assert ini.get_int("EMCMOT", "BASE_PERIOD") == 0
    assert ini.get_int("TRAJ", "SPINDLES") == 1
    assert 0 < (ini.get_float("TASK", "CYCLE_TIME") or 0) <= 0.01
    assert (ini.get_float("TRAJ", "DEFAULT_LINEAR_VELOCITY") or 0) <= (
        ini.get_float("TRAJ", "MAX_LINEAR_VELOCITY") or 0
    )
    # the files it names exist, relative to the INI file's folder as in LinuxCNC
    halfiles = ini.findall("HAL", "HALFILE")
    assert halfiles
    for value in halfiles:
        assert find_halfile(value, SIM).path.parent == SIM
    for section, key in [("EMCIO", "TOOL_TABLE"), ("RS274NGC", "PARAMETER_FILE")]:
        assert (SIM / ini.require(section, key)).is_file()
    for section, key in [("RS274NGC", "SUBROUTINE_PATH"), ("DISPLAY", "PROGRAM_PREFIX")]:
        assert (SIM / ini.require(section, key)).is_dir()


@pytest.mark.parametrize("name", CONFIGS)
def test_joints_and_axes_agree_with_the_kinematics(name: str) -> None:
    ini = load(name)
    count, coords = joints(ini), letters(ini)
    assert sorted(s for s in ini.sections() if s.startswith("JOINT_")) == sorted(
        f"JOINT_{n}" for n in range(count)
    )
    assert {s[5:] for s in ini.sections() if s.startswith("AXIS_")} == set(coords)
    module, *args = ini.require("KINS", "KINEMATICS").split()
    options = dict(arg.split("=", 1) for arg in args)
    if module == "trivkins":
        mapped = options.get("coordinates", "XYZABCUVW").upper()
        assert mapped == coords and len(mapped) == count
        for joint, letter in enumerate(mapped):  # a joint covers its axis's whole range
            assert joint_float(ini, joint, "MIN_LIMIT") <= ini.get_float(
                f"AXIS_{letter}", "MIN_LIMIT"
            )
            assert joint_float(ini, joint, "MAX_LIMIT") >= ini.get_float(
                f"AXIS_{letter}", "MAX_LIMIT"
            )
    else:
        assert module == "corexykins" and coords == "XYZ" and count == 3
    for letter in set(coords):
        section = f"AXIS_{letter}"
        assert ini.get_float(section, "MIN_LIMIT") < ini.get_float(section, "MAX_LIMIT")
        assert ini.get_float(section, "MAX_VELOCITY") > 0
        assert ini.get_float(section, "MAX_ACCELERATION") > 0
    for joint in range(count):
        low, high = joint_float(ini, joint, "MIN_LIMIT"), joint_float(ini, joint, "MAX_LIMIT")
        assert low <= joint_float(ini, joint, "HOME") <= high
        assert ini.find(f"JOINT_{joint}", "TYPE") == "LINEAR"
        max_vel = joint_float(ini, joint, "MAX_VELOCITY")
        assert max_vel > 0 and joint_float(ini, joint, "MAX_ACCELERATION") > 0
        assert abs(joint_float(ini, joint, "HOME_SEARCH_VEL")) <= max_vel
        assert 0 < joint_float(ini, joint, "MIN_FERROR") <= joint_float(ini, joint, "FERROR")


@pytest.mark.parametrize("name", CONFIGS)
def test_home_sequences_are_contiguous_from_zero(name: str) -> None:
    """LinuxCNC's rule: |HOME_SEQUENCE| values 0, 1, 2, ... without gaps."""
    ini = load(name)
    sequences = [int(joint_float(ini, j, "HOME_SEQUENCE")) for j in range(joints(ini))]
    steps = sorted({abs(s) for s in sequences})
    assert steps == list(range(len(steps)))


def test_mill_homes_in_place_and_mill_switches_is_the_same_machine_with_switches() -> None:
    mill, switches = load("mill"), load("mill_switches")
    for joint in range(3):
        assert joint_float(mill, joint, "HOME_SEARCH_VEL") == 0
        assert joint_float(mill, joint, "HOME_LATCH_VEL") == 0
        for key in ("MIN_LIMIT", "MAX_LIMIT", "MAX_VELOCITY", "MAX_ACCELERATION"):
            assert joint_float(mill, joint, key) == joint_float(switches, joint, key)
    assert "home_switches.hal" not in mill.findall("HAL", "HALFILE")
    assert "mill_switches.ini" in (SIM / "mill.ini").read_text()
    assert mill.findall("HAL", "HALFILE") == [
        f for f in switches.findall("HAL", "HALFILE") if f != "home_switches.hal"
    ]


@pytest.mark.parametrize("name", [n for n in CONFIGS if n != "mill"])
def test_switch_homing_searches_towards_its_simulated_switch(name: str) -> None:
    ini = load(name)
    for joint in range(joints(ini)):
        search = joint_float(ini, joint, "HOME_SEARCH_VEL")
        latch = joint_float(ini, joint, "HOME_LATCH_VEL")
        switch = joint_float(ini, joint, "SIM_HOME_SWITCH_POS")
        assert search != 0 and latch != 0
        assert abs(latch) < abs(search)
        # the switch is open at power-on (motor at 0) and lies in the search direction
        assert math.copysign(1, switch) == math.copysign(1, search)
        assert abs(switch) > joint_float(ini, joint, "SIM_HOME_SWITCH_HYST") > 0


def test_gantry_homes_both_y_joints_together() -> None:
    ini = load("gantry")
    assert ini.require("KINS", "KINEMATICS") == "trivkins coordinates=XYYZ kinstype=BOTH"
    y_joints = [j for j, letter in enumerate(letters(ini)) if letter == "Y"]
    assert y_joints == [1, 2]
    sequences = {int(joint_float(ini, j, "HOME_SEQUENCE")) for j in y_joints}
    assert len(sequences) == 1 and sequences.pop() < 0
    # the two sides start racked: their switches are not at the same motor position
    positions = {joint_float(ini, j, "SIM_HOME_SWITCH_POS") for j in y_joints}
    assert len(positions) == 2


def test_lathe_is_an_xz_lathe_in_diameter_mode() -> None:
    ini = load("lathe")
    assert ini.get_bool("DISPLAY", "LATHE") is True
    assert letters(ini) == "XZ"
    assert {"G18", "G7"} <= set(ini.require("RS274NGC", "RS274NGC_STARTUP_CODE").split())
    table = ToolTable()
    table.load(SIM / ini.require("EMCIO", "TOOL_TABLE"))
    orientations = [e.orientation for i, e in table.entries.items() if i > 0]
    assert orientations and all(1 <= q <= 9 for q in orientations)


def test_random_toolchanger_config() -> None:
    ini = load("random_tc")
    assert ini.get_bool("EMCIO", "RANDOM_TOOLCHANGER") is True
    assert len(ini.require("EMCIO", "TOOL_CHANGE_POSITION").split()) == len(letters(ini))
    table = ToolTable(random_toolchanger=True)
    table.load(SIM / ini.require("EMCIO", "TOOL_TABLE"))
    assert table.entries[0].toolno == 0  # the spindle starts empty
    pockets = [i for i in table.entries if i > 0]
    assert pockets != list(range(1, len(pockets) + 1))  # pockets are not simply 1..n


# ----------------------------------------------------------- tool tables, parameters, programs
@pytest.mark.parametrize("name", CONFIGS)
def test_tool_table_loads_and_holds_the_tools_of_the_example_programs(name: str) -> None:
    ini = load(name)
    table = ToolTable(random_toolchanger=bool(ini.get_bool("EMCIO", "RANDOM_TOOLCHANGER", False)))
    table.load(SIM / ini.require("EMCIO", "TOOL_TABLE"))  # strict: any bad line fails
    tools = {entry.toolno for entry in table.entries.values()}
    needed = set()
    for program in PROGRAMS[name]:
        needed |= {
            int(t) for t in re.findall(r"\bT(\d+)\s*M6", (SIM / "nc_files" / program).read_text())
        }
    assert needed and needed <= tools


@pytest.mark.parametrize("name", CONFIGS)
def test_parameter_file_has_linuxcncs_persistent_parameters(name: str) -> None:
    ini = load(name)
    values = {}
    for line in (SIM / ini.require("RS274NGC", "PARAMETER_FILE")).read_text().splitlines():
        number, value = line.split("\t")
        values[int(number)] = float(value)
    assert list(values) == sorted(values)
    assert set(REQUIRED_PARAMETERS) <= set(values)
    assert values[5220] == 1.0  # G54 active


def _machine_positions(output: str, units_per_mm: float) -> Iterator[tuple[float, float, float]]:
    """X, Y, Z in machine units of every straight move of ``cnc rs274`` output: program
    position plus work offsets (G5x, G92) plus tool offset, as task's canon adds them."""
    g5x = g92 = tool = (0.0, 0.0, 0.0)
    scale = units_per_mm
    num = r"(-?[\d.]+)"
    for line in output.splitlines():
        if "USE_LENGTH_UNITS" in line:
            scale = units_per_mm if "MM" in line else units_per_mm * 25.4
        elif found := re.search(rf"SET_G5X_OFFSET\(\d+, {num}, {num}, {num}", line):
            g5x = tuple(float(v) for v in found.groups())
        elif found := re.search(rf"SET_G92_OFFSET\({num}, {num}, {num}", line):
            g92 = tuple(float(v) for v in found.groups())
        elif found := re.search(rf"USE_TOOL_LENGTH_OFFSET\({num} {num} {num}", line):
            tool = tuple(float(v) for v in found.groups())
        elif found := re.search(rf"STRAIGHT_(?:FEED|TRAVERSE)\({num}, {num}, {num}", line):
            yield tuple(  # type: ignore[misc]
                (float(v) + a + b + c) * scale
                for v, a, b, c in zip(found.groups(), g5x, g92, tool, strict=True)
            )


def _inch_copies(ini: IniFile, folder: Path) -> tuple[Path, Path]:
    """The parameter file and tool table for standalone rs274, which, like LinuxCNC's, takes
    their lengths as inches: a millimetre machine's values are converted."""
    is_mm = ini.find("TRAJ", "LINEAR_UNITS") == "mm"
    factor = 1 / 25.4 if is_mm else 1.0
    var = folder / "params.var"  # also: the interpreter rewrites its parameter file
    lines = (SIM / ini.require("RS274NGC", "PARAMETER_FILE")).read_text().splitlines()
    converted = []
    for line in lines:
        number, value = line.split("\t")
        scale = factor if int(number) in LENGTH_PARAMETERS else 1.0
        converted.append(f"{number}\t{float(value) * scale:.6f}")
    var.write_text("\n".join(converted) + "\n")
    tools = ToolTable(random_toolchanger=bool(ini.get_bool("EMCIO", "RANDOM_TOOLCHANGER", False)))
    tools.load(SIM / ini.require("EMCIO", "TOOL_TABLE"))
    for entry in tools.entries.values():
        entry.offset = [v * factor for v in entry.offset]
        entry.diameter *= factor
    table = folder / "tools.tbl"
    tools.save(table)
    return var, table


@pytest.mark.parametrize(
    ("name", "program"), [(name, p) for name in CONFIGS for p in PROGRAMS[name]]
)
def test_example_program_runs_in_the_interpreter_within_the_machine_limits(
    name: str, program: str, tmp_path: Path
) -> None:
    ini = load(name)
    var, table = _inch_copies(ini, tmp_path)
    result = subprocess.run(
        [sys.executable, "-m", "cnc", "rs274", "-g", "-i", f"{name}.ini", "-t", str(table),
         "-v", str(var), f"nc_files/{program}"],
        capture_output=True, text=True, cwd=SIM, timeout=60,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "CHANGE_TOOL" in result.stdout
    units_per_mm = 1.0 if ini.find("TRAJ", "LINEAR_UNITS") == "mm" else 1 / 25.4
    positions = list(_machine_positions(result.stdout, units_per_mm))
    assert positions
    for letter in set(letters(ini)):
        index = "XYZ".index(letter)
        low = ini.get_float(f"AXIS_{letter}", "MIN_LIMIT")
        high = ini.get_float(f"AXIS_{letter}", "MAX_LIMIT")
        values = [p[index] for p in positions]
        assert low <= min(values) and max(values) <= high, letter


# ------------------------------------------------------------------ the HAL files, for real
class Machine:
    """A realtime host with the NML buffers and iocontrol's pins, as the launcher makes them:
    iocontrol is the real process when ``io_ini`` is given, else a stand-in component."""

    def __init__(self, procs, io_ini: Path | None = None) -> None:  # type: ignore[no-untyped-def]
        config = load_config()
        self.nml = Nml(config, "cnc", [*NML_BUFFERS])
        self.task: Nml | None = None
        self.host = None
        self.hal: Hal | None = None
        self.io = None
        self.io_proc = None
        try:
            self.host = procs.python("-m", "hal.rtapi_app", "--no-rt")
            assert self.host.stdout.readline().strip() == "rtapi_app: ready"
            self.hal = Hal()
            # iocontrol runs before the HAL files, so they can connect its pins
            if io_ini is None:
                self.io = component("iocontrol", prefix="iocontrol.0", hal=self.hal)
                for pin_name, hal_type, direction in IOCONTROL_PINS:
                    self.io.newpin(pin_name, hal_type, direction)
                self.io.ready()
            else:
                self.task = Nml(config, "emc", [TOOL_COMMAND, TOOL_STATUS])
                self.io_proc = procs.python("-m", "iocontrol", "-ini", str(io_ini))
                self.wait(lambda: self.hal.meta["comps"].get("iocontrol", {}).get("is_ready"))
        except BaseException:
            self.close()
            raise

    def wait(self, condition) -> None:  # type: ignore[no-untyped-def]
        deadline = time.monotonic() + WAIT_S
        while not condition():
            if self.io_proc is not None:
                assert self.io_proc.poll() is None, self.io_proc.communicate()[1]
            assert time.monotonic() < deadline, "condition never met"
            time.sleep(0.005)

    def run_halfiles(self, ini: Path, capsys: pytest.CaptureFixture[str]) -> None:
        failures = run_ini_halfiles(str(ini))
        assert failures == 0, capsys.readouterr().err
        assert self.hal is not None
        assert HalCmd(self.hal).run_words(["start"])

    def pin(self, name: str) -> dict:
        assert self.hal is not None
        found = self.hal.find_pin(name)
        assert found is not None, f"no pin {name}"
        return found[1]

    def value(self, name: str) -> float:
        assert self.hal is not None
        return self.hal.pin_value(self.pin(name))

    def writer(self, signal_name: str | None) -> str | None:
        """The pin driving a signal (an OUT or IO pin), or None."""
        assert self.hal is not None
        if signal_name is None:
            return None
        for name, pin in self.hal.meta["pins"].items():
            if pin["sig"] == signal_name and pin["dir"] != HAL_IN:
                return name
        return None

    def driver_of(self, pin_name: str) -> str | None:
        return self.writer(self.pin(pin_name)["sig"])

    def wait_for(self, pin_name: str, expected: float) -> float:
        deadline = time.monotonic() + WAIT_S
        value = self.value(pin_name)
        while value != expected and time.monotonic() < deadline:
            time.sleep(0.005)
            value = self.value(pin_name)
        return value

    def io_command(self, msg: emc.RCS_CMD_MSG) -> emc.EMC_IO_STAT:
        """Send a command to iocontrol as task does; its status once it is no longer EXEC."""
        assert self.task is not None
        serial = self.task[TOOL_COMMAND].write(msg)
        found: list[emc.EMC_IO_STAT] = []

        def is_finished() -> bool:
            st = self.task[TOOL_STATUS].peek()  # type: ignore[index]
            found[:] = [st]
            return (
                st is not None
                and st.echo_serial_number == serial
                and (st.status != RCS_STATUS.EXEC)
            )

        self.wait(is_finished)
        return found[0]

    def close(self) -> None:
        if self.io is not None:
            self.io.exit()
        if self.io_proc is not None and self.io_proc.poll() is None:
            self.io_proc.send_signal(signal.SIGTERM)
            self.io_proc.wait(timeout=10)
        if self.host is not None and self.host.poll() is None:
            run_cnc("halcmd", "unload", "all")
            self.host.send_signal(signal.SIGTERM)
            self.host.wait(timeout=10)
        if self.hal is not None:
            self.hal.close()
        if self.task is not None:
            self.task.close()
        self.nml.close()


@pytest.fixture
def machine(procs) -> Iterator[Machine]:  # type: ignore[no-untyped-def]
    running = Machine(procs)
    try:
        yield running
    finally:
        running.close()


@pytest.mark.parametrize("name", CONFIGS)
def test_hal_files_load_and_wire_the_machine(
    name: str, machine: Machine, capsys: pytest.CaptureFixture[str]
) -> None:
    ini = load(name)
    machine.run_halfiles(SIM / f"{name}.ini", capsys)
    assert machine.hal is not None
    meta = machine.hal.meta
    # the servo thread runs motion first, then every function that was loaded
    chain = meta["threads"]["servo-thread"]["functs"]
    assert chain[:2] == ["motion-command-handler", "motion-controller"]
    assert meta["threads"]["servo-thread"]["period"] == ini.get_int("EMCMOT", "SERVO_PERIOD")
    assert "base-thread" not in meta["threads"]
    assert [f for f, info in meta["functs"].items() if not info["users"]] == []
    # each joint: the command comes back as the feedback (a perfect servo)
    count = joints(ini)
    assert f"joint.{count}.motor-pos-cmd" not in meta["pins"]
    for joint in range(count):
        assert machine.driver_of(f"joint.{joint}.motor-pos-fb") == f"joint.{joint}.motor-pos-cmd"
        switch = machine.driver_of(f"joint.{joint}.home-sw-in")
        if name == "mill":
            assert switch is None
        else:  # a simulated switch watching this joint's motor, open at power-on
            assert switch is not None and switch.endswith(".home-sw")
            watched = machine.pin(switch.replace(".home-sw", ".cur-pos"))["sig"]
            assert machine.writer(watched) == f"joint.{joint}.motor-pos-cmd"
            assert machine.value(f"joint.{joint}.home-sw-in") == 0
    # spindle: speed and at-speed fed back; at-speed rises once the servo thread runs
    assert machine.driver_of("spindle.0.speed-in") is not None
    assert machine.driver_of("spindle.0.at-speed") is not None
    assert machine.wait_for("spindle.0.at-speed", 1) == 1
    # iocontrol: E-stop loop, coolant outputs and the tool changer handshake
    assert machine.driver_of("iocontrol.0.emc-enable-in") == "iocontrol.0.user-enable-out"
    for output in ("coolant-flood", "coolant-mist", "lube", "tool-number"):
        assert machine.pin(f"iocontrol.0.{output}")["sig"] is not None
    assert machine.io is not None
    for request, answer in (("tool-prepare", "tool-prepared"), ("tool-change", "tool-changed")):
        assert machine.value(f"iocontrol.0.{answer}") == 0
        machine.io[request] = 1
        assert machine.wait_for(f"iocontrol.0.{answer}", 1) == 1
        machine.io[request] = 0
        assert machine.wait_for(f"iocontrol.0.{answer}", 0) == 0


def test_gantry_y_motors_have_their_own_feedback_and_switches(
    machine: Machine, capsys: pytest.CaptureFixture[str]
) -> None:
    machine.run_halfiles(SIM / "gantry.ini", capsys)
    y_switches = {machine.driver_of(f"joint.{j}.home-sw-in") for j in (1, 2)}
    assert len(y_switches) == 2
    feedback = {machine.pin(f"joint.{j}.motor-pos-fb")["sig"] for j in (1, 2)}
    assert len(feedback) == 2
    # the simulated switch closes when its motor reaches the INI position
    ini = load("gantry")
    switch = machine.driver_of("joint.2.home-sw-in")
    assert switch is not None
    assert machine.value(switch.replace(".home-sw", ".home-pos")) == joint_float(
        ini, 2, "SIM_HOME_SWITCH_POS"
    )


@pytest.mark.parametrize(("name", "tool", "pocket"), [("mill", 3, 3), ("random_tc", 3, 5)])
def test_real_iocontrol_changes_tools_and_resets_estop_through_the_hal_files(
    name: str,
    tool: int,
    pocket: int,
    procs,
    tmp_path: Path,
    capsys,  # type: ignore[no-untyped-def]
) -> None:
    """The launcher's order: iocontrol first, then the HAL files; then the E-stop loop and the
    changer (loop-back or simulated carousel) answer iocontrol's handshakes."""
    folder = tmp_path / "sim"
    shutil.copytree(SIM, folder)  # iocontrol rewrites its tool table
    running = Machine(procs, io_ini=folder / f"{name}.ini")
    try:
        running.run_halfiles(folder / f"{name}.ini", capsys)
        assert running.io_command(emc.EMC_AUX_ESTOP_OFF()).status == RCS_STATUS.DONE
        running.wait(lambda: running.task[TOOL_STATUS].peek().aux.estop == 0)  # type: ignore[index]
        st = running.io_command(emc.EMC_TOOL_PREPARE(tool=tool))
        assert st.status == RCS_STATUS.DONE and st.tool.pocketPrepped == pocket
        st = running.io_command(emc.EMC_TOOL_LOAD())
        assert st.status == RCS_STATUS.DONE and st.tool.toolInSpindle == tool
        assert running.value("iocontrol.0.tool-number") == tool
        st = running.io_command(emc.EMC_COOLANT_FLOOD_ON())
        assert st.coolant.flood == 1 and running.value("iocontrol.0.coolant-flood") == 1
    finally:
        running.close()
