"""mb2hal: LinuxCNC's generic Modbus to HAL bridge, configured by its INI file.

``loadusr -W mb2hal config=FILE.ini`` (or ``-Wn NAME`` when ``HAL_MODULE_NAME=NAME``).
The file is LinuxCNC's: ``[MB2HAL_INIT]`` (``INIT_DEBUG``, ``VERSION``, ``HAL_MODULE_NAME``,
``SLOWDOWN``, ``TOTAL_TRANSACTIONS``) and ``[TRANSACTION_00]``, ``[TRANSACTION_01]`` ...
with the link (``LINK_TYPE=serial``: ``SERIAL_PORT``, ``SERIAL_BAUD``, ``SERIAL_BITS``,
``SERIAL_PARITY``, ``SERIAL_STOP``, ``SERIAL_DELAY_MS``; ``LINK_TYPE=tcp``: ``TCP_IP``,
``TCP_PORT``), ``MB_SLAVE_ID``, ``FIRST_ELEMENT``, ``NELEMENTS`` or ``PIN_NAMES``,
``MB_TX_CODE`` (``fnct_01_read_coils`` ... ``fnct_16_write_multiple_registers``),
``MB_RESPONSE_TIMEOUT_MS``, ``MB_BYTE_TIMEOUT_MS``, ``HAL_TX_NAME``, ``MAX_UPDATE_RATE``,
``DEBUG``. A key left out of a transaction is taken from the one before (the link's keys
too, so transactions of one device share its link).

Pins (``m`` = ``HAL_TX_NAME`` or the transaction number, ``n`` = element number or name):
``mb2hal.m.n.bit`` / ``.bit-inv`` (functions 1, 2: out), ``.float`` / ``.int`` (3, 4:
out; 6, 16: in, added and limited to 0..65535), ``.bit`` (5, 15: in), and
``mb2hal.m.num_errors`` (u32 out: failed transactions in a row, 0 after a good one).
``VERSION`` 1.0 files get 1.0's names (``mb2hal.m.n`` for bits and written registers).

Each link runs in its own thread, through its transactions in turn. A failure (no port,
no answer, bad CRC, an exception answer) counts on ``num_errors`` and is told to the
operator when a transaction starts failing, or fails another way, and when it recovers
(not at every retry); a
port that cannot be opened is retried every half second. mb2hal is a userspace process
carrying I/O: a machine that relies on it wires ``num_errors`` (or the values) into its
E-stop or fault logic.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import socket
import struct
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cnc.ini import IniError, IniFile
from hal.modbus import rtu
from hal.modbus.rtu import ModbusError, NoAnswerError, PortError

FUNCTIONS = {
    "fnct_01_read_coils": 1,
    "fnct_02_read_discrete_inputs": 2,
    "fnct_03_read_holding_registers": 3,
    "fnct_04_read_input_registers": 4,
    "fnct_05_write_single_coil": 5,
    "fnct_06_write_single_register": 6,
    "fnct_15_write_multiple_coils": 15,
    "fnct_16_write_multiple_registers": 16,
}
LINK_KEYS = (
    "LINK_TYPE", "SERIAL_PORT", "SERIAL_BAUD", "SERIAL_BITS", "SERIAL_PARITY", "SERIAL_STOP",
    "TCP_IP", "TCP_PORT",
)  # fmt: skip
CARRIED_KEYS = (
    *LINK_KEYS, "SERIAL_DELAY_MS", "MB_SLAVE_ID", "MB_RESPONSE_TIMEOUT_MS",
    "MB_BYTE_TIMEOUT_MS", "MAX_UPDATE_RATE", "DEBUG",
)  # fmt: skip
PORT_RETRY_S = 0.5


class ConfigError(ValueError):
    """A bad mb2hal INI file: ``str()`` is ``file:line: cause`` where there is a line."""


@dataclass
class Transaction:
    number: int
    name: str  # HAL_TX_NAME or the number
    function: int
    slave: int
    first: int
    elements: list[str]  # pin name parts
    link_key: tuple
    response_timeout: float = 0.5
    byte_timeout: float = 0.5
    update_interval: float = 0.0
    delay: float = 0.0  # SERIAL_DELAY_MS
    debug: int = 1
    pins: dict[str, list[Any]] = field(default_factory=dict)
    num_errors: Any = None
    next_time: float = 0.0
    is_failing: bool = False
    failure_code: int = 0  # what the current run of failures is (mb2hal's error number)


@dataclass
class Config:
    module_name: str
    version: int  # 1000 for 1.0, 1001 for 1.1
    slowdown: float
    init_debug: int
    transactions: list[Transaction]
    links: dict[tuple, dict[str, str]]


def _version(text: str, where: str) -> int:
    try:
        major, minor = text.split(".", 1)
        return int(major) * 1000 + int(minor)
    except ValueError:
        raise ConfigError(f"{where}: VERSION must look like 1.1, not '{text}'") from None


def load_config(path: str) -> Config:
    try:
        ini = IniFile.load(path)
    except (OSError, IniError) as exc:
        raise ConfigError(f"cannot read {path}: {exc}") from None

    def where(section: str, key: str) -> str:
        entry = ini.entry(section, key)
        return f"{entry.file}:{entry.line}" if entry else f"{path}: [{section}]{key}"

    def number(section: str, key: str, kind: type, default: Any = None) -> Any:
        text = ini.find(section, key)
        if text is None:
            if default is None:
                raise ConfigError(f"{path}: [{section}]{key} is required")
            return default
        try:
            return kind(text.strip())
        except ValueError:
            raise ConfigError(f"{where(section, key)}: {key} must be a number") from None

    init = "MB2HAL_INIT"
    total = number(init, "TOTAL_TRANSACTIONS", int)
    version = _version(ini.find(init, "VERSION", "1.0") or "1.0", where(init, "VERSION"))
    module = (ini.find(init, "HAL_MODULE_NAME") or "mb2hal").strip()
    values: dict[str, str] = {}
    transactions: list[Transaction] = []
    links: dict[tuple, dict[str, str]] = {}
    for n in range(total):
        section = f"TRANSACTION_{n:02d}"
        if not ini.has_section(section):
            raise ConfigError(f"{path}: [{section}] missing (TOTAL_TRANSACTIONS={total})")
        for key in CARRIED_KEYS:  # the previous transaction's value unless given
            text = ini.find(section, key)
            if text is not None:
                values[key] = text.strip()
        link_type = values.get("LINK_TYPE", "")
        if link_type not in ("serial", "tcp"):
            raise ConfigError(f"{where(section, 'LINK_TYPE')}: LINK_TYPE must be serial or tcp")
        needed = (
            ("SERIAL_PORT", "SERIAL_BAUD", "SERIAL_BITS", "SERIAL_PARITY", "SERIAL_STOP")
            if link_type == "serial"
            else ("TCP_IP",)
        )
        for key in (*needed, "MB_SLAVE_ID"):
            if key not in values:
                raise ConfigError(f"{path}: [{section}]{key} is required")
        code_name = (ini.find(section, "MB_TX_CODE") or "").strip()
        if code_name not in FUNCTIONS:
            raise ConfigError(
                f"{where(section, 'MB_TX_CODE')}: MB_TX_CODE must be one of {', '.join(FUNCTIONS)}"
            )
        function = FUNCTIONS[code_name]
        if function in (1, 5) and version < 1001:
            raise ConfigError(f"{where(section, 'MB_TX_CODE')}: {code_name} needs VERSION=1.1")
        names_text, count_text = ini.find(section, "PIN_NAMES"), ini.find(section, "NELEMENTS")
        if (names_text is None) == (count_text is None):
            raise ConfigError(f"{path}: [{section}] needs NELEMENTS or PIN_NAMES (one of them)")
        if names_text is not None:
            elements = [name for name in names_text.strip().split(",") if name]
        else:
            elements = [f"{i:02d}" for i in range(number(section, "NELEMENTS", int))]
        if not elements:
            raise ConfigError(f"{path}: [{section}] has no elements")
        if function in (5, 6) and len(elements) != 1:
            raise ConfigError(f"{path}: [{section}] {code_name} writes exactly one element")
        link_key = tuple(values.get(key, "") for key in LINK_KEYS)
        links.setdefault(link_key, {key: values.get(key, "") for key in LINK_KEYS})
        rate = float(values.get("MAX_UPDATE_RATE", "0") or 0)
        tx_name = (ini.find(section, "HAL_TX_NAME") or f"{n:02d}").strip()
        try:
            transaction = Transaction(
                number=n,
                name=tx_name,
                function=function,
                slave=int(values["MB_SLAVE_ID"]),
                first=number(section, "FIRST_ELEMENT", int),
                elements=elements,
                link_key=link_key,
                response_timeout=int(values.get("MB_RESPONSE_TIMEOUT_MS", "500")) / 1000,
                byte_timeout=int(values.get("MB_BYTE_TIMEOUT_MS", "500")) / 1000,
                update_interval=1.0 / rate if rate > 0 else 0.0,
                delay=int(values.get("SERIAL_DELAY_MS", "0") or 0) / 1000,
                debug=int(values.get("DEBUG", "1")),
            )
        except ValueError:
            raise ConfigError(f"{path}: [{section}] has a value that is not a number") from None
        transactions.append(transaction)
    return Config(
        module_name=module,
        version=version,
        slowdown=number(init, "SLOWDOWN", float, 0.0),
        init_debug=number(init, "INIT_DEBUG", int, 1),
        transactions=transactions,
        links=links,
    )


# ---------------------------------------------------------------- links
class TcpLink:
    """Modbus TCP: the PDU after a 7-byte MBAP header, on one connection."""

    def __init__(self, ip: str, port: int) -> None:
        self.ip, self.port = ip, port
        self.sock: socket.socket | None = None
        self.transaction_id = 0

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()
            self.sock = None

    def transact(self, request: bytes, answer_bytes: int, response_timeout: float,
                 byte_timeout: float) -> bytes:  # fmt: skip
        """Same contract as RtuLink.transact: ``request`` is an RTU frame (its address and
        PDU are used, its CRC is not sent), the answer is address and PDU."""
        try:
            if self.sock is None:
                self.sock = socket.create_connection((self.ip, self.port), timeout=response_timeout)
            self.transaction_id = (self.transaction_id + 1) & 0xFFFF
            unit, pdu = request[0], request[1:-2]
            header = struct.pack(">HHHB", self.transaction_id, 0, len(pdu) + 1, unit)
            self.sock.settimeout(response_timeout)
            self.sock.sendall(header + pdu)
            head = self._read(7)
            tid, _protocol, length, unit_back = struct.unpack(">HHHB", head)
            body = self._read(length - 1)
        except TimeoutError:
            self.close()
            raise NoAnswerError(f"no answer from {self.ip}:{self.port}") from None
        except OSError as exc:
            self.close()
            raise PortError(f"{self.ip}:{self.port}: {exc.strerror or exc}") from None
        if tid != self.transaction_id:
            raise NoAnswerError(f"answer to another transaction from {self.ip}:{self.port}")
        if body[0] & 0x80:
            raise rtu.SlaveExceptionError(request[1], body[1])
        return bytes((unit_back,)) + body

    def _read(self, size: int) -> bytes:
        assert self.sock is not None
        data = b""
        while len(data) < size:
            chunk = self.sock.recv(size - len(data))
            if not chunk:
                raise OSError("connection closed")
            data += chunk
        return data


def make_link(settings: dict[str, str]) -> Any:
    if settings["LINK_TYPE"] == "tcp":
        return TcpLink(settings["TCP_IP"], int(settings.get("TCP_PORT") or 502))
    return rtu.RtuLink(
        settings["SERIAL_PORT"],
        int(settings["SERIAL_BAUD"]),
        int(settings["SERIAL_BITS"]),
        settings["SERIAL_PARITY"],
        int(settings["SERIAL_STOP"]),
    )


# ---------------------------------------------------------------- the bridge
class Bridge:
    """The HAL component and one thread per link."""

    def __init__(self, config: Config) -> None:
        from hal.api import component
        from hal.operator_messages import operator_channel

        self.config = config
        self.comp = component(config.module_name)
        self.is_stopping = False
        self.tell = operator_channel("tool")
        for transaction in config.transactions:
            self._make_pins(transaction)
        self.comp.ready()

    def _make_pins(self, tx: Transaction) -> None:
        from hal.api import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_OUT, HAL_S32, HAL_U32

        comp, v11 = self.comp, self.config.version >= 1001
        tx.num_errors = comp.newpin(f"{tx.name}.num_errors", HAL_U32, HAL_OUT)
        for element in tx.elements:
            base = f"{tx.name}.{element}"
            pins: list[Any] = []
            if tx.function in (1, 2):
                pins.append(comp.newpin(f"{base}.bit" if v11 else base, HAL_BIT, HAL_OUT))
                if v11:
                    pins.append(comp.newpin(f"{base}.bit-inv", HAL_BIT, HAL_OUT))
            elif tx.function in (3, 4):
                pins.append(comp.newpin(f"{base}.float", HAL_FLOAT, HAL_OUT))
                pins.append(comp.newpin(f"{base}.int", HAL_S32, HAL_OUT))
            elif tx.function in (5, 15):
                pins.append(comp.newpin(f"{base}.bit" if v11 else base, HAL_BIT, HAL_IN))
            else:  # 6, 16
                pins.append(comp.newpin(f"{base}.float" if v11 else base, HAL_FLOAT, HAL_IN))
                if v11:
                    pins.append(comp.newpin(f"{base}.int", HAL_S32, HAL_IN))
            tx.pins[element] = pins

    def say(self, text: str) -> None:
        print(f"{self.config.module_name}: {text}", file=sys.stderr, flush=True)

    def report_fault(self, text: str) -> None:
        """A transaction started failing: stderr and the operator's error channel (the one
        place this bridge raises an alarm; stopping the machine is the HAL wiring's job)."""
        self.say(text)
        if self.tell is not None:
            with contextlib.suppress(Exception):
                self.tell(f"{self.config.module_name}: {text}")

    def run(self) -> None:
        threads = []
        for key, settings in self.config.links.items():
            transactions = [tx for tx in self.config.transactions if tx.link_key == key]
            thread = threading.Thread(
                target=self._serve_link, args=(make_link(settings), transactions), daemon=True
            )
            thread.start()
            threads.append(thread)
        while not self.is_stopping:
            time.sleep(0.05)

    def _serve_link(self, link: Any, transactions: list[Transaction]) -> None:
        while not self.is_stopping:
            is_idle = True
            for tx in transactions:
                if self.is_stopping:
                    break
                now = time.monotonic()
                if now < tx.next_time:
                    continue
                is_idle = False
                try:
                    self.execute(link, tx)
                except PortError as exc:
                    self._failed(tx, exc)
                    link.close()
                    time.sleep(PORT_RETRY_S)
                except ModbusError as exc:
                    self._failed(tx, exc)
                else:
                    if tx.is_failing:
                        self.say(f"transaction {tx.name}: working again")
                    tx.is_failing = False
                    tx.num_errors.set(0)
                tx.next_time = time.monotonic() + tx.update_interval
                if tx.delay:
                    time.sleep(tx.delay)
                if self.config.slowdown:
                    time.sleep(self.config.slowdown)
            if is_idle:
                time.sleep(0.001)
        link.close()

    def _failed(self, tx: Transaction, exc: ModbusError) -> None:
        tx.num_errors.set(tx.num_errors.get() + 1)
        if not tx.is_failing or exc.code != tx.failure_code:  # new, or failing differently
            tx.is_failing = True
            tx.failure_code = exc.code
            text = f"transaction {tx.name} (slave {tx.slave}) failed: {exc} [{exc.code}]"
            self.report_fault(text)

    def execute(self, link: Any, tx: Transaction) -> None:
        """One transaction: the request, the answer, the pins."""
        fn, count = tx.function, len(tx.elements)
        timeouts = (tx.response_timeout, tx.byte_timeout)
        if fn in (1, 2, 3, 4):
            request, answer_bytes = rtu.read_request(tx.slave, fn, tx.first, count)
            body = link.transact(request, answer_bytes, *timeouts)
            if fn in (1, 2):
                for element, bit in zip(tx.elements, rtu.parse_bits(body, count), strict=True):
                    pins = tx.pins[element]
                    pins[0].set(bit)
                    if len(pins) > 1:
                        pins[1].set(not bit)
            else:
                for element, value in zip(
                    tx.elements, rtu.parse_registers(body, count), strict=True
                ):
                    float_pin, int_pin = tx.pins[element]
                    float_pin.set(float(value))
                    int_pin.set(value)
            return
        if fn in (5, 15):
            bits = [bool(tx.pins[e][0].get()) for e in tx.elements]
            if fn == 5:
                request = rtu.write_single_request(tx.slave, 5, tx.first, bits[0])
            else:
                request = rtu.write_multiple_request(tx.slave, 15, tx.first, bits)
        else:
            registers = [self._register_value(tx.pins[e]) for e in tx.elements]
            if fn == 6:
                request = rtu.write_single_request(tx.slave, 6, tx.first, registers[0])
            else:
                request = rtu.write_multiple_request(tx.slave, 16, tx.first, registers)
        link.transact(request, rtu.WRITE_ANSWER_BYTES, *timeouts)

    @staticmethod
    def _register_value(pins: list[Any]) -> int:
        """A written register: its float and int pins added, limited to 0..65535."""
        total = sum(pin.get() for pin in pins)
        return int(min(max(total, 0), 65535))


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(prog="mb2hal", description=__doc__.split("\n\n")[0])
    parser.add_argument("settings", nargs="*", help="config=FILE.ini (LinuxCNC's syntax)")
    options = parser.parse_args(args)
    path = next((s.split("=", 1)[1] for s in options.settings if s.startswith("config=")), "")
    if not path:
        print("mb2hal: usage: mb2hal config=FILE.ini", file=sys.stderr)
        return 1
    try:
        config = load_config(str(Path(path).expanduser()))
    except ConfigError as exc:
        print(f"mb2hal: {exc}", file=sys.stderr)
        return 1
    bridge = Bridge(config)

    def stop(*_: object) -> None:
        bridge.is_stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    bridge.say(f"{len(config.transactions)} transactions on {len(config.links)} links")
    try:
        bridge.run()
    finally:
        bridge.comp.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
