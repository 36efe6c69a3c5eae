"""The hostmot2 driver for one board: discovery, configuration and the periodic work.

``Board`` reads the board's self-description (cookie, IDROM, module and pin
descriptors), takes LinuxCNC's config string (``num_encoders=N num_stepgens=N
num_pwmgens=N ...``, -1 or absent: all), gives each enabled function its I/O pins (the
rest are GPIO), makes the HAL objects and then, every period:

- ``read_request``: sends the read request (if ``read`` runs without one, it sends it);
- ``read``: waits for the answer until the read deadline, and hands the values to the
  functions; a late or lost answer is a packet error (``hm2_eth``'s pins), and past the
  limit the board stops (``io_error``) and says so;
- ``write``: the functions' values, settings that changed and the watchdog pet, in one
  datagram.

With ``io_error`` set, read and write do nothing until the user clears it. A watchdog
bite sets ``watchdog.has_bit`` and stops the outputs on the board; clearing ``has_bit``
rewrites every setting (LinuxCNC's recovery). Operator messages go through
``report_fault`` (stderr, and the operator's error channel when the machine runs).
"""

from __future__ import annotations

import contextlib
import struct
import sys
import time
from dataclasses import dataclass

from hal.api import RtComponent, param
from hal.core import Hal
from hal.hm2 import functions, lbp16
from hal.hm2.eth import EthLink, PacketErrors
from hal.hm2.idrom import (
    CONFIG_NAME,
    CONFIG_NAME_ADDRESS,
    COOKIE,
    COOKIE_ADDRESS,
    GLOBAL_UNIT,
    GTAG_HM2DPLL,
    GTAG_IOPORT,
    GTAG_LED,
    GTAG_STEPGEN,
    GTAG_WATCHDOG,
    IDROM_POINTER_ADDRESS,
    MAX_MODULE_DESCRIPTORS,
    Idrom,
    IdromError,
    Module,
    ModuleDescriptor,
    PinDescriptor,
)

# config string keys -> the function they size (LinuxCNC's names)
CONFIG_COUNTS = {
    "num_encoders": functions.GTAG_ENCODER,
    "num_stepgens": GTAG_STEPGEN,
    "num_pwmgens": functions.GTAG_PWMGEN,
    "num_ssrs": functions.GTAG_SSR,
    "num_outms": functions.GTAG_OUTM,
    "num_inms": functions.GTAG_INM,
    "num_leds": GTAG_LED,
    "num_dplls": GTAG_HM2DPLL,
}
# accepted for LinuxCNC configs, for functions this driver does not drive (yet)
CONFIG_IGNORED = (
    "num_3pwmgens", "num_rcpwmgens", "num_resolvers", "num_bspis", "num_uarts",
    "num_pktuarts", "num_inmuxs", "num_oneshots", "num_xy2mods", "num_sserials",
)  # fmt: skip


class ConfigError(ValueError):
    """A config string the driver cannot follow (unknown token, too many instances)."""


@dataclass
class Config:
    counts: dict[int, int]  # gtag -> instances wanted, -1 = all
    stepgen_width: int = 2
    sserial_ports: tuple[str, ...] = ()


def parse_config(text: str) -> Config:
    """LinuxCNC's hostmot2 config string, e.g. ``num_encoders=1 num_stepgens=5``."""
    counts: dict[int, int] = {}
    config = Config(counts)
    for token in text.replace(",", " ").split():
        key, sep, value = token.partition("=")
        if key == "enable_raw":
            continue
        if not sep:
            raise ConfigError(f'invalid token in config string: "{token}"')
        if key == "firmware":
            continue  # Ethernet boards keep their firmware in flash (mesaflash writes it)
        if key.startswith(("sserial_port_", "ssi_chan_", "biss_chan_", "fanuc_chan_")):
            continue
        try:
            number = int(value, 0)
        except ValueError:
            raise ConfigError(f'invalid number in config string: "{token}"') from None
        if key in CONFIG_COUNTS:
            counts[CONFIG_COUNTS[key]] = number
        elif key == "stepgen_width":
            config.stepgen_width = number
        elif key not in CONFIG_IGNORED:
            raise ConfigError(f'invalid token in config string: "{token}"')
    return config


@dataclass(frozen=True)
class LowLevel:
    """What the low-level driver knows of a board model (LinuxCNC's llio fields)."""

    name: str  # HAL prefix, e.g. "hm2_7i96s.0"
    io_ports: int
    port_width: int
    num_leds: int = 0
    pin_names: tuple[str, ...] = ()


