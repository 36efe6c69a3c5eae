"""``python -m iocontrol`` as a real process on real NML buffers and a real HAL (IO-001..019).

The test plays task (commands on toolCmd as process ``emc``, status from toolSts) and the
machine's HAL (setp / net on ``iocontrol.0.*``), like a tool changer or an e-stop latch would.
"""

from __future__ import annotations

import contextlib
import random
import signal
import subprocess
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from hal.core import HAL_BIT, HAL_IN, HAL_OUT, HAL_S32, Hal
from hal.halcmd import HalCmd
from iocontrol.tooldata import ToolDataError, read_tool_data
from iocontrol.tooltable import ToolTable
from nml import emc
from nml.channels import EMC_ERROR, TOOL_COMMAND, TOOL_STATUS, Nml, is_io_type, load_config
from nml.message import RCS_CMD_MSG, RCS_STATUS, MessageKind, i32
from nml.registry import REGISTRY
from tests.conftest import Processes

WAIT_S = 10.0
NONRANDOM_TABLE = "T1 P1 Z0.5 ;one\nT2 P7 Z1.0 D3 ;two\n"
RANDOM_TABLE = "T5 P0 Z5.0 ;five\nT1 P1 Z0.5 ;one\nT2 P2 Z1.0 ;two\n"


class EMC_IO_TEST_UNKNOWN(RCS_CMD_MSG, type_id=1650):
    """A command only this test knows: iocontrol cannot decode it."""

    value: i32


@dataclass
class Machine:
    hal: Hal
    cmd: HalCmd
    task: Nml  # process "emc": writes toolCmd, reads toolSts
    ui: Nml  # process "xemc": reads emcError (a broadcast queue)
    proc: subprocess.Popen[str]
    table: Path

    def send(self, msg: emc.RCS_CMD_MSG) -> int:
        return self.task[TOOL_COMMAND].write(msg)

    def status(self) -> emc.EMC_IO_STAT:
        st = self.task[TOOL_STATUS].peek()
        assert isinstance(st, emc.EMC_IO_STAT)
        return st

    def wait_status(self, is_wanted: Callable[[emc.EMC_IO_STAT], bool]) -> emc.EMC_IO_STAT:
        deadline = time.monotonic() + WAIT_S
        while True:
            st = self.status()
            if is_wanted(st):
                return st
            assert self.proc.poll() is None, self.proc.communicate()[1]
            assert time.monotonic() < deadline, f"status never matched: {st}"
            time.sleep(0.001)

    def wait_ack(self, serial: int) -> emc.EMC_IO_STAT:
        """The first status that echoes ``serial`` (EXEC, DONE or ERROR)."""
        return self.wait_status(lambda st: st.echo_serial_number == serial)

    def run(self, msg: emc.RCS_CMD_MSG) -> emc.EMC_IO_STAT:
        """Send a command and wait until it is no longer executing."""
        serial = self.send(msg)
        return self.wait_status(
            lambda st: st.echo_serial_number == serial and st.status != RCS_STATUS.EXEC
        )

    def pin(self, name: str) -> int | float:
        found = self.hal.find_pin(f"iocontrol.0.{name}")
        assert found is not None, name
        return self.hal.pin_value(found[1])

    def hal_do(self, *words: str) -> None:
        assert self.cmd.run_words(list(words)), words

    def setp(self, name: str, value: object) -> None:
        self.hal_do("setp", f"iocontrol.0.{name}", str(value))

    def wait_pin(self, name: str, value: object) -> None:
        deadline = time.monotonic() + WAIT_S
        while self.pin(name) != value:
            assert time.monotonic() < deadline, f"{name} never became {value}"
            time.sleep(0.001)

    def errors(self) -> list[str]:
        found = []
        while (msg := self.ui[EMC_ERROR].read()) is not None:
            found.append(msg.error)
        return found


def write_config(folder: Path, table_text: str, *, is_random: bool = False) -> Path:
    (folder / "tools.tbl").write_text(table_text)
    ini = folder / "machine.ini"
    ini.write_text(
        "[EMCIO]\nEMCIO = io\nCYCLE_TIME = 0.5\nTOOL_TABLE = tools.tbl\n"
        f"RANDOM_TOOLCHANGER = {int(is_random)}\n"
    )
    return ini


