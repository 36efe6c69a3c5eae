"""hm2_eth: Mesa Ethernet boards with HostMot2 firmware (``loadrt hm2_eth``).

``loadrt hm2_eth board_ip=IP[,IP...] [config="STR[,STR...]"]`` after ``loadrt hostmot2``:
each board is found by its name (LBP16 board information), its firmware read from the
board (IDROM), and its functions get LinuxCNC's HAL names under ``hm2_<board>.<n>``
(``hm2_7i96s.0.stepgen.00.position-cmd``, ``.encoder.00.count``, ``.gpio.034.out``,
``.watchdog.has_bit`` ...; see ``hal/hm2/functions.py``). Functions per board:
``hm2_<board>.<n>.read-request``, ``.read``, ``.write``.

Besides hostmot2's pins, per board: ``packet-error`` (bit out, this period), ``packet-
error-level`` (s32 out), ``packet-error-exceeded`` (bit out), ``packet-error-total``
(u32 io) and the parameters ``packet-error-limit`` (10), ``packet-error-increment``
(2), ``packet-error-decrement`` (1, read-only), ``packet-read-timeout`` (80: <= 0 means
80 % of the thread period, < 100 a percentage of it, else ns; never under 100 us), as
in LinuxCNC: past the limit the board's ``io_error`` is set and read/write stop until it
is cleared. ``board_mac`` is accepted and ignored. Unloading makes the board's watchdog
bite, so its outputs go off.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, param, pin
from hal.core import HalError
from hal.hm2.driver import Board, ConfigError, LowLevel, parse_config
from hal.hm2.eth import EthLink, LinkError
from hal.hm2.firmware import SEVEN_I96S
from hal.hm2.idrom import IdromError
from hal.operator_messages import operator_channel

# Boards by their LBP16 name: (HAL name, I/O ports, pins per port, LEDs, connector names).
BOARDS = {
    "7I96S": ("7i96s", 3, 17, 4, SEVEN_I96S.pin_names),
    "7I96": ("7i96", 3, 17, 4, SEVEN_I96S.pin_names),
    "7I76E": ("7i76e", 3, 17, 4, ()),
    "7I92": ("7i92", 2, 17, 2, ()),
    "7I95": ("7i95", 3, 29, 4, ()),
    "7I97": ("7i97", 3, 24, 4, ()),
}


class PacketPins(RtComponent):
    packet_error = pin("bit out")
    packet_error_exceeded = pin("bit out")
    packet_error_level = pin("s32 out")
    packet_error_total = pin("u32 io")
    packet_error_decrement = param("s32 ro", default=1)
    packet_error_increment = param("s32 rw", default=2)
    packet_error_limit = param("s32 rw", default=10)
    packet_read_timeout = param("s32 rw", default=80)


class EthBoard:
    """A board with hm2_eth's packet-error pins around the hostmot2 driver."""

    def __init__(self, board: Board, pins: Any) -> None:
        self.board = board
        self.pins = pins

    def read_request(self, period: int) -> None:
        self.board.read_request(period)

    def read(self, period: int) -> None:
        board, pins, errors = self.board, self.pins, self.board.errors
        errors.limit = pins.packet_error_limit
        errors.increment = pins.packet_error_increment
        errors.decrement = pins.packet_error_decrement
        errors.total = pins.packet_error_total
        board.read_timeout_param = pins.packet_read_timeout
        board.read(period)
        pins.packet_error = errors.is_error
        pins.packet_error_level = errors.level
        pins.packet_error_exceeded = errors.is_exceeded
        pins.packet_error_total = errors.total

    def write(self, period: int) -> None:
        self.board.write(period)


def _split(value: str) -> list[str]:
    return [part.strip() for part in value.split(",")] if value else []


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    unknown = set(args) - {"board_ip", "board_mac", "config", "debug"}
    if unknown:
        raise HalError(f"hm2_eth: unknown argument '{sorted(unknown)[0]}'")
    if "hostmot2" not in host.modules:
        raise HalError("hm2_eth: load hostmot2 first (loadrt hostmot2)")
    ips = [ip for ip in _split(args.get("board_ip", "")) if ip]
    if not ips:
        raise HalError("hm2_eth: no board_ip given")
    configs = _split(args.get("config", ""))
    print("hm2_eth: loading Mesa AnyIO HostMot2 ethernet driver version 0.2 (cnc)", flush=True)
    boards: list[EthBoard] = []
    counts: dict[str, int] = {}
    tell = operator_channel("motion")  # the servo thread writes it: never blocks
    try:
        for n, ip in enumerate(ips):
            boards.append(_open_board(host, comp, ip, configs[n] if n < len(configs) else "",
                                      counts, tell))  # fmt: skip
    except Exception:
        for eth in boards:
            eth.board.close()
        raise
    host.hm2_eth_boards = boards


def _open_board(host: Any, comp: str, ip: str, config_text: str, counts: dict[str, int],
                tell: Any) -> EthBoard:  # fmt: skip
    try:
        config = parse_config(config_text)
    except ConfigError as exc:
        raise HalError(f"hm2_eth: {exc}") from None
    try:
        link = EthLink(ip)
    except LinkError as exc:
        raise HalError(f"hm2_eth: {exc}") from None
    try:
        board_name = link.board_name()
        known = BOARDS.get(board_name)
        if known is None:
            raise HalError(f"hm2_eth: {ip}: unsupported board '{board_name}'")
        hal_name, ports, width, leds, pin_names = known
        index = counts.get(hal_name, 0)
        counts[hal_name] = index + 1
        name = f"hm2_{hal_name}.{index}"
        print(f"hm2_eth: {ip}: discovered {board_name} (MAC {link.mac_address()})", flush=True)
        llio = LowLevel(name, ports, width, leds, pin_names)
        board = Board(link, llio, config, host.hal, comp)
    except (LinkError, IdromError, ConfigError) as exc:
        link.close()
        raise HalError(f"hm2_eth: {ip}: {exc}") from None
    except BaseException:
        link.close()
        raise
    board.report_fault_hook = tell
    pins = PacketPins.create(host.hal, comp, name)
    eth = EthBoard(board, pins)
    host.add_function(comp, f"{name}.read-request", eth.read_request)
    host.add_function(comp, f"{name}.read", eth.read)
    host.add_function(comp, f"{name}.write", eth.write)
    board.say("registered")
    return eth


def rtapi_app_exit(host: Any, comp: str) -> None:
    for eth in getattr(host, "hm2_eth_boards", []):
        eth.board.close()
    host.hm2_eth_boards = []
