"""hy_vfd: a Huanyang VFD on RS-485, with LinuxCNC's ``hy_vfd`` options and pins.

``loadusr -Wn NAME hy_vfd -n NAME -d /dev/ttyUSB0 [-r 19200 -p none -b 8 -s 1 -t 1]
[-F maxfreq -f minfreq -V volts -I amps -S maxrpm -P poles] [-x PDnnn=value ...] [-g]``

Once ``NAME.enable`` is set it reads the VFD's setup (PD005 max frequency, PD004 base
frequency, PD011 lower limit, PD141/142 rated voltage/current, PD143 poles, PD144 rpm at
50 Hz; the options write them first), then every 0.1 s reads the eight status values
(``SetF``, ``OutF``, ``OutA``, ``Rott``, ``DCV``, ``ACV``, ``Cont``, ``Tmp``), writes the
frequency for ``speed-command`` (rpm) and the run command for ``spindle-forward`` /
``spindle-reverse`` / ``spindle-on``, and reports the status bits (``CNST-*``),
``spindle-speed-fb`` (rpm) and ``spindle-at-speed`` (within
``spindle-at-speed-tolerance``, 2 %).

``hycomm-ok`` is true after more than 10 good exchanges in a row and false from the
first failure; ``error-count`` counts failures and ``retval`` holds the last one's code.
A failure (no port, no answer, bad CRC) is told to the operator when the link goes bad and
when it comes back. The machine is stopped by the HAL wiring: ``hycomm-ok`` into the
spindle's ``amp-fault-in`` (see configs/mesa/custom.hal).
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import time
from typing import Any

from hal.modbus import huanyang as hy
from hal.modbus import rtu
from hal.modbus.rtu import ModbusError, RtuLink

LOOP_S = 0.1
MIN_OK = 10  # good exchanges in a row before hycomm-ok


def _options(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="hy_vfd", description=__doc__.split("\n\n")[0])
    parser.add_argument("-d", "--device", default="/dev/ttyS0")
    parser.add_argument("-n", "--name", default="hy_vfd")
    parser.add_argument("-b", "--bits", type=int, default=8, choices=(5, 6, 7, 8))
    parser.add_argument("-p", "--parity", default="odd", choices=("even", "odd", "none"))
    parser.add_argument(
        "-r", "--rate", type=int, default=38400,
        choices=(110, 300, 600, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200),
    )  # fmt: skip
    parser.add_argument("-s", "--stopbits", type=int, default=1, choices=(1, 2))
    parser.add_argument("-t", "--target", type=int, default=1)
    parser.add_argument("-F", "--max-frequency", type=float, default=0.0)
    parser.add_argument("-f", "--min-frequency", type=float, default=0.0)
    parser.add_argument("-V", "--motor-voltage", type=float, default=0.0)
    parser.add_argument("-I", "--motor-current", type=float, default=0.0)
    parser.add_argument("-S", "--motor-speed", type=float, default=0.0)
    parser.add_argument("-P", "--motor-poles", type=int, default=0)
    parser.add_argument("-x", "--register", action="append", default=[], metavar="PDnnn=value")
    parser.add_argument("-g", "--debug", action="store_true")
    parser.add_argument("-y", "--regdump", action="store_true")
    return parser.parse_args(argv)


def _extra_registers(items: list[str]) -> list[tuple[int, int]]:
    registers = []
    for item in items:
        name, sep, value = item.partition("=")
        try:
            if not sep or not name.upper().startswith("PD"):
                raise ValueError
            registers.append((int(name[2:]), int(value)))
        except ValueError:
            raise SystemExit(f"hy_vfd: --register wants PDnnn=value, not '{item}'") from None
    return registers


class HyVfd:
    """The HAL component and the exchanges with one VFD."""

    def __init__(self, options: argparse.Namespace, link: Any = None) -> None:
        from hal.api import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_OUT, HAL_RW, HAL_S32, HAL_U32, component
        from hal.operator_messages import operator_channel

        self.options = options
        self.name = options.name
        self.slave = options.target
        self.link = link or RtuLink(
            options.device, options.rate, options.bits, options.parity, options.stopbits
        )
        self.extra = _extra_registers(options.register)
        self.comp = c = component(self.name)
        pins: dict[str, Any] = {}

        def new(name: str, hal_type: int, direction: int) -> None:
            pins[name] = c.newpin(name, hal_type, direction)

        new("enable", HAL_BIT, HAL_IN)
        for name in hy.STATUS_NAMES:
            new(name, HAL_FLOAT, HAL_OUT)
        for name in ("spindle-forward", "spindle-reverse", "spindle-on"):
            new(name, HAL_BIT, HAL_IN)
        new("CNTR", HAL_FLOAT, HAL_OUT)
        new("CNST", HAL_FLOAT, HAL_OUT)
        for bit in hy.CNST_BITS:
            new(f"CNST-{bit}", HAL_BIT, HAL_OUT)
        new("speed-command", HAL_FLOAT, HAL_IN)
        new("frequency-command", HAL_FLOAT, HAL_OUT)
        for name in ("max-freq", "base-freq", "freq-lower-limit", "rated-motor-voltage",
                     "rated-motor-current", "rated-motor-rev"):  # fmt: skip
            new(name, HAL_FLOAT, HAL_OUT)
        new("motor-poles", HAL_U32, HAL_OUT)
        new("hycomm-ok", HAL_BIT, HAL_OUT)
        new("spindle-speed-fb", HAL_FLOAT, HAL_OUT)
        new("spindle-at-speed", HAL_BIT, HAL_OUT)
        new("spindle-at-speed-tolerance", HAL_FLOAT, HAL_IN)
        self.error_count = c.newparam("error-count", HAL_S32, HAL_RW)
        self.retval = c.newparam("retval", HAL_FLOAT, HAL_RW)
        self.pins = pins
        pins["spindle-at-speed-tolerance"].set(0.02)
        # what the options ask to program (0: read it from the VFD)
        pins["max-freq"].set(options.max_frequency)
        pins["freq-lower-limit"].set(options.min_frequency)
        pins["rated-motor-voltage"].set(options.motor_voltage)
        pins["rated-motor-current"].set(options.motor_current)
        pins["rated-motor-rev"].set(options.motor_speed)
        pins["motor-poles"].set(options.motor_poles)
        self.ok_count = 0
        self.is_link_bad = False
        self.is_setup_read = False
        self.is_stopping = False
        self.tell = operator_channel("tool")
        c.ready()

    # ------------------------------------------------------------ exchanges
    def exchange(self, function: int, *, register: int = 0, value: int = 0) -> int:
        frame = hy.request(self.slave, function, register=register, value=value)
        body = self.link.transact(frame, hy.ANSWER_BYTES[function], 0.5, 0.5)
        return hy.answer_value(function, body)

    def read_register(self, register: int) -> int:
        return self.exchange(hy.READ_REGISTER, register=register)

    def write_register(self, register: int, value: float) -> None:
        self.exchange(hy.WRITE_REGISTER, register=register, value=int(value))

    def read_setup(self) -> None:
        """The VFD's limits, programmed first where the options gave them."""
        pins = self.pins
        for register, pin, scale in ((5, "max-freq", 100), (4, "base-freq", 100),
                                     (11, "freq-lower-limit", 100),
                                     (141, "rated-motor-voltage", 10),
                                     (142, "rated-motor-current", 10)):  # fmt: skip
            wanted = pins[pin].get()
            if wanted:
                self.write_register(register, wanted * scale)
            pins[pin].set(self.read_register(register) / scale)
        if pins["motor-poles"].get():
            self.write_register(143, pins["motor-poles"].get())
        pins["motor-poles"].set(self.read_register(143))
        max_freq = pins["max-freq"].get()
        wanted_rpm = pins["rated-motor-rev"].get()
        if wanted_rpm and max_freq:
            self.write_register(144, wanted_rpm / max_freq * 50.0)
        rpm_at_50 = self.read_register(144)
        pins["rated-motor-rev"].set(rpm_at_50 / 50.0 * max_freq)
        for register, value in self.extra:
            self.write_register(register, value)
            self.read_register(register)
        self.is_setup_read = True

    def read_data(self) -> None:
        pins = self.pins
        values = [self.exchange(hy.READ_STATUS, value=n) for n in range(8)]
        scales = (0.01, 0.01, 0.1, 1, 1, 1, 1, 1)
        for name, value, scale in zip(hy.STATUS_NAMES, values, scales, strict=True):
            pins[name].set(value * scale)
        command = abs(pins["speed-command"].get())
        max_freq, rated = pins["max-freq"].get(), pins["rated-motor-rev"].get()
        if pins["spindle-on"].get() and command > 0 and pins["SetF"].get() > 0 and max_freq:
            speed = pins["OutF"].get() / max_freq * rated
            pins["spindle-speed-fb"].set(speed)
            tolerance = pins["spindle-at-speed-tolerance"].get()
            pins["spindle-at-speed"].set(abs(1 - speed / command) < tolerance)
        else:
            pins["spindle-speed-fb"].set(0.0)
            pins["spindle-at-speed"].set(False)

    def write_data(self) -> None:
        pins = self.pins
        forward, reverse = pins["spindle-forward"].get(), pins["spindle-reverse"].get()
        is_on = pins["spindle-on"].get()
        max_freq, rated = pins["max-freq"].get(), pins["rated-motor-rev"].get()
        hz_per_rpm = max_freq / rated if rated else 0.0
        frequency = abs(pins["speed-command"].get()) * hz_per_rpm * 100
        frequency = min(max(frequency, pins["freq-lower-limit"].get() * 100), max_freq * 100)
        if int(frequency) != int(pins["frequency-command"].get()):
            self.exchange(hy.WRITE_FREQUENCY, value=int(frequency))
            pins["frequency-command"].set(int(frequency))
        if is_on and forward and not reverse:
            control = hy.RUN_FORWARD
        elif is_on and reverse and not forward:
            control = hy.RUN_REVERSE
        else:
            control = hy.STOP
        status = self.exchange(hy.WRITE_CONTROL, value=control)
        pins["CNTR"].set(control)
        pins["CNST"].set(status)
        for bit, name in enumerate(hy.CNST_BITS):
            pins[f"CNST-{name}"].set(bool(status >> bit & 1))

    # ------------------------------------------------------------ the loop
    def cycle(self) -> None:
        """One exchange round: setup once, then status and commands."""
        try:
            if not self.is_setup_read:
                self.read_setup()
            self.read_data()
            self.write_data()
        except ModbusError as exc:
            self.ok_count = 0
            self.error_count.set(self.error_count.get() + 1)
            self.retval.set(exc.code)
            if isinstance(exc, rtu.PortError):
                self.link.close()
            if not self.is_link_bad:
                self.is_link_bad = True
                self.report_link_lost(str(exc))
        else:
            self.ok_count += 1
            self.retval.set(0)
            if self.is_link_bad and self.ok_count > MIN_OK:
                self.is_link_bad = False
                self.say("the VFD answers again")
        self.pins["hycomm-ok"].set(self.ok_count > MIN_OK)

    def say(self, text: str) -> None:
        print(f"{self.name}: {text}", file=sys.stderr, flush=True)

    def report_link_lost(self, cause: str) -> None:
        """The VFD link failed: the single place this component raises an alarm
        (stderr and the operator's error channel; ``hycomm-ok`` drops, and the HAL wiring
        turns that into a spindle fault that stops the machine)."""
        text = f"VFD link lost: {cause}"
        self.say(text)
        if self.tell is not None:
            with contextlib.suppress(Exception):
                self.tell(f"{self.name}: {text}")

    def run(self) -> None:
        while not self.is_stopping:
            started = time.monotonic()
            if self.pins["enable"].get():
                self.cycle()
            time.sleep(max(LOOP_S - (time.monotonic() - started), 0.001))


def main(argv: list[str] | None = None) -> int:
    options = _options(sys.argv[1:] if argv is None else argv)
    vfd = HyVfd(options)

    def stop(*_: object) -> None:
        vfd.is_stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    try:
        vfd.run()
    finally:
        vfd.link.close()
        vfd.comp.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