def start(procs: Processes, hal: Hal, ini: Path) -> subprocess.Popen[str]:
    proc = procs.python("-m", "iocontrol", "-ini", str(ini))
    deadline = time.monotonic() + WAIT_S
    while (
        hal.meta["comps"].get("iocontrol", {}).get("pid") != proc.pid
        or not (hal.meta["comps"]["iocontrol"]["is_ready"])
    ):
        assert proc.poll() is None, proc.communicate()[1]
        assert time.monotonic() < deadline, "iocontrol never became ready"
        time.sleep(0.01)
    return proc


def stop(proc: subprocess.Popen[str]) -> tuple[int, str]:
    """SIGTERM, as the launcher sends it; SIGKILL if it does not exit (then the test fails)."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
    try:
        _, err = proc.communicate(timeout=WAIT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        err += "\n(did not exit on SIGTERM)"
    return proc.returncode, err


@pytest.fixture
def machine_factory(procs: Processes, tmp_path: Path) -> Iterator[Callable[..., Machine]]:
    hal = Hal()
    config = load_config()
    master = Nml(config, "cnc", [TOOL_COMMAND, TOOL_STATUS, EMC_ERROR])
    task = Nml(config, "emc", [TOOL_COMMAND, TOOL_STATUS])
    ui = Nml(config, "xemc", [EMC_ERROR])
    started: list[subprocess.Popen[str]] = []

    def make(table_text: str = NONRANDOM_TABLE, *, is_random: bool = False) -> Machine:
        ini = write_config(tmp_path, table_text, is_random=is_random)
        proc = start(procs, hal, ini)
        started.append(proc)
        return Machine(hal, HalCmd(hal), task, ui, proc, tmp_path / "tools.tbl")

    try:
        yield make
    finally:
        for proc in started:
            stop(proc)
        ui.close()
        task.close()
        master.close()
        hal.close()
        hal.destroy()


@pytest.fixture
def machine(machine_factory: Callable[..., Machine]) -> Machine:
    return machine_factory()


def test_pins_have_linuxcnc_names_types_and_directions(machine: Machine) -> None:
    pins = {
        name.removeprefix("iocontrol.0."): (pin["type"], pin["dir"])
        for name, pin in machine.hal.meta["pins"].items()
        if pin["owner"] == "iocontrol"
    }
    bits_in = ("emc-enable-in", "lube_level", "tool-prepared", "tool-changed")
    bits_out = ("user-enable-out", "user-request-enable", "coolant-flood", "coolant-mist")
    bits_out += ("lube", "tool-prepare", "tool-change")
    s32_out = ("tool-number", "tool-prep-number", "tool-prep-pocket", "tool-prep-index")
    s32_out += ("tool-from-pocket",)
    assert pins == {
        **{name: (HAL_BIT, HAL_IN) for name in bits_in},
        **{name: (HAL_BIT, HAL_OUT) for name in bits_out},
        **{name: (HAL_S32, HAL_OUT) for name in s32_out},
    }


def test_initial_status_and_cycle_time(machine: Machine) -> None:
    st = machine.status()
    assert st.status == RCS_STATUS.DONE
    assert (st.aux.estop, st.tool.toolInSpindle, st.tool.pocketPrepped) == (1, 0, -1)
    assert st.cycleTime == 0.5
    assert machine.run(emc.EMC_IO_SET_CYCLE_TIME(cycleTime=0.25)).cycleTime == 0.25
    assert machine.run(emc.EMC_IO_SET_CYCLE_TIME(cycleTime=0)).status == RCS_STATUS.ERROR


def test_estop_chain_through_emc_enable_in(machine: Machine) -> None:
    machine.hal_do("net", "estop-loop", "iocontrol.0.user-enable-out", "iocontrol.0.emc-enable-in")
    assert machine.run(emc.EMC_AUX_ESTOP_OFF()).status == RCS_STATUS.DONE
    assert machine.pin("user-enable-out") == 1
    assert machine.pin("user-request-enable") == 1  # a pulse of one cycle (0.5 s here)
    machine.wait_status(lambda st: st.aux.estop == 0)
    machine.wait_pin("user-request-enable", 0)
    machine.run(emc.EMC_COOLANT_FLOOD_ON())
    # an external e-stop: the latch drops emc-enable-in
    machine.hal_do("unlinkp", "iocontrol.0.emc-enable-in")
    machine.setp("emc-enable-in", 0)
    machine.wait_status(lambda st: st.aux.estop == 1)
    machine.hal_do("net", "estop-loop", "iocontrol.0.emc-enable-in")
    machine.wait_status(lambda st: st.aux.estop == 0)
    st = machine.run(emc.EMC_AUX_ESTOP_ON())
    assert machine.pin("user-enable-out") == 0
    assert machine.pin("coolant-flood") == 0 and st.coolant.flood == 0
    machine.wait_status(lambda st: st.aux.estop == 1)


def test_io_init_resets_every_output(machine: Machine) -> None:
    machine.run(emc.EMC_AUX_ESTOP_OFF())
    machine.run(emc.EMC_COOLANT_MIST_ON())
    machine.send(emc.EMC_TOOL_PREPARE(tool=2))
    st = machine.run(emc.EMC_IO_INIT())
    assert (st.status, st.coolant.mist, st.tool.pocketPrepped) == (RCS_STATUS.DONE, 0, -1)
    for name in ("user-enable-out", "coolant-mist", "tool-prepare", "tool-prep-number"):
        assert machine.pin(name) == 0, name


def test_coolant_and_lube(machine: Machine) -> None:
    st = machine.run(emc.EMC_COOLANT_FLOOD_ON())
    assert (st.coolant.flood, st.coolant.mist, machine.pin("coolant-flood")) == (1, 0, 1)
    st = machine.run(emc.EMC_COOLANT_MIST_ON())
    assert (st.coolant.mist, machine.pin("coolant-mist")) == (1, 1)
    st = machine.run(emc.EMC_LUBE_ON())
    assert (st.lube.on, machine.pin("lube")) == (1, 1)
    machine.setp("lube_level", 1)
    machine.wait_status(lambda st: st.lube.level == 1)
    st = machine.run(emc.EMC_COOLANT_FLOOD_OFF())
    assert (st.coolant.flood, machine.pin("coolant-flood")) == (0, 0)
    st = machine.run(emc.EMC_LUBE_OFF())
    assert (st.lube.on, machine.pin("lube")) == (0, 0)


def test_nonrandom_prepare_and_change_handshakes(machine: Machine) -> None:
    before = machine.table.read_text()
    serial = machine.send(emc.EMC_TOOL_PREPARE(tool=2))
    st = machine.wait_ack(serial)
    assert st.status == RCS_STATUS.EXEC and st.command_type == emc.EMC_TOOL_PREPARE.TYPE
    assert machine.pin("tool-prepare") == 1
    assert (machine.pin("tool-prep-number"), machine.pin("tool-prep-pocket")) == (2, 7)
    assert machine.pin("tool-prep-index") == 2
    assert machine.status().status == RCS_STATUS.EXEC  # still waiting for tool-prepared
    machine.setp("tool-prepared", 1)
    st = machine.wait_status(lambda st: st.status == RCS_STATUS.DONE)
    assert st.echo_serial_number == serial and st.tool.pocketPrepped == 2
    assert machine.pin("tool-prepare") == 0
    machine.setp("tool-prepared", 0)

    serial = machine.send(emc.EMC_TOOL_LOAD())
    assert machine.wait_ack(serial).status == RCS_STATUS.EXEC
    assert machine.pin("tool-change") == 1
    machine.setp("tool-changed", 1)
    st = machine.wait_status(lambda st: st.status == RCS_STATUS.DONE)
    assert (st.tool.toolInSpindle, st.tool.toolFromPocket, st.tool.pocketPrepped) == (2, 7, -1)
    assert (st.tool.toolTableCurrent.toolno, st.tool.toolTableCurrent.offset.tran.z) == (2, 1.0)
    assert machine.pin("tool-change") == 0 and machine.pin("tool-number") == 2
    assert machine.pin("tool-from-pocket") == 7 and machine.pin("tool-prep-number") == 0
    assert machine.table.read_text() == before  # nonrandom: the file does not change
    shared = read_tool_data()
    assert (shared.get(0).toolno, shared.get(0).pocketno, shared.get(2).toolno) == (2, 7, 2)


def test_random_changer_with_loopback_swaps_pockets_and_saves(
    machine_factory: Callable[..., Machine],
) -> None:
    machine = machine_factory(RANDOM_TABLE, is_random=True)
    machine.hal_do("net", "prep-loop", "iocontrol.0.tool-prepare", "iocontrol.0.tool-prepared")
    machine.hal_do("net", "change-loop", "iocontrol.0.tool-change", "iocontrol.0.tool-changed")
    assert machine.status().tool.toolInSpindle == 5
    serial = machine.send(emc.EMC_TOOL_PREPARE(tool=2))
    st = machine.wait_ack(serial)  # the loopback acknowledges in the same cycle (IO-010)
    assert st.status == RCS_STATUS.DONE and st.tool.pocketPrepped == 2
    serial = machine.send(emc.EMC_TOOL_LOAD())
    st = machine.wait_ack(serial)
    assert st.status == RCS_STATUS.DONE
    assert (st.tool.toolInSpindle, st.tool.toolFromPocket) == (2, 2)
    saved = ToolTable(random_toolchanger=True)
    saved.load(machine.table)
    assert {idx: e.toolno for idx, e in saved.entries.items()} == {0: 2, 1: 1, 2: 5}
    assert saved.get(2).offset[2] == 5.0 and saved.get(2).comment == "five"
    assert not list(machine.table.parent.glob(".tools.tbl.*"))  # no temporary file left
    shared = read_tool_data()  # what task and the UIs see
    assert {idx: e.toolno for idx, e in shared.entries.items()} == {0: 2, 1: 1, 2: 5}


def test_abort_cancels_a_pending_handshake(machine: Machine) -> None:
    machine.run(emc.EMC_COOLANT_MIST_ON())
    serial = machine.send(emc.EMC_TOOL_PREPARE(tool=1))
    assert machine.wait_ack(serial).status == RCS_STATUS.EXEC
    st = machine.run(emc.EMC_TOOL_ABORT(reason=emc.EMC_IO_ABORT_REASON_ENUM.AUX_ESTOP))
    assert st.status == RCS_STATUS.DONE and st.coolant.mist == 0
    assert st.tool.pocketPrepped == -1 and st.reason == emc.EMC_IO_ABORT_REASON_ENUM.AUX_ESTOP
    assert machine.pin("tool-prepare") == 0 and machine.pin("coolant-mist") == 0


def test_set_offset_and_set_number_update_status_and_file(machine: Machine) -> None:
    offset = emc.EmcPose()
    offset.tran.z = 2.25
    st = machine.run(emc.EMC_TOOL_SET_OFFSET(pocket=1, toolno=1, offset=offset, diameter=6.0))
    assert st.status == RCS_STATUS.DONE
    saved = ToolTable()
    saved.load(machine.table)
    assert (saved.get(1).offset[2], saved.get(1).diameter, saved.get(1).comment) == (2.25, 6, "one")
    st = machine.run(emc.EMC_TOOL_SET_NUMBER(tool=1))  # M61 Q1: tooldata index 1
    assert (st.tool.toolInSpindle, st.tool.toolTableCurrent.offset.tran.z) == (1, 2.25)
    assert machine.pin("tool-number") == 1 and machine.pin("tool-change") == 0


@pytest.mark.parametrize("word", ["Zoops", "Z+nan", "Z-inf"])
def test_reload_of_a_bad_tool_table_reports_file_and_line(machine: Machine, word: str) -> None:
    bad = f"T1 P1 Z0.5\nT2 P2 {word}\n"
    machine.table.write_text(bad)
    st = machine.run(emc.EMC_TOOL_LOAD_TOOL_TABLE(file=""))
    assert st.status == RCS_STATUS.ERROR
    assert any(f"{machine.table}:2:" in text for text in machine.errors())
    # a change to the table in use is not saved over the file the user is editing
    offset = emc.EmcPose()
    st = machine.run(emc.EMC_TOOL_SET_OFFSET(pocket=1, toolno=1, offset=offset, diameter=3))
    assert st.status == RCS_STATUS.ERROR
    assert any("tool table not saved" in text for text in machine.errors())
    assert machine.table.read_text() == bad
    # the previous table stays in use
    serial = machine.send(emc.EMC_TOOL_PREPARE(tool=2))
    assert machine.wait_ack(serial).status == RCS_STATUS.EXEC
    assert machine.pin("tool-prep-pocket") == 7
    machine.hal_do("net", "prep-loop", "iocontrol.0.tool-prepare", "iocontrol.0.tool-prepared")
    machine.wait_status(lambda st: st.status == RCS_STATUS.DONE)
    # once the file is fixed, it loads
    machine.table.write_text("T1 P1 Z0.5\nT3 P2 Z3\n")
    assert machine.run(emc.EMC_TOOL_LOAD_TOOL_TABLE(file="")).status == RCS_STATUS.DONE
    st = machine.run(emc.EMC_TOOL_PREPARE(tool=3))
    assert st.status == RCS_STATUS.DONE and st.tool.pocketPrepped == 2


def test_a_tool_table_name_no_file_can_have_is_refused_with_why(machine: Machine) -> None:
    machine.errors()
    st = machine.run(emc.EMC_TOOL_LOAD_TOOL_TABLE(file="tools\0.tbl"))
    assert st.status == RCS_STATUS.ERROR
    assert machine.errors() == ["tool table file name 'tools\\x00.tbl' holds a NUL character"]


def test_unknown_and_unsupported_commands_are_reported(machine: Machine) -> None:
    st = machine.run(emc.EMC_AUX_INPUT_WAIT(index=0))
    assert st.status == RCS_STATUS.ERROR
    assert any("EMC_AUX_INPUT_WAIT" in text for text in machine.errors())
    machine.send(EMC_IO_TEST_UNKNOWN(value=1))
    deadline = time.monotonic() + WAIT_S
    found: list[str] = []
    while not any("1650" in text for text in found):
        assert time.monotonic() < deadline, found
        found += machine.errors()
        time.sleep(0.01)
    assert machine.run(emc.EMC_COOLANT_FLOOD_ON()).status == RCS_STATUS.DONE


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_exits_cleanly_and_leaves_hal(machine: Machine, sig: signal.Signals) -> None:
    machine.proc.send_signal(sig)
    with contextlib.suppress(subprocess.TimeoutExpired):  # (stop() would send SIGTERM at once,
        machine.proc.wait(timeout=WAIT_S)  # which could reach a process already finalizing)
    code, err = stop(machine.proc)
    assert code == 0, err
    assert "iocontrol" not in machine.hal.meta["comps"]
    with pytest.raises(ToolDataError):
        read_tool_data()
    assert not [name for name in machine.hal.meta["pins"] if name.startswith("iocontrol.")]


def test_restart_after_kill_takes_over(machine_factory: Callable[..., Machine]) -> None:
    machine = machine_factory()
    machine.run(emc.EMC_COOLANT_FLOOD_ON())
    machine.proc.kill()
    machine.proc.wait()
    machine = machine_factory()  # a new iocontrol finds the dead one's component and store
    assert machine.status().coolant.flood == 0 and machine.pin("coolant-flood") == 0
    serial = machine.send(emc.EMC_TOOL_PREPARE(tool=1))
    assert machine.wait_ack(serial).status == RCS_STATUS.EXEC
    assert read_tool_data().find_index_for_tool(2) == 2


@pytest.mark.parametrize(
    ("table", "cause"),
    [
        ("T1 P1\nT2 P2 Q1x\n", "bad number in word 'Q1x'"),  # LinuxCNC would read Q1
        ("T1 P1 Z2\nT2 P2 Z+nan\n", "Z = nan is not a finite number"),
        ("T1 P1\nT2 P2 D1.5mm\n", "bad number in word 'D1.5mm'"),
    ],
)
def test_a_malformed_tool_table_stops_iocontrol_before_it_starts(
    procs: Processes, tmp_path: Path, table: str, cause: str
) -> None:
    """A line LinuxCNC would misread: never a machine with a wrong or empty tool table,
    and the user's file left as it is."""
    ini = write_config(tmp_path, table)
    proc = procs.python("-m", "iocontrol", "-ini", str(ini))
    _, err = proc.communicate(timeout=WAIT_S)
    assert proc.returncode == 1
    assert f"iocontrol: {tmp_path / 'tools.tbl'}:2: {cause}" in err
    assert (tmp_path / "tools.tbl").read_text() == table
    assert sorted(path.name for path in tmp_path.iterdir()) == ["machine.ini", "tools.tbl"]