class BoardPins(RtComponent):
    io_error = param("bit rw", "io_error")


class Board:
    """One HostMot2 board; ``read``, ``read_request`` and ``write`` are its HAL functions."""

    def __init__(self, link: EthLink, llio: LowLevel, config: Config, hal: Hal, comp: str) -> None:
        self.link = link
        self.llio = llio
        self.name = llio.name
        self.hal = hal
        self.comp = comp
        self.errors = PacketErrors()
        self.needs_reset = False  # the watchdog bit: rewrite everything once the user clears it
        self.needs_soft_reset = False  # a packet was lost: rewrite the settings
        self.read_regions: list[tuple[int, int]] = []
        self.write_regions: list[tuple[int, int]] = []
        self.read_words = 0
        self.write_words = 0
        self.queued: list[tuple[int, list[int]]] = []
        self.period = 1_000_000
        self.report_fault_hook = None  # set by the component: where operator messages go
        self.idrom = self._read_idrom()
        self.modules = self._read_modules()
        self.pins = self._read_pins()
        self.has_dpll = any(m.descriptor.gtag == GTAG_HM2DPLL for m in self.modules)
        self.pin_owner: list[int | None] = [None] * len(self.pins)
        self.pin_is_output = [False] * len(self.pins)
        self.functions: list[functions.Function] = []
        self.watchdog: functions.Watchdog | None = None
        self.ioport: functions.IOPort | None = None
        self.board_pins = BoardPins.create(hal, comp, self.name)
        self._make_functions(config)
        self.out = [0] * self.write_words
        self.settings_checks = [
            check
            for function in (self.ioport, *self.functions)
            for check in function.settings_checks()
        ]
        self.next_check = 0
        self._make_write_packet()
        self.link.set_read_regions(self.read_regions)
        self.force_write()
        self._flush_queued_now()

    # ------------------------------------------------------------ discovery
    def _read_idrom(self) -> Idrom:
        link = self.link
        if link.read(COOKIE_ADDRESS, 1)[0] != COOKIE:
            raise IdromError(f"invalid cookie at 0x{COOKIE_ADDRESS:04X}: not a HostMot2 board")
        name = struct.pack("<2I", *link.read(CONFIG_NAME_ADDRESS, 2))
        if name != CONFIG_NAME:
            raise IdromError(f"invalid config name {name!r}, expected {CONFIG_NAME!r}")
        self.idrom_address = link.read(IDROM_POINTER_ADDRESS, 1)[0] & 0xFFFF
        idrom = Idrom.unpack(struct.pack("<16I", *link.read(self.idrom_address, 16)))
        idrom.check()
        if idrom.port_width != self.llio.port_width:
            raise IdromError(
                f"invalid IDROM PortWidth {idrom.port_width}, this board has "
                f"{self.llio.port_width} pins per connector"
            )
        if idrom.io_ports != self.llio.io_ports:
            raise IdromError(
                f"IDROM IOPorts is {idrom.io_ports} but the board has {self.llio.io_ports}"
            )
        return idrom

    def _read_modules(self) -> list[Module]:
        modules = []
        address = self.idrom_address + self.idrom.offset_to_modules
        for _ in range(MAX_MODULE_DESCRIPTORS):
            words = self.link.read(address, 3)
            md = ModuleDescriptor.unpack(struct.pack("<3I", *words))
            if md.gtag == 0:
                break
            modules.append(Module.resolve(md, self.idrom))
            address += 12
        return modules

    def _read_pins(self) -> list[PinDescriptor]:
        address = self.idrom_address + self.idrom.offset_to_pins
        words = self.link.read(address, self.idrom.io_width)
        pins = [PinDescriptor.unpack(struct.pack("<I", w)) for w in words]
        for n, pd in enumerate(pins):
            if pd.primary_tag == 0:
                raise IdromError(f"pin {n} primary tag is 0, expected {len(pins)} pins")
            if pd.primary_tag != GTAG_IOPORT:
                raise IdromError(f"pin {n} primary tag is {pd.primary_tag}, not IOPort")
        return pins

    # ------------------------------------------------------------ configuration
    def _wanted(self, config: Config, md: ModuleDescriptor) -> int:
        wanted = config.counts.get(md.gtag, -1)
        if wanted > md.instances:
            raise ConfigError(
                f"config.{_config_key(md.gtag)}={wanted}, but only {md.instances} are "
                "available, not loading driver"
            )
        return md.instances if wanted < 0 else wanted

    def _make_functions(self, config: Config) -> None:
        with self.hal.edit():
            by_tag = {m.descriptor.gtag: m for m in self.modules}
            io = by_tag.get(GTAG_IOPORT)
            if io is None:
                raise IdromError("the firmware has no IOPort")
            self.ioport = functions.IOPort(self, io, io.descriptor.instances)
            wd = by_tag.get(GTAG_WATCHDOG)
            if wd is not None:
                self.watchdog = functions.Watchdog(self, wd, 1)
            counts: dict[int, int] = {}
            for module in self.modules:
                md = module.descriptor
                gtag = md.gtag
                if gtag in (GTAG_IOPORT, GTAG_WATCHDOG):
                    continue
                if gtag == GTAG_LED:
                    count = self.llio.num_leds
                    wanted = config.counts.get(GTAG_LED, -1)
                    count = count if wanted < 0 else min(wanted, count)
                    if count:
                        self.functions.append(functions.Led(self, module, count))
                    continue
                if gtag == GTAG_HM2DPLL:
                    if self._wanted(config, md):
                        self.functions.append(functions.Dpll(self, module, 1))
                    continue
                cls = functions.FUNCTIONS.get(gtag)
                if cls is None:
                    self.say(f"MD: {md.instances}x {md.name} v{md.version}: ignored")
                    continue
                count = self._wanted(config, md)
                counts[gtag] = count
                self._take_pins(gtag, count, config.stepgen_width)
                if count:
                    self.functions.append(cls(self, module, count))
            self.ioport.make_pins()
            self._alias_module_outputs()

    def _take_pins(self, gtag: int, count: int, stepgen_width: int) -> None:
        """Give the enabled instances of a function their pins (LinuxCNC's allocation)."""
        for n, pd in enumerate(self.pins):
            if pd.sec_tag != gtag:
                continue
            is_global = bool(pd.sec_unit & GLOBAL_UNIT)
            if not (pd.sec_unit < count or (is_global and count > 0)):
                continue
            if gtag == GTAG_STEPGEN and pd.is_output and pd.pin_number > stepgen_width:
                continue
            self.pin_owner[n] = gtag
            self.pin_is_output[n] = pd.is_output

    def _alias_module_outputs(self) -> None:
        """``stepgen.NN.step.invert_output`` etc., naming the GPIO parameters of the pins
        a function drives, as LinuxCNC does."""
        names = {(GTAG_STEPGEN, 1): "step", (GTAG_STEPGEN, 2): "direction"}
        with self.hal.edit() as meta:
            for n, pd in enumerate(self.pins):
                name = names.get((pd.sec_tag, pd.pin_number))
                if name is None or self.pin_owner[n] != pd.sec_tag:
                    continue
                for parameter in ("invert_output", "is_opendrain"):
                    real = f"{self.name}.gpio.{n:03d}.{parameter}"
                    alias = f"{self.name}.stepgen.{pd.sec_unit:02d}.{name}.{parameter}"
                    meta["param_alias"][alias] = real

    # ------------------------------------------------------------ registers
    def add_read(self, address: int, words: int) -> int:
        """Read ``words`` registers from ``address`` every period; returns their index
        in the values ``process_read`` gets."""
        at = self.read_words
        self.read_regions.append((address, words))
        self.read_words += words
        return at

    def add_write(self, address: int, words: int) -> int:
        at = self.write_words
        self.write_regions.append((address, words))
        self.write_words += words
        return at

    def queue_write(self, address: int, values: list[int]) -> None:
        """Write these registers in this period's write packet (settings)."""
        self.queued.append((address, values))

    def _make_write_packet(self) -> None:
        parts = []
        fmt = "<"
        for address, words in self.write_regions:
            parts.append(lbp16.write_hm2(address, words).header())
            fmt += "I" * words
        headers = parts
        self.write_layout = []  # (header, first value, words)
        at = 0
        for header, (_, words) in zip(headers, self.write_regions, strict=True):
            self.write_layout.append((header, at, words))
            at += words
        self.write_struct = struct.Struct(fmt)

    def _packet(self) -> bytearray:
        packet = bytearray()
        out = self.out
        for header, at, words in self.write_layout:
            packet += header
            packet += struct.pack(f"<{words}I", *out[at : at + words])
        for address, values in self.queued:
            packet += lbp16.write_hm2(address, len(values)).header()
            packet += struct.pack(f"<{len(values)}I", *values)
        self.queued.clear()
        return packet

    def _flush_queued_now(self) -> None:
        """Start-up: send the settings at once, outside the periodic packets."""
        if self.queued:
            packet = bytearray()
            for address, values in self.queued:
                packet += lbp16.write_hm2(address, len(values)).header()
                packet += struct.pack(f"<{len(values)}I", *values)
            self.queued.clear()
            with contextlib.suppress(OSError):
                self.link.send_writes(packet)

    def force_write(self) -> None:
        if self.ioport:
            self.ioport.force_write()
        if self.watchdog:
            self.watchdog.force_write()
        for function in self.functions:
            function.force_write()

    # ------------------------------------------------------------ HAL functions
    @property
    def is_io_error(self) -> bool:
        return bool(self.board_pins.io_error)

    def read_request(self, period: int) -> None:
        self.period = period
        if self.is_io_error:
            return
        try:
            self.link.send_read_request(time.monotonic_ns())
        except OSError as exc:
            self._link_failed(f"cannot send: {exc.strerror}")

    def read(self, period: int) -> None:
        if not self.link.is_read_requested:
            self.read_request(period)
        if self.is_io_error or not self.link.is_read_requested:
            self.link.is_read_requested = False
            return
        errors = self.errors
        if errors.level >= errors.limit:  # the user cleared io_error: start afresh
            errors.level = 0
        deadline = self.link.request_time_ns + self.read_timeout_ns(period)
        values = self.link.receive(deadline)
        if values is None:
            if not errors.record_error():
                self.board_pins.io_error = True
                self.report_fault(
                    f"{errors.total} packet errors: the error level reached its limit "
                    f"({errors.limit}); communication with the board stopped (io_error)"
                )
            self.needs_soft_reset = True
            return
        errors.record_success()
        if self.watchdog:
            self.watchdog.process_read(values, period)
        if self.ioport:
            self.ioport.process_read(values, period)
        for function in self.functions:
            function.process_read(values, period)

    def write(self, period: int) -> None:
        self.period = period
        if self.is_io_error:
            return
        out = self.out
        if self.watchdog:
            self.watchdog.prepare_write(out, period)
        if self.ioport:
            self.ioport.prepare_write(out, period)
        for function in self.functions:
            function.prepare_write(out, period)
        if self.watchdog:
            self.watchdog.write_changes(period)
        checks = self.settings_checks
        if checks:  # one settings check per period, in turn
            self.next_check = (self.next_check + 1) % len(checks)
            checks[self.next_check](period)
        try:
            self.link.send_writes(self._packet())
        except OSError as exc:
            self._link_failed(f"cannot send: {exc.strerror}")

    read_timeout_param = 80  # set by the component from packet-read-timeout

    def read_timeout_ns(self, period: int) -> int:
        """LinuxCNC's rule: <= 0 means 80 % of the period, < 100 a percentage of the
        period, else nanoseconds; never under 100 us."""
        value = self.read_timeout_param
        if value <= 0:
            value = 80
        if value < 100:
            value = value * period // 100
        return max(value, 100_000)

    def _link_failed(self, text: str) -> None:
        if not self.errors.record_error():
            self.board_pins.io_error = True
            self.report_fault(f"{text}; communication with the board stopped (io_error)")

    # ------------------------------------------------------------ messages
    def say(self, text: str) -> None:
        print(f"hm2/{self.name}: {text}", file=sys.stderr, flush=True)

    def report_fault(self, text: str) -> None:
        """A fault the operator must see (watchdog bite, packet errors past the limit):
        the single place where this driver raises an alarm. Today: stderr and the
        operator's error channel; the E-stop itself comes from the HAL wiring
        (``watchdog.has_bit``, ``packet-error-exceeded`` in the E-stop chain)."""
        self.say(text)
        hook = self.report_fault_hook
        if hook is not None:
            with contextlib.suppress(Exception):
                hook(f"{self.name}: {text}")

    def close(self) -> None:
        """Unload: make the watchdog bite (outputs off), as LinuxCNC does, and let go."""
        if self.watchdog is not None:
            self.link.bite_watchdog(self.watchdog.address(0))
        self.link.close()


def _config_key(gtag: int) -> str:
    return next((k for k, v in CONFIG_COUNTS.items() if v == gtag), f"gtag {gtag}")
