"""Firmware layouts: what a board's HostMot2 configuration contains, as IDROM data.

``SEVEN_I96S`` is the 7I96S with its stock configuration (``7i96s_d``): 51 I/O pins on
three 17-pin ports (TB3: 11 isolated inputs and 6 SSR outputs; TB1/TB2: 5 step/dir
channels, one encoder, the RS-422 pair; P1: 17 expansion GPIO), a watchdog, a DPLL,
one PWM generator (the isolated spindle analog output, hard-wired: no I/O pin), four
LEDs. The register bases follow HostMot2's register map; the SSR and OutM bases are this
layout's choice (a driver finds them in the module descriptors anyway). The smart-serial
port is not described (its pins are plain GPIO here).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from hal.hm2.idrom import (
    CLOCK_HIGH_TAG,
    CLOCK_LOW_TAG,
    GLOBAL_UNIT,
    GTAG_ENCODER,
    GTAG_HM2DPLL,
    GTAG_INM,
    GTAG_IOPORT,
    GTAG_LED,
    GTAG_OUTM,
    GTAG_PWMGEN,
    GTAG_SSR,
    GTAG_STEPGEN,
    GTAG_WATCHDOG,
    PIN_IS_OUTPUT,
    Idrom,
    ModuleDescriptor,
    PinDescriptor,
)

IDROM_ADDRESS = 0x0400
OFFSET_TO_MODULES = 0x0040
OFFSET_TO_PINS = 0x0200


@dataclass(frozen=True)
class Firmware:
    """A board and its firmware: the LBP16 board name, the IDROM, modules and pins."""

    board_name: str  # what LBP16's board information space says, e.g. "7I96S"
    idrom: Idrom
    modules: tuple[ModuleDescriptor, ...]
    pins: tuple[PinDescriptor, ...]
    pin_names: tuple[str, ...] = field(default=())  # connector pin of each I/O (manuals)
    num_leds: int = 0

    def module(self, gtag: int) -> ModuleDescriptor | None:
        return next((md for md in self.modules if md.gtag == gtag), None)


def _md(gtag: int, version: int, instances: int, base: int, nregs: int, multiple: int, *,
        clock: int = CLOCK_LOW_TAG) -> ModuleDescriptor:  # fmt: skip
    return ModuleDescriptor(gtag, version, clock, instances, base, nregs, 0, 0, multiple)


def _pin(tag: int, unit: int, number: int, *, is_output: bool = False) -> PinDescriptor:
    return PinDescriptor(number | (PIN_IS_OUTPUT if is_output else 0), tag, unit)


def _gpio() -> PinDescriptor:
    return PinDescriptor(0, 0, 0)


def _seven_i96s() -> Firmware:
    pins: list[PinDescriptor] = []
    pins += [_pin(GTAG_INM, 0, n + 1) for n in range(11)]  # TB3 isolated inputs 0-10
    pins += [_pin(GTAG_SSR, 0, n + 1, is_output=True) for n in range(4)]  # SSR outputs 0-3
    pins += [_pin(GTAG_OUTM, 0, n + 5, is_output=True) for n in range(2)]  # outputs 4, 5
    for channel in range(5):  # TB1: step/dir 0-3, TB2: step/dir 4
        pins.append(_pin(GTAG_STEPGEN, channel, 1, is_output=True))
        pins.append(_pin(GTAG_STEPGEN, channel, 2, is_output=True))
    pins += [_pin(GTAG_ENCODER, 0, n) for n in (1, 2, 3)]  # TB2: encoder A, B, index
    pins += [_gpio() for _ in range(3)]  # RS-422 RX/TX and its TX enable (no smart-serial)
    pins.append(_pin(GTAG_SSR, GLOBAL_UNIT, 32, is_output=True))  # SSR AC reference
    pins += [_gpio() for _ in range(17)]  # P1 expansion connector
    names = (
        *(f"TB3-{n:02d}" for n in range(1, 12)),
        *(f"TB3-{n:02d}/TB3-{n + 1:02d}" for n in range(13, 25, 2)),
        *(f"TB1-{a:02d}/TB1-{a + 1:02d}" for a in (2, 4, 8, 10, 14, 16, 20, 22)),
        *(f"TB2-{a:02d}/TB2-{a + 1:02d}" for a in (2, 4, 7, 10, 13, 16, 18)),
        "internal",
        "internal",
        *(f"P1-{p:02d}" for p in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 13, 15, 17, 19, 21, 23, 25)),
    )
    modules = (
        _md(GTAG_HM2DPLL, 0, 1, 0x7000, 7, 0x0000),
        _md(GTAG_WATCHDOG, 0, 1, 0x0C00, 3, 0x0000),
        _md(GTAG_IOPORT, 0, 3, 0x1000, 5, 0x001F),
        _md(GTAG_ENCODER, 3, 1, 0x3000, 5, 0x0003),
        _md(GTAG_STEPGEN, 2, 5, 0x2000, 10, 0x01FF),
        _md(GTAG_PWMGEN, 0, 1, 0x4100, 5, 0x0003, clock=CLOCK_HIGH_TAG),
        _md(GTAG_SSR, 0, 1, 0xB400, 2, 0x0003),
        _md(GTAG_OUTM, 0, 1, 0xB600, 1, 0x0001),
        _md(GTAG_INM, 0, 1, 0x8500, 5, 0x001F),
        _md(GTAG_LED, 0, 1, 0x0200, 1, 0x0000),
    )
    idrom = Idrom(
        idrom_type=3,
        offset_to_modules=OFFSET_TO_MODULES,
        offset_to_pins=OFFSET_TO_PINS,
        board_name=b"MESA7I96",
        fpga_size=20,
        fpga_pins=256,
        io_ports=3,
        io_width=51,
        port_width=17,
        clock_low=100_000_000,
        clock_high=200_000_000,
        instance_stride_0=4,
        instance_stride_1=0x40,
        register_stride_0=0x100,
        register_stride_1=4,
    )
    return Firmware("7I96S", idrom, modules, tuple(pins), names, num_leds=4)


SEVEN_I96S = _seven_i96s()
FIRMWARES = {"7i96s": SEVEN_I96S}
