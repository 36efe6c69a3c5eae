"""A simulated Huanyang VFD and spindle motor on a pseudo-terminal, for sim configs and tests.

``python -m hal.modbus.vfd_sim --link PATH [--baud 19200] [--slave 1] [--hal NAME]``
makes a pseudo-terminal pair, links PATH to its serial end (give PATH to ``hy_vfd -d``),
and answers Huanyang requests as a VFD driving a 24000 rpm, 400 Hz, 2-pole spindle:
the output frequency ramps to the set frequency at 400 Hz/s while running, back to 0
when stopped, turning round through 0 on reversal. Answers wait as long as the frames
take on a wire at the baud rate, so throughput is that of a real line.

With ``--hal NAME`` it is a userspace HAL component: ``NAME.frequency`` (Hz, negative in
reverse), ``NAME.rpm``, ``NAME.is-running``, ``NAME.is-reverse`` (out), and for tests
``NAME.is-mute`` (no answers: a cut cable) and ``NAME.is-corrupt`` (answers with a bad
CRC: noise) (in).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import select
import signal
import sys
import termios
import time
import tty
from pathlib import Path

from hal.modbus import huanyang as hy
from hal.modbus import rtu

REQUEST_BYTES = {hy.READ_REGISTER: 8, hy.WRITE_REGISTER: 8, hy.WRITE_CONTROL: 6,
                 hy.READ_STATUS: 6, hy.WRITE_FREQUENCY: 7}  # fmt: skip
RAMP_HZ_PER_S = 400.0
FRAME_GAP_S = 0.05  # a partial frame older than this is noise: dropped


class PtyPort:
    """The device end of a pseudo-terminal pair; the other end is a serial port path."""

    def __init__(self, link: str = "") -> None:
        self.fd, self.peer_fd = os.openpty()
        tty.setraw(self.peer_fd)
        attributes = termios.tcgetattr(self.peer_fd)
        attributes[3] &= ~termios.ECHO
        termios.tcsetattr(self.peer_fd, termios.TCSANOW, attributes)
        self.path = os.ttyname(self.peer_fd)
        self.link = link
        if link:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(link)
            os.symlink(self.path, link)

    def read(self, size: int, timeout: float) -> bytes:
        data = b""
        deadline = time.monotonic() + timeout
        while len(data) < size:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not select.select([self.fd], [], [], remaining)[0]:
                break
            data += os.read(self.fd, size - len(data))
        return data

    def write(self, data: bytes) -> None:
        os.write(self.fd, data)

    def close(self) -> None:
        if self.link:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self.link)
        for fd in (self.fd, self.peer_fd):
            with contextlib.suppress(OSError):
                os.close(fd)


class SimVfd:
    """The VFD's registers, its run state and the motor's frequency."""

    def __init__(self, slave: int = 1, baud: int = 19200, bits_per_char: int = 10) -> None:
        self.slave = slave
        self.baud = baud
        self.bits_per_char = bits_per_char
        self.registers = {4: 40000, 5: 40000, 11: 10000, 141: 2200, 142: 80, 143: 2, 144: 3000}
        self.set_frequency = 0  # x 100
        self.output_hz = 0.0  # negative in reverse
        self.control = hy.STOP
        self.last_time = time.monotonic()
        self.is_mute = False
        self.is_corrupt = False
        self.requests = 0

    def advance(self, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        elapsed, self.last_time = now - self.last_time, now
        target = 0.0
        if self.control == hy.RUN_FORWARD:
            target = self.set_frequency / 100
        elif self.control == hy.RUN_REVERSE:
            target = -self.set_frequency / 100
        step = RAMP_HZ_PER_S * elapsed
        self.output_hz = min(max(target, self.output_hz - step), self.output_hz + step)

    @property
    def rpm(self) -> float:
        poles = self.registers.get(143, 2) or 2
        return self.output_hz * 120.0 / poles

    def status_word(self) -> int:
        word = 0
        if self.control in (hy.RUN_FORWARD, hy.RUN_REVERSE):
            word |= 0x01
        if self.control == hy.RUN_REVERSE:
            word |= 0x04
        if abs(self.output_hz) > 0.005:
            word |= 0x08
            if self.output_hz < 0:
                word |= 0x20
        return word

    def status_value(self, which: int) -> int:
        values = {
            hy.STATUS_SETF: self.set_frequency,
            hy.STATUS_OUTF: round(abs(self.output_hz) * 100),
            hy.STATUS_OUTA: round(abs(self.output_hz) / 400 * 60),  # 6 A at full speed
            hy.STATUS_ROTT: round(abs(self.rpm)),
            hy.STATUS_DCV: 310,
            hy.STATUS_ACV: 220,
            hy.STATUS_CONT: 0,
            hy.STATUS_TMP: 35,
        }
        return values.get(which, 0)

    def answer(self, request: bytes) -> bytes | None:
        """The answer frame to a request frame, or None (not for us, or broken)."""
        self.requests += 1
        try:
            body = rtu.check_frame(request)
        except rtu.BadCrcError:
            return None
        if body[0] != self.slave:
            return None
        self.advance()
        function = body[1]
        if function in (hy.READ_REGISTER, hy.WRITE_REGISTER):
            register, value = body[3], int.from_bytes(body[4:6], "big")
            if function == hy.WRITE_REGISTER:
                self.registers[register] = value
            return hy.answer(self.slave, function, register, self.registers.get(register, 0))
        if function == hy.READ_STATUS:
            which = body[3]
            return hy.answer(self.slave, function, which, self.status_value(which))
        if function == hy.WRITE_CONTROL:
            if body[3] in (hy.RUN_FORWARD, hy.RUN_REVERSE, hy.STOP):
                self.control = body[3]
            return hy.answer(self.slave, function, 0, self.status_word())
        if function == hy.WRITE_FREQUENCY:
            limit = self.registers.get(5, 40000)
            self.set_frequency = min(int.from_bytes(body[3:5], "big"), limit)
            return hy.answer(self.slave, function, 0, self.set_frequency)
        return None

    def wire_time(self, request: bytes, answer: bytes) -> float:
        """How long both frames take on a line at this baud rate (and the turnaround)."""
        return (len(request) + len(answer)) * self.bits_per_char / self.baud


def serve(vfd: SimVfd, port: PtyPort, is_stopping, on_cycle=None) -> None:
    """Answer requests until ``is_stopping()``."""
    pending = b""
    last = time.monotonic()
    while not is_stopping():
        chunk = port.read(1, 0.02)
        now = time.monotonic()
        if on_cycle is not None:
            on_cycle()
        if not chunk:
            vfd.advance(now)
            if pending and now - last > FRAME_GAP_S:
                pending = b""
            continue
        last = now
        pending += chunk
        if len(pending) >= 2:
            wanted = REQUEST_BYTES.get(pending[1], 0)
            if not wanted:
                pending = b""
                continue
            if len(pending) < wanted:
                pending += port.read(wanted - len(pending), 0.05)
            request, pending = pending[:wanted], pending[wanted:]
            answer = vfd.answer(request)
            if answer is None or vfd.is_mute:
                continue
            time.sleep(vfd.wire_time(request, answer))
            if vfd.is_corrupt:
                answer = answer[:-1] + bytes((answer[-1] ^ 0xFF,))
            port.write(answer)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hy_vfd_sim", description=__doc__.split("\n\n")[0])
    parser.add_argument("--link", required=True, help="path to link to the serial port")
    parser.add_argument("--baud", type=int, default=19200)
    parser.add_argument("--slave", type=int, default=1)
    parser.add_argument("--hal", default="", metavar="NAME")
    args = parser.parse_args(argv)
    vfd = SimVfd(args.slave, args.baud)
    port = PtyPort(str(Path(args.link).expanduser()))
    stopping = []
    signal.signal(signal.SIGTERM, lambda *_: stopping.append(1))
    signal.signal(signal.SIGINT, lambda *_: stopping.append(1))
    on_cycle = None
    comp = None
    if args.hal:
        from hal.api import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_OUT, component

        comp = component(args.hal)
        out = {name: comp.newpin(name, HAL_FLOAT, HAL_OUT) for name in ("frequency", "rpm")}
        flags = {name: comp.newpin(name, HAL_BIT, HAL_OUT) for name in ("is-running", "is-reverse")}
        faults = {name: comp.newpin(name, HAL_BIT, HAL_IN) for name in ("is-mute", "is-corrupt")}
        comp.ready()

        def on_cycle() -> None:
            vfd.is_mute = faults["is-mute"].get()
            vfd.is_corrupt = faults["is-corrupt"].get()
            out["frequency"].set(vfd.output_hz)
            out["rpm"].set(vfd.rpm)
            flags["is-running"].set(abs(vfd.output_hz) > 0.005)
            flags["is-reverse"].set(vfd.output_hz < 0)

    print(f"hy_vfd_sim: VFD {args.slave} on {port.path} ({args.link})", file=sys.stderr, flush=True)
    try:
        serve(vfd, port, lambda: bool(stopping), on_cycle)
    finally:
        port.close()
        if comp is not None:
            comp.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
