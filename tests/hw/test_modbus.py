"""Modbus RTU: frames and CRC, mb2hal's INI file and bridge, hy_vfd against the simulated
VFD, each on a pseudo-terminal pair (a serial line with a simulated device on the end)."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from hal.api import set_shared_hal
from hal.core import HAL_BIT, Hal
from hal.modbus import rtu
from hal.modbus.mb2hal import Bridge, ConfigError, load_config
from hal.modbus.vfd_sim import PtyPort


def wait_for(condition: Callable[[], bool], what: str, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


# ---------------------------------------------------------------- frames
def test_the_crc_is_modbus_crc16() -> None:
    # the specification's example: read 10 holding registers of slave 1 from 0
    assert rtu.frame(1, bytes.fromhex("030000000a")).hex() == "01030000000ac5cd"


def test_requests_carry_the_function_its_elements_and_the_answer_length() -> None:
    request, answer_bytes = rtu.read_request(17, 1, 19, 37)
    assert request[:6] == bytes.fromhex("110100130025") and answer_bytes == 3 + 5 + 2
    assert rtu.write_multiple_request(1, 15, 0, [1, 0, 1])[:8] == bytes.fromhex("010f000000030105")
    assert rtu.write_single_request(1, 5, 7, True)[:6] == bytes.fromhex("01050007ff00")


def test_a_corrupted_answer_is_a_crc_error() -> None:
    good = rtu.frame(1, b"\x03\x02\x00\x07")
    assert rtu.check_frame(good) == good[:-2]
    with pytest.raises(rtu.BadCrcError):
        rtu.check_frame(good[:-1] + bytes((good[-1] ^ 1,)))


# ---------------------------------------------------------------- a Modbus slave
class Slave:
    """A Modbus RTU slave on a pseudo-terminal: coils, inputs, registers, and faults."""

    def __init__(self, port: PtyPort, slave: int = 1) -> None:
        self.port, self.slave = port, slave
        self.coils = [False] * 64
        self.inputs = [False] * 64
        self.holding = [0] * 64
        self.input_registers = [0] * 64
        self.is_mute = self.is_corrupt = False
        self.is_stopping = False
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self) -> None:
        lengths = {1: 8, 2: 8, 3: 8, 4: 8, 5: 8, 6: 8}
        while not self.is_stopping:
            head = self.port.read(2, 0.05)
            if len(head) < 2:
                continue
            function = head[1]
            try:
                if function in lengths:
                    raw = head + self.port.read(lengths[function] - 2, 0.2)
                else:  # 15, 16: the byte count says
                    rest = self.port.read(5, 0.2)
                    raw = head + rest + self.port.read(rest[4] + 2, 0.2)
                answer = self.answer(raw)
            except (rtu.BadCrcError, IndexError):  # out of step: wait for a quiet line
                while self.port.read(64, 0.02):
                    pass
                continue
            if answer is None or self.is_mute:
                continue
            if self.is_corrupt:
                answer = answer[:-1] + bytes((answer[-1] ^ 0xFF,))
            self.port.write(answer)

    def answer(self, raw: bytes) -> bytes | None:
        body = rtu.check_frame(raw)
        function = body[1]
        first, count = int.from_bytes(body[2:4], "big"), int.from_bytes(body[4:6], "big")
        if first + (count if function not in (5, 6) else 1) > 64:
            return rtu.frame(self.slave, bytes((function | 0x80, 2)))  # illegal address
        if function in (1, 2):
            bits = (self.coils if function == 1 else self.inputs)[first : first + count]
            data = bytearray((count + 7) // 8)
            for i, bit in enumerate(bits):
                data[i // 8] |= bit << (i % 8)
            return rtu.frame(self.slave, bytes((function, len(data))) + bytes(data))
        if function in (3, 4):
            table = self.holding if function == 3 else self.input_registers
            data = b"".join(v.to_bytes(2, "big") for v in table[first : first + count])
            return rtu.frame(self.slave, bytes((function, len(data))) + data)
        if function == 5:
            self.coils[first] = count == 0xFF00
        elif function == 6:
            self.holding[first] = count
        elif function == 15:
            for i in range(count):
                self.coils[first + i] = bool(body[7 + i // 8] >> (i % 8) & 1)
        elif function == 16:
            for i in range(count):
                self.holding[first + i] = int.from_bytes(body[7 + 2 * i : 9 + 2 * i], "big")
        return rtu.frame(self.slave, body[1:6])

    def stop(self) -> None:
        self.is_stopping = True
        self.thread.join(2)
        self.port.close()


MB2HAL_INI = """[MB2HAL_INIT]
VERSION=1.1
HAL_MODULE_NAME=mb2hal
TOTAL_TRANSACTIONS=5