def test_bad_ini_value_is_a_clear_error(procs: Processes, tmp_path: Path) -> None:
    ini = tmp_path / "bad.ini"
    ini.write_text("[EMCIO]\nCYCLE_TIME = 0.1\nRANDOM_TOOLCHANGER = maybe\n")
    proc = procs.python("-m", "iocontrol", "-ini", str(ini))
    _, err = proc.communicate(timeout=WAIT_S)
    assert proc.returncode == 1
    assert f"{ini}:3: [EMCIO]RANDOM_TOOLCHANGER = 'maybe'" in err


def test_commands_with_any_field_values_are_answered_and_nothing_is_lost(machine) -> None:
    """Every command iocontrol takes, its fields random bytes (a buggy client, corrupt
    shared memory): each is answered, iocontrol stays up, and the tool table it writes
    still reads back (no NaN offsets, no lost tools)."""
    machine.hal_do("net", "prepare-loop", "iocontrol.0.tool-prepare", "iocontrol.0.tool-prepared")
    machine.hal_do("net", "change-loop", "iocontrol.0.tool-change", "iocontrol.0.tool-changed")
    commands = [
        cls
        for cls in REGISTRY.of_kind(MessageKind.COMMAND)
        if is_io_type(cls.TYPE)
        and cls.__module__ == "nml.emc"
        # (a random cycle time of seconds would only make the test slow)
        and cls is not emc.EMC_IO_SET_CYCLE_TIME
    ]
    rng = random.Random(1)
    for _ in range(200):
        cls = rng.choice(commands)
        status = machine.run(cls.from_bytes(rng.randbytes(cls.fixed_size())))
        assert status.status in (RCS_STATUS.DONE, RCS_STATUS.ERROR), cls.NAME
    assert machine.proc.poll() is None
    table = ToolTable()
    assert table.load(machine.table) == []  # (no complaints)
    assert machine.run(emc.EMC_TOOL_LOAD_TOOL_TABLE(file="")).status == RCS_STATUS.DONE


def test_a_table_with_lines_linuxcnc_skips_loads_but_is_never_saved_over(
    machine_factory: Callable[..., Machine],
) -> None:
    """An old-format table (LinuxCNC's gantry_mm.tbl): the lines LinuxCNC skips are
    skipped, the rest is used, and no change is written over the file (it would lose
    those lines): the change is refused with a message saying so."""
    text = "TOOLNO POCKET LENGTH\nT1 P1 Z0.5 ;one\n     2      2    +0.100000\n"
    machine = machine_factory(text)
    st = machine.run(emc.EMC_TOOL_SET_NUMBER(tool=1))
    assert (st.tool.toolInSpindle, st.tool.toolTableCurrent.offset.tran.z) == (1, 0.5)
    offset = emc.EmcPose()
    offset.tran.z = 2.0
    st = machine.run(emc.EMC_TOOL_SET_OFFSET(pocket=1, toolno=1, offset=offset, diameter=3))
    assert st.status == RCS_STATUS.ERROR
    assert any("could not be read (saving would lose them)" in t for t in machine.errors())
    assert machine.table.read_text() == text
