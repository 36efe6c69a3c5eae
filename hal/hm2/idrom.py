"""The HostMot2 register map's self-description: the IDROM, module and pin descriptors.

A HostMot2 firmware describes itself in its register space (all registers 32 bits,
little-endian, byte addresses):

- 0x0100 the cookie 0x55AACAFE, 0x0104 the name "HOSTMOT2", 0x010C the IDROM's address;
- the IDROM header (type 2 or 3): where the module and pin descriptors are, the board
  name, the I/O ports and their width, the two clocks and the strides a module
  descriptor selects between;
- module descriptors, 12 bytes each until a zero tag: which function (its general tag),
  its version, clock, number of instances, base address, number of registers, which
  strides, and which registers are one per instance;
- pin descriptors, one 32-bit word per I/O pin: the secondary function that may own the
  pin (tag, instance, pin number with bit 7 set for outputs), primary tag IOPort.

Everything here is plain data and its byte layout, used by the driver to read a board
and by the simulator to describe one.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

COOKIE_ADDRESS = 0x0100
COOKIE = 0x55AACAFE
CONFIG_NAME_ADDRESS = 0x0104
CONFIG_NAME = b"HOSTMOT2"
IDROM_POINTER_ADDRESS = 0x010C
WATCHDOG_ADDRESS = 0x0C00  # the timer register; writing 1 makes it bite at once

MAX_MODULE_DESCRIPTORS = 48
MODULE_DESCRIPTOR_BYTES = 12

# General function tags (the functions the driver knows).
GTAG_WATCHDOG = 2
GTAG_IOPORT = 3
GTAG_ENCODER = 4
GTAG_STEPGEN = 5
GTAG_PWMGEN = 6
GTAG_HM2DPLL = 26
GTAG_INM = 35
GTAG_OUTM = 45
GTAG_LED = 128
GTAG_SMARTSERIAL = 193
GTAG_SSR = 195

FUNCTION_NAMES = {
    GTAG_WATCHDOG: "Watchdog",
    GTAG_IOPORT: "IOPort",
    GTAG_ENCODER: "Encoder",
    GTAG_STEPGEN: "StepGen",
    GTAG_PWMGEN: "PWMGen",
    GTAG_HM2DPLL: "Hostmot2 DPLL",
    GTAG_INM: "InM Input Module",
    GTAG_OUTM: "OutM Output Module",
    GTAG_LED: "LED",
    GTAG_SMARTSERIAL: "Smart Serial Interface",
    GTAG_SSR: "SSR",
}

CLOCK_LOW_TAG = 1
CLOCK_HIGH_TAG = 2
PIN_IS_OUTPUT = 0x80  # bit 7 of a pin descriptor's secondary pin number
GLOBAL_UNIT = 0x80  # a secondary unit number with bit 7 set: the pin serves every instance


class IdromError(ValueError):
    """The board's self-description is inconsistent or of an unknown kind."""


@dataclass(frozen=True, slots=True)
class Idrom:
    """The IDROM header (64 bytes)."""

    idrom_type: int
    offset_to_modules: int
    offset_to_pins: int
    board_name: bytes  # 8 ASCII bytes, not terminated
    fpga_size: int
    fpga_pins: int
    io_ports: int
    io_width: int
    port_width: int
    clock_low: int
    clock_high: int
    instance_stride_0: int
    instance_stride_1: int
    register_stride_0: int
    register_stride_1: int

    FORMAT = struct.Struct("<3I8s11I")

    def pack(self) -> bytes:
        return self.FORMAT.pack(
            self.idrom_type,
            self.offset_to_modules,
            self.offset_to_pins,
            self.board_name,
            self.fpga_size,
            self.fpga_pins,
            self.io_ports,
            self.io_width,
            self.port_width,
            self.clock_low,
            self.clock_high,
            self.instance_stride_0,
            self.instance_stride_1,
            self.register_stride_0,
            self.register_stride_1,
        )

    @classmethod
    def unpack(cls, data: bytes) -> Idrom:
        return cls(*cls.FORMAT.unpack_from(data))

    def check(self) -> None:
        """IdromError unless the header is one the driver can use (as hostmot2 checks)."""
        if self.idrom_type not in (2, 3):
            raise IdromError(f"invalid IDROM type {self.idrom_type}, expected 2 or 3")
        if self.io_width != self.io_ports * self.port_width:
            raise IdromError(
                f"IDROM IOWidth is {self.io_width}, but IOPorts is {self.io_ports} and "
                f"PortWidth is {self.port_width} (inconsistent firmware)"
            )
        if not 0 < self.port_width <= 32:
            raise IdromError(f"invalid IDROM PortWidth {self.port_width}")
        for name in ("clock_low", "clock_high"):
            if getattr(self, name) < 1_000_000:
                raise IdromError(f"IDROM {name} is {getattr(self, name)} Hz, that's too low")