[TRANSACTION_00]
LINK_TYPE=serial
SERIAL_PORT={port}
SERIAL_BAUD=115200
SERIAL_BITS=8
SERIAL_PARITY=none
SERIAL_STOP=1
MB_SLAVE_ID=1
MB_TX_CODE=fnct_03_read_holding_registers
FIRST_ELEMENT=0
NELEMENTS=2
HAL_TX_NAME=drive
MB_RESPONSE_TIMEOUT_MS=100
MB_BYTE_TIMEOUT_MS=50

[TRANSACTION_01]
MB_TX_CODE=fnct_16_write_multiple_registers
FIRST_ELEMENT=10
PIN_NAMES=speed,accel

[TRANSACTION_02]
MB_TX_CODE=fnct_02_read_discrete_inputs
FIRST_ELEMENT=4
NELEMENTS=3
HAL_TX_NAME=inputs

[TRANSACTION_03]
MB_TX_CODE=fnct_05_write_single_coil
FIRST_ELEMENT=20
PIN_NAMES=pump

[TRANSACTION_04]
MB_TX_CODE=fnct_01_read_coils
FIRST_ELEMENT=60
NELEMENTS=8
HAL_TX_NAME=beyond
"""


@pytest.fixture
def hal() -> Iterator[Hal]:
    h = Hal()
    set_shared_hal(h)
    yield h
    set_shared_hal(None)
    h.destroy()
    h.close()


@pytest.fixture
def bridge_on_slave(tmp_path: Path, hal: Hal) -> Iterator[tuple[Bridge, Slave, list[str]]]:
    port = PtyPort(str(tmp_path / "plc.tty"))
    slave = Slave(port)
    ini = tmp_path / "mb2hal.ini"
    ini.write_text(MB2HAL_INI.format(port=tmp_path / "plc.tty"))
    bridge = Bridge(load_config(str(ini)))
    faults: list[str] = []
    bridge.tell = faults.append
    thread = threading.Thread(target=bridge.run, daemon=True)
    thread.start()
    yield bridge, slave, faults
    bridge.is_stopping = True
    thread.join(3)
    slave.stop()
    bridge.comp.exit()


def pin(hal: Hal, name: str):
    found = hal.find_pin(name)
    assert found, name
    value = hal.read_slot(found[1]["type"], hal.ptr[found[1]["slot"]])
    return bool(value) if found[1]["type"] == HAL_BIT else value


def set_pin(hal: Hal, name: str, value) -> None:
    found = hal.find_pin(name)
    assert found, name
    hal.write_slot(found[1]["type"], hal.ptr[found[1]["slot"]], value)


def test_mb2hal_reads_and_writes_through_its_transactions(bridge_on_slave, hal: Hal) -> None:
    _bridge, slave, faults = bridge_on_slave
    slave.holding[0:2] = [1234, 65535]
    slave.inputs[4:7] = [True, False, True]
    set_pin(hal, "mb2hal.01.speed.float", 100.0)
    set_pin(hal, "mb2hal.01.speed.int", 23)  # added: 123
    set_pin(hal, "mb2hal.01.accel.float", 70000.0)  # limited to 65535
    set_pin(hal, "mb2hal.03.pump.bit", True)
    wait_for(lambda: pin(hal, "mb2hal.drive.00.int") == 1234, "the registers")
    assert pin(hal, "mb2hal.drive.00.float") == 1234.0
    assert pin(hal, "mb2hal.drive.01.int") == 65535
    wait_for(lambda: slave.holding[10:12] == [123, 65535], "the written registers")
    wait_for(lambda: slave.coils[20], "the coil")
    wait_for(lambda: pin(hal, "mb2hal.inputs.00.bit"), "the inputs")
    assert [pin(hal, f"mb2hal.inputs.{i:02d}.bit") for i in range(3)] == [True, False, True]
    assert pin(hal, "mb2hal.inputs.01.bit-inv") is True
    # transaction 04 asks beyond the slave's 64 coils: an exception answer, counted and told
    wait_for(lambda: pin(hal, "mb2hal.beyond.num_errors") > 2, "the refused transaction")
    assert pin(hal, "mb2hal.drive.num_errors") == 0
    assert any("beyond" in f and "ILLEGAL_DATA_ADDRESS" in f for f in faults)


def test_mb2hal_counts_a_silent_or_noisy_slave_and_says_so_once(bridge_on_slave, hal) -> None:
    _bridge, slave, faults = bridge_on_slave
    wait_for(lambda: pin(hal, "mb2hal.drive.00.float") == 0.0, "a good start")
    slave.is_mute = True
    wait_for(lambda: pin(hal, "mb2hal.drive.num_errors") >= 3, "errors while mute")
    assert sum("drive" in f and "no answer" in f and "[-12]" in f for f in faults) == 1
    slave.is_mute, slave.is_corrupt = False, True
    wait_for(lambda: any("drive" in f and "bad CRC" in f for f in faults), "CRC errors")
    slave.is_corrupt = False
    wait_for(lambda: pin(hal, "mb2hal.drive.num_errors") == 0, "recovery")


def test_mb2hal_says_when_its_port_is_missing(tmp_path: Path, hal: Hal) -> None:
    ini = tmp_path / "mb2hal.ini"
    ini.write_text(MB2HAL_INI.format(port=tmp_path / "no-such-tty"))
    bridge = Bridge(load_config(str(ini)))
    faults: list[str] = []
    bridge.tell = faults.append
    thread = threading.Thread(target=bridge.run, daemon=True)
    thread.start()
    try:
        # (the counter may move before the message is told: wait for the message)
        wait_for(
            lambda: any("cannot open" in f and "no-such-tty" in f and "[-13]" in f for f in faults),
            "the port error",
        )
        assert pin(hal, "mb2hal.drive.num_errors") > 0
    finally:
        bridge.is_stopping = True
        thread.join(3)
        bridge.comp.exit()


@pytest.mark.parametrize(
    "old, new, cause",
    [
        ("TOTAL_TRANSACTIONS=5", "TOTAL_TRANSACTIONS=6", "[TRANSACTION_05] missing"),
        ("NELEMENTS=3", "NELEMENTS=3\nPIN_NAMES=a,b", "needs NELEMENTS or PIN_NAMES"),
        ("fnct_02_read_discrete_inputs", "fnct_99_frobnicate", "MB_TX_CODE must be one of"),
        ("LINK_TYPE=serial", "LINK_TYPE=can", "LINK_TYPE must be serial or tcp"),
        ("VERSION=1.1", "VERSION=1.0", "fnct_05_write_single_coil needs VERSION=1.1"),
    ],
)
def test_a_bad_mb2hal_file_is_refused_with_its_place_and_cause(
    tmp_path: Path, old: str, new: str, cause: str
) -> None:
    ini = tmp_path / "bad.ini"
    ini.write_text(MB2HAL_INI.format(port="/dev/null").replace(old, new, 1))
    with pytest.raises(ConfigError) as failure:
        load_config(str(ini))
    assert str(ini) in str(failure.value) and cause in str(failure.value)