@dataclass(frozen=True, slots=True)
class ModuleDescriptor:
    """One function of the firmware, e.g. 5 stepgens at 0x2000."""

    gtag: int
    version: int
    clock_tag: int
    instances: int
    base_address: int
    num_registers: int
    register_stride_sel: int  # 0: IDROM register stride 0, 1: stride 1
    instance_stride_sel: int
    multiple_registers: int  # bit n set: register n exists once per instance

    FORMAT = struct.Struct("<BBBBHBBI")

    def pack(self) -> bytes:
        strides = (self.instance_stride_sel & 0xF) << 4 | (self.register_stride_sel & 0xF)
        return self.FORMAT.pack(
            self.gtag,
            self.version,
            self.clock_tag,
            self.instances,
            self.base_address,
            self.num_registers,
            strides,
            self.multiple_registers,
        )

    @classmethod
    def unpack(cls, data: bytes) -> ModuleDescriptor:
        gtag, version, clock, instances, base, nregs, strides, multiple = cls.FORMAT.unpack_from(
            data
        )
        reg_sel, inst_sel = strides & 0xF, strides >> 4
        return cls(gtag, version, clock, instances, base, nregs, reg_sel, inst_sel, multiple)

    @property
    def name(self) -> str:
        return FUNCTION_NAMES.get(self.gtag, f"(unknown-gtag-{self.gtag})")


@dataclass(frozen=True, slots=True)
class Module:
    """A module descriptor resolved against its IDROM: clock in Hz and strides in bytes."""

    descriptor: ModuleDescriptor
    clock_hz: int
    register_stride: int
    instance_stride: int

    @classmethod
    def resolve(cls, md: ModuleDescriptor, idrom: Idrom) -> Module:
        if md.clock_tag == CLOCK_LOW_TAG:
            clock = idrom.clock_low
        elif md.clock_tag == CLOCK_HIGH_TAG:
            clock = idrom.clock_high
        else:
            raise IdromError(f"{md.name}: invalid clock tag {md.clock_tag}")
        strides = {
            "register": (idrom.register_stride_0, idrom.register_stride_1),
            "instance": (idrom.instance_stride_0, idrom.instance_stride_1),
        }
        if md.register_stride_sel > 1 or md.instance_stride_sel > 1:
            raise IdromError(f"{md.name}: invalid stride selector")
        return cls(
            md,
            clock,
            strides["register"][md.register_stride_sel],
            strides["instance"][md.instance_stride_sel],
        )

    def address(self, register: int, instance: int = 0) -> int:
        """The byte address of ``register`` (0-based) of ``instance``."""
        md = self.descriptor
        return md.base_address + register * self.register_stride + instance * self.instance_stride


@dataclass(frozen=True, slots=True)
class PinDescriptor:
    """One I/O pin: the secondary function that can own it."""

    sec_pin: int  # function pin number, bit 7 set for an output
    sec_tag: int  # 0: plain GPIO
    sec_unit: int  # instance; bit 7 set: all instances
    primary_tag: int = GTAG_IOPORT

    FORMAT = struct.Struct("<4B")

    def pack(self) -> bytes:
        return self.FORMAT.pack(self.sec_pin, self.sec_tag, self.sec_unit, self.primary_tag)

    @classmethod
    def unpack(cls, data: bytes) -> PinDescriptor:
        return cls(*cls.FORMAT.unpack_from(data))

    @property
    def is_output(self) -> bool:
        return bool(self.sec_pin & PIN_IS_OUTPUT)

    @property
    def pin_number(self) -> int:
        """1-based pin number within the function (step = 1, dir = 2, ...)."""
        return self.sec_pin & 0x7F
