"""A simulated Mesa Ethernet board (7I96S by default) answering LBP16 over UDP.

``python -m hal.hm2.sim [--ip 127.0.0.1] [--port 27181] [--hal NAME]`` serves until it
is signalled. Any LBP16 client sees a board: ``hm2_eth`` here and LinuxCNC's own read the
same IDROM, module and pin descriptors from it (``firmware.SEVEN_I96S``).

What the FPGA functions do, modelled in time (the board's clock is the monotonic clock):

- IOPort: data, direction, alternate source, open drain and output inversion per port;
  reading the data registers returns the pin levels (outputs: what is driven; inputs:
  what the field drives, ``set_field_inputs``).
- Watchdog: loaded with a timeout in clocks (bit 31: disabled), petted by writing its
  reset register; when the timeout passes without a pet it bites: status bit 0 is set and
  every I/O pin becomes an input, so no step, SSR or GPIO output reaches the machine,
  until the host clears the status and rewrites the directions.
- StepGen: a 48-bit accumulator adds the signed rate register every clock; its upper 32
  bits (16.16 steps) are the readable accumulator. Step pins are driven while the pins are
  outputs; ``step_position()`` gives the motor's position in steps.
- Encoder: the counter follows the field count (``encoder_counts``), 16 bits with a
  16-bit timestamp of the last count; clear/latch on index when the control register
  asks for it.
- PWM, SSR, OutM, LED, DPLL: registers kept; the SSR/OutM data drive their pins.
- InM: its inputs' levels; the control register reads the scan width.

Fault injection, for tests: ``drop_one_in`` = N drops every N-th answer (1: all),
``is_mute`` answers nothing. With ``--hal NAME`` the field side is HAL pins of a
userspace component: ``NAME.io.NNN.in`` (bit in, what the field drives on pin NNN),
``NAME.io.NNN.out`` (bit out, the pin's level), ``NAME.io.NNN.is-output``,
``NAME.stepgen.NN.position`` (steps) and ``.rate`` (steps/s), ``NAME.encoder.NN.counts``
(s32 in), ``NAME.encoder.NN.index`` (bit in), ``NAME.pwmgen.NN.duty`` and ``.enable``,
``NAME.led.NN``, ``NAME.watchdog.has-bit``, and ``NAME.drop-one-in`` (u32 in),
``NAME.is-mute`` (bit in).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import socket
import struct
import sys
import time
from collections.abc import Callable

from hal.hm2 import lbp16
from hal.hm2.firmware import FIRMWARES, IDROM_ADDRESS, Firmware
from hal.hm2.idrom import (
    CONFIG_NAME,
    CONFIG_NAME_ADDRESS,
    COOKIE,
    COOKIE_ADDRESS,
    GTAG_ENCODER,
    GTAG_INM,
    GTAG_IOPORT,
    GTAG_LED,
    GTAG_OUTM,
    GTAG_PWMGEN,
    GTAG_SSR,
    GTAG_STEPGEN,
    GTAG_WATCHDOG,
    IDROM_POINTER_ADDRESS,
    MODULE_DESCRIPTOR_BYTES,
    Module,
)

_U32 = struct.Struct("<I")
MASK32 = 0xFFFFFFFF
WATCHDOG_DISABLED = 0x80000000
WATCHDOG_PET_COOKIE = 0x5A
IDLE_TICK_S = 0.002  # the model advances (watchdog bites) even when no packet comes
FIELD_SYNC_NS = 1_000_000  # how often the HAL pins of the connectors are updated
SIM_PRIORITY = 80  # SCHED_FIFO, under the realtime host's (99 and down)
BOARD_MAC = bytes((0x00, 0x60, 0x1B, 0x96, 0x00, 0x01))  # Mesa's prefix, a made-up rest


class SimBoard:
    """The board's memory spaces and functions; ``handle(datagram)`` answers LBP16."""

    def __init__(self, firmware: Firmware, clock: Callable[[], int] = time.monotonic_ns) -> None:
        self.firmware = firmware
        self.clock = clock
        self._levels: dict[int, int] = {}  # port -> pin levels, for the current datagram
        idrom = firmware.idrom
        self.modules = {md.gtag: Module.resolve(md, idrom) for md in firmware.modules}
        self.num_pins = idrom.io_width
        self.port_width = idrom.port_width
        self.static = self._static_image()
        self.regs: dict[int, int] = {}  # every other written register, as written
        # field side: what drives the input pins (TB3 inputs idle low, pulled-up pins high),
        # one bit per pin of each port
        self.field_ports = [0] * idrom.io_ports
        self.set_field_inputs([pd.sec_tag != GTAG_INM for pd in firmware.pins])
        self.encoder_counts = [0] * self._instances(GTAG_ENCODER)
        self.encoder_index = [False] * self._instances(GTAG_ENCODER)
        # IOPort registers per port
        ports = idrom.io_ports
        self.port_data = [0] * ports
        self.port_ddr = [0] * ports
        self.port_alt = [0] * ports
        self.port_open_drain = [0] * ports
        self.port_invert = [0] * ports
        # watchdog
        self.wd_timer = WATCHDOG_DISABLED
        self.wd_status = 0
        self.wd_last_pet = clock()
        # stepgens: rate registers and 48-bit accumulators (32 fraction bits)
        n_step = self._instances(GTAG_STEPGEN)
        self.step_rate = [0] * n_step
        self.step_acc = [0] * n_step
        step = self.modules.get(GTAG_STEPGEN)
        self.step_clock = step.clock_hz if step else 1
        self.step_ticks = self._ticks(clock())
        # encoders: the counter's own count (after clear-on-index) and last timestamp
        n_enc = self._instances(GTAG_ENCODER)
        self.enc_count = [0] * n_enc
        self.enc_seen = [0] * n_enc  # field counts already taken in
        self.enc_control = [0] * n_enc
        self.enc_timestamp = [0] * n_enc
        self.enc_latch = [0] * n_enc
        # fault injection and statistics
        self.drop_one_in = 0
        self.is_mute = False
        self.rx_packets = 0
        self.answers = 0
        self.answers_due = 0
        self.parse_errors = 0
        self.timer_space = bytearray(64)
        self._read_hooks: dict[int, Callable[[], int]] = {}
        self._write_hooks: dict[int, Callable[[int], None]] = {}
        self._map_pins()
        self._install_hooks()

    # ------------------------------------------------------------ layout
    def _instances(self, gtag: int) -> int:
        module = self.modules.get(gtag)
        return module.descriptor.instances if module else 0

    def _static_image(self) -> dict[int, int]:
        """The read-only registers: cookie, name, IDROM pointer, IDROM, descriptors."""
        fw = self.firmware
        image: dict[int, int] = {COOKIE_ADDRESS: COOKIE, IDROM_POINTER_ADDRESS: IDROM_ADDRESS}
        blobs = [
            (CONFIG_NAME_ADDRESS, CONFIG_NAME),
            (IDROM_ADDRESS, fw.idrom.pack()),
            (
                IDROM_ADDRESS + fw.idrom.offset_to_modules,
                b"".join(md.pack() for md in fw.modules) + bytes(MODULE_DESCRIPTOR_BYTES),
            ),
            (IDROM_ADDRESS + fw.idrom.offset_to_pins, b"".join(pd.pack() for pd in fw.pins)),
        ]
        for address, blob in blobs:
            padded = blob + bytes(-len(blob) % 4)
            for offset in range(0, len(padded), 4):
                image[address + offset] = _U32.unpack_from(padded, offset)[0]
        return image

    def _install_hooks(self) -> None:
        ioport = self.modules.get(GTAG_IOPORT)
        if ioport:
            for port in range(ioport.descriptor.instances):
                self._read_hooks[ioport.address(0, port)] = lambda p=port: self._read_port(p)
                for reg, table in enumerate(
                    (self.port_data, self.port_ddr, self.port_alt, self.port_open_drain,
                     self.port_invert)
                ):  # fmt: skip
                    self._write_hooks[ioport.address(reg, port)] = lambda v, t=table, p=port: (
                        t.__setitem__(p, v)
                    )
                    if reg:
                        self._read_hooks[ioport.address(reg, port)] = lambda t=table, p=port: t[p]
        wd = self.modules.get(GTAG_WATCHDOG)
        if wd:
            self._write_hooks[wd.address(0)] = self._write_wd_timer
            self._read_hooks[wd.address(0)] = lambda: self.wd_timer
            self._write_hooks[wd.address(1)] = self._write_wd_status
            self._read_hooks[wd.address(1)] = lambda: self.wd_status
            self._write_hooks[wd.address(2)] = self._write_wd_reset
        step = self.modules.get(GTAG_STEPGEN)
        if step:
            for i in range(step.descriptor.instances):
                self._write_hooks[step.address(0, i)] = lambda v, i=i: self._write_rate(i, v)
                self._read_hooks[step.address(0, i)] = lambda i=i: self.step_rate[i] & MASK32
                self._read_hooks[step.address(1, i)] = lambda i=i: self._read_accumulator(i)
        enc = self.modules.get(GTAG_ENCODER)
        if enc:
            for i in range(enc.descriptor.instances):
                self._read_hooks[enc.address(0, i)] = lambda i=i: self._read_counter(i)
                self._write_hooks[enc.address(0, i)] = lambda v, i=i: self._clear_counter(i)
                self._read_hooks[enc.address(1, i)] = lambda i=i: self._read_enc_control(i)
                self._write_hooks[enc.address(1, i)] = lambda v, i=i: self._write_enc_control(i, v)
            self._read_hooks[enc.address(3)] = lambda: self._timestamp()
        inm = self.modules.get(GTAG_INM)
        if inm:
            width = sum(1 for pd in self.firmware.pins if pd.sec_tag == GTAG_INM)
            for i in range(inm.descriptor.instances):
                self._read_hooks[inm.address(0, i)] = lambda w=width: (w - 1) & 0x1F
                self._read_hooks[inm.address(2, i)] = lambda i=i: self._read_inm(i)
                self._read_hooks[inm.address(3, i)] = lambda i=i: self._read_inm(i)

    # ------------------------------------------------------------ time
    def _ticks(self, now_ns: int) -> int:
        return now_ns * self.step_clock // 1_000_000_000

    def advance(self, now_ns: int | None = None) -> None:
        """Bring the model to ``now_ns``: stepgens move, the watchdog may bite."""
        now = self.clock() if now_ns is None else now_ns
        ticks = self._ticks(now)
        elapsed = ticks - self.step_ticks
        if elapsed > 0:
            for i, rate in enumerate(self.step_rate):
                if rate:
                    self.step_acc[i] += rate * elapsed
            self.step_ticks = ticks
        self._check_watchdog(now)

    def _check_watchdog(self, now: int) -> None:
        wd = self.modules.get(GTAG_WATCHDOG)
        if not wd or self.wd_timer & WATCHDOG_DISABLED or self.wd_status & 1:
            return
        timeout_ns = (self.wd_timer + 1) * 1_000_000_000 // wd.clock_hz
        if now - self.wd_last_pet > timeout_ns:
            self.bite()

    def bite(self) -> None:
        """The watchdog bites: status bit 0, and every pin an input."""
        self._levels.clear()
        self.wd_status |= 1
        self.port_ddr[:] = [0] * len(self.port_ddr)  # in place: the register hooks hold it

    @property
    def has_bit(self) -> bool:
        return bool(self.wd_status & 1)

    # ------------------------------------------------------------ watchdog registers
    def _write_wd_timer(self, value: int) -> None:
        self.wd_timer = value
        self.wd_last_pet = self.clock()

    def _write_wd_status(self, value: int) -> None:
        self.wd_status = value & 1

    def _write_wd_reset(self, value: int) -> None:
        if value >> 24 == WATCHDOG_PET_COOKIE:
            self.wd_last_pet = self.clock()

    # ------------------------------------------------------------ stepgen
    def _write_rate(self, index: int, value: int) -> None:
        self.advance()
        self.step_rate[index] = value - (1 << 32) if value & 0x80000000 else value

    def _read_accumulator(self, index: int) -> int:
        return (self.step_acc[index] >> 16) & MASK32

    def step_position(self, index: int) -> float:
        """Steps made by stepgen ``index`` since start (with the fraction of a step)."""
        return self.step_acc[index] / 2**32

    def step_rate_hz(self, index: int) -> float:
        return self.step_rate[index] * self.step_clock / 2**32

    # ------------------------------------------------------------ encoder
    def _timestamp(self) -> int:
        enc = self.modules[GTAG_ENCODER]
        return (self.clock() * enc.clock_hz // 1_000_000_000 // 64) & 0xFFFF

    def _take_counts(self, index: int) -> None:
        field = self.encoder_counts[index]
        delta = field - self.enc_seen[index]
        if delta:
            self.enc_seen[index] = field
            self.enc_count[index] += delta
            self.enc_timestamp[index] = self._timestamp()
        control = self.enc_control[index]
        if self.encoder_index[index] and control & (1 << 4 | 1 << 5):  # latch/clear on index
            self.enc_latch[index] = self.enc_count[index]
            if control & (1 << 5):
                self.enc_count[index] = 0
            if control & (1 << 6):  # just once
                self.enc_control[index] &= ~(1 << 4 | 1 << 5)

    def _read_counter(self, index: int) -> int:
        self._take_counts(index)
        return (self.enc_timestamp[index] << 16) | (self.enc_count[index] & 0xFFFF)

    def _clear_counter(self, index: int) -> None:
        self._take_counts(index)
        self.enc_count[index] = 0

    def _read_enc_control(self, index: int) -> int:
        self._take_counts(index)
        a, b, idx = (self._pin_level(io) for io in self.encoder_pins[index])
        inputs = int(a) | int(b) << 1 | int(idx or self.encoder_index[index]) << 2
        latch = self.enc_latch[index] & 0xFFFF
        return (latch << 16) | (self.enc_control[index] & 0xFFF8) | inputs

    def _write_enc_control(self, index: int, value: int) -> None:
        self.enc_control[index] = value & 0xFFFF

    # ------------------------------------------------------------ pins
    def _map_pins(self) -> None:
        """Where each function's pins are: (port, bit) tables used on every read."""
        width = self.port_width
        self.dir_bits: list[tuple[int, int]] = []  # stepgen i's direction pin (port, mask)
        self.module_data_bits: list[tuple[int, int, int, int]] = []  # (gtag, unit, bit, io)
        self.encoder_pins: list[list[int | None]] = []
        self.inm_pins: list[list[tuple[int, int]]] = []  # per instance: (input bit, io)
        for io, pd in enumerate(self.firmware.pins):
            if pd.sec_tag == GTAG_STEPGEN and pd.pin_number == 2:
                while len(self.dir_bits) <= pd.sec_unit:
                    self.dir_bits.append((0, 0))
                self.dir_bits[pd.sec_unit] = (io // width, 1 << io % width)
            elif pd.sec_tag in (GTAG_SSR, GTAG_OUTM) and pd.sec_unit < 0x80:
                self.module_data_bits.append((pd.sec_tag, pd.sec_unit, pd.pin_number - 1, io))
        for unit in range(self._instances(GTAG_ENCODER)):
            self.encoder_pins.append(
                [self._module_pin(GTAG_ENCODER, unit, number) for number in (1, 2, 3)]
            )
        for unit in range(self._instances(GTAG_INM)):
            self.inm_pins.append(
                [
                    (pd.pin_number - 1, io)
                    for io, pd in enumerate(self.firmware.pins)
                    if pd.sec_tag == GTAG_INM and pd.sec_unit == unit
                ]
            )

    def _module_pin(self, gtag: int, unit: int, number: int) -> int | None:
        for io, pd in enumerate(self.firmware.pins):
            if pd.sec_tag == gtag and pd.sec_unit == unit and pd.pin_number == number:
                return io
        return None

    def set_field_inputs(self, levels: list[bool]) -> None:
        """What the field drives on every pin (a pin that is an output ignores it)."""
        self._levels.clear()
        ports = [0] * len(self.field_ports)
        width = self.port_width
        for io, level in enumerate(levels):
            if level:
                ports[io // width] |= 1 << io % width
        self.field_ports = ports

    def field_in(self, io: int) -> bool:
        port, bit = divmod(io, self.port_width)
        return bool(self.field_ports[port] >> bit & 1)

    def _module_levels(self, port: int) -> int:
        """The bits the functions drive on ``port`` (where its pins use them)."""
        value = 0
        for i, (dir_port, mask) in enumerate(self.dir_bits):
            if dir_port == port and self.step_rate[i] < 0:
                value |= mask
        width = self.port_width
        for gtag, unit, bit, io in self.module_data_bits:
            if io // width == port:
                data = self.regs.get(self.modules[gtag].address(0, unit), 0)
                if data >> bit & 1:
                    value |= 1 << io % width
        return value

    def port_levels(self, port: int) -> int:
        """The levels of a port's pins: outputs as driven, inputs as the field drives
        (worked out once per datagram: ``handle`` clears the cache)."""
        cached = self._levels.get(port)
        if cached is not None:
            return cached
        levels = self._port_levels(port)
        self._levels[port] = levels
        return levels

    def _port_levels(self, port: int) -> int:
        ddr = self.port_ddr[port]
        field = self.field_ports[port]
        alt = self.port_alt[port]
        driven = (self.port_data[port] & ~alt) | (self._module_levels(port) & alt if alt else 0)
        driven ^= self.port_invert[port]
        released = self.port_open_drain[port] & driven  # open drain high: the field decides
        return (ddr & driven & ~released) | (ddr & released & field) | (~ddr & field)

    def _forget_levels(self) -> None:
        self._levels.clear()

    def is_output(self, io: int) -> bool:
        port, bit = divmod(io, self.port_width)
        return bool(self.port_ddr[port] >> bit & 1)

    def pin_out(self, io: int) -> bool:
        """The level of pin ``io`` (driven by the board when it is an output)."""
        port, bit = divmod(io, self.port_width)
        return bool(self.port_levels(port) >> bit & 1)

    def _read_port(self, port: int) -> int:
        return self.port_levels(port) & ((1 << self.port_width) - 1)

    def _pin_level(self, io: int | None) -> bool:
        return False if io is None else self.pin_out(io)

    def _read_inm(self, index: int) -> int:
        value = 0
        ports, width = self.field_ports, self.port_width
        for bit, io in self.inm_pins[index]:
            if ports[io // width] >> (io % width) & 1:
                value |= 1 << bit
        return value

    def pwm_duty(self, index: int) -> float:
        """PWM generator ``index``'s duty cycle, -1..1 (sign from its direction output)."""
        pwm = self.modules.get(GTAG_PWMGEN)
        if not pwm:
            return 0.0
        raw = self.regs.get(pwm.address(0, index), 0)
        bits = 9 + (self.regs.get(pwm.address(1, index), 0) & 3)  # PWM width code
        magnitude = (raw >> 16 & 0x7FFF) / (1 << bits)
        return -magnitude if raw & 0x80000000 else magnitude

    def pwm_enable(self, index: int) -> bool:
        pwm = self.modules.get(GTAG_PWMGEN)
        return bool(pwm and self.regs.get(pwm.address(4), 0) >> index & 1)

    def led(self, index: int) -> bool:
        led = self.modules.get(GTAG_LED)
        return bool(led and self.regs.get(led.address(0), 0) >> (31 - index) & 1)

    # ------------------------------------------------------------ LBP16
    def handle(self, datagram: bytes) -> bytes | None:
        """Run one datagram; the answer (the data of its reads) or None."""
        self.rx_packets += 1
        self.advance()
        self._levels.clear()
        try:
            commands = lbp16.parse(datagram)
        except lbp16.Lbp16Error:
            self.parse_errors += 1
            return None
        answer = bytearray()
        cursor = [0] * 8
        for command, data in commands:
            space = command.space
            address = command.address if command.address is not None else cursor[space]
            size = lbp16.BYTES_PER_SIZE[command.size]
            step = size if command.is_increment else 0
            count = command.count
            if command.is_info:
                for n in range(count):
                    answer += self._info(space, address + n * step, size)
            elif space == lbp16.SPACE_HM2 and size == 4:  # the usual: 32-bit registers
                if command.is_write:
                    values = struct.unpack(f"<{count}I", data)
                    for n in range(count):
                        self.write_register(address + n * step, values[n])
                else:
                    read = self.read_register
                    answer += struct.pack(
                        f"<{count}I", *[read(address + n * step) for n in range(count)]
                    )
            else:
                for n in range(count):
                    at = address + n * step
                    if command.is_write:
                        self._write(space, at, data[n * size : (n + 1) * size])
                    else:
                        answer += self._read(space, at, size)
            cursor[space] = address + count * step
        if not answer:
            return None
        return bytes(answer)

    def _read(self, space: int, address: int, size: int) -> bytes:
        if space == lbp16.SPACE_HM2:
            out = bytearray()
            for offset in range(0, max(size, 4), 4):
                out += _U32.pack(self.read_register((address + offset) & ~3))
            return bytes(out[:size])
        memory = self._space_bytes(space)
        chunk = memory[address : address + size]
        return chunk + bytes(size - len(chunk))

    def _write(self, space: int, address: int, data: bytes) -> None:
        if space == lbp16.SPACE_HM2:
            padded = data + bytes(-len(data) % 4)
            for offset in range(0, len(padded), 4):
                self.write_register(address + offset, _U32.unpack_from(padded, offset)[0])
        elif space == lbp16.SPACE_TIMER:
            self.timer_space[address : address + len(data)] = data

    def _space_bytes(self, space: int) -> bytes:
        if space == lbp16.SPACE_TIMER:
            return bytes(self.timer_space)
        if space == lbp16.SPACE_BOARD_INFO:
            name = self.firmware.board_name.encode()[:16].ljust(16, b"\0")
            return name + struct.pack("<3H", 16, 20, 0)  # LBP16 version, firmware, jumpers
        if space == lbp16.SPACE_EEPROM:
            return bytes(2) + bytes(reversed(BOARD_MAC)) + bytes(24)
        if space == lbp16.SPACE_COMM_CTRL:
            return struct.pack(
                "<8H", 0, self.parse_errors, 0, 0, self.rx_packets & 0xFFFF,
                self.rx_packets & 0xFFFF, 0, self.answers & 0xFFFF,
            )  # fmt: skip
        return b""

    def _info(self, space: int, address: int, size: int) -> bytes:
        names = {0: b"HostMot2", 2: b"EEPROM", 4: b"Timer", 6: b"LBP16rw", 7: b"BoardID"}
        record = struct.pack("<4H", 0x5A00 | space, 0x0200, 0, 0) + names.get(space, b"").ljust(
            8, b"\0"
        )
        chunk = record[address : address + size]
        return chunk + bytes(size - len(chunk))

    def read_register(self, address: int) -> int:
        hook = self._read_hooks.get(address)
        if hook is not None:
            return hook() & MASK32
        value = self.static.get(address)
        return value if value is not None else self.regs.get(address, 0)

    def write_register(self, address: int, value: int) -> None:
        self._levels.clear()
        if address in self.static:
            return  # the IDROM is read-only
        hook = self._write_hooks.get(address)
        if hook is not None:
            hook(value)
        else:
            self.regs[address] = value

    def should_answer(self) -> bool:
        """Fault injection: whether the next answer goes out."""
        self.answers_due += 1
        if self.is_mute:
            return False
        if self.drop_one_in and self.answers_due % self.drop_one_in == 0:
            return False
        self.answers += 1
        return True


# ---------------------------------------------------------------- serving
class SimServer:
    """The board on a UDP socket, with its field side as HAL pins when ``hal_name``."""

    def __init__(self, board: SimBoard, ip: str, port: int, hal_name: str = "") -> None:
        self.board = board
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((ip, port))
        self.sock.settimeout(IDLE_TICK_S)
        self.is_stopping = False
        self.field = FieldPins(board, hal_name) if hal_name else None

    def serve_forever(self) -> None:
        board, sock, field = self.board, self.sock, self.field
        next_sync = 0
        while not self.is_stopping:
            try:
                datagram, peer = sock.recvfrom(2048)
            except TimeoutError:
                board.advance()
            except OSError:
                if self.is_stopping:
                    return
                raise
            else:
                answer = board.handle(datagram)
                if answer is not None and board.should_answer():
                    with contextlib.suppress(OSError):  # the host went away: keep serving
                        sock.sendto(answer, peer)
            # the connectors, once a ms, after answering (the host is waiting for answers)
            if field and time.monotonic_ns() >= next_sync:
                field.take_inputs()
                field.publish()
                next_sync = time.monotonic_ns() + FIELD_SYNC_NS

    def close(self) -> None:
        self.is_stopping = True
        self.sock.close()
        if self.field:
            self.field.close()


class FieldPins:
    """The simulated board's connectors as HAL pins of a userspace component."""

    def __init__(self, board: SimBoard, name: str) -> None:
        from hal.api import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_OUT, HAL_S32, HAL_U32, component

        self.board = board
        self.comp = comp = component(name)
        self.io_in = []
        self.io_out = []
        self.io_is_output = []
        for io in range(board.num_pins):
            pin_in = comp.newpin(f"io.{io:03d}.in", HAL_BIT, HAL_IN)
            pin_in.set(board.field_in(io))
            self.io_in.append(pin_in)
            self.io_out.append(comp.newpin(f"io.{io:03d}.out", HAL_BIT, HAL_OUT))
            self.io_is_output.append(comp.newpin(f"io.{io:03d}.is-output", HAL_BIT, HAL_OUT))
        self.step = [
            (
                comp.newpin(f"stepgen.{i:02d}.position", HAL_FLOAT, HAL_OUT),
                comp.newpin(f"stepgen.{i:02d}.rate", HAL_FLOAT, HAL_OUT),
            )
            for i in range(len(board.step_rate))
        ]
        self.encoder = [
            (
                comp.newpin(f"encoder.{i:02d}.counts", HAL_S32, HAL_IN),
                comp.newpin(f"encoder.{i:02d}.index", HAL_BIT, HAL_IN),
            )
            for i in range(len(board.encoder_counts))
        ]
        n_pwm = board._instances(GTAG_PWMGEN)
        self.pwm = [
            (
                comp.newpin(f"pwmgen.{i:02d}.duty", HAL_FLOAT, HAL_OUT),
                comp.newpin(f"pwmgen.{i:02d}.enable", HAL_BIT, HAL_OUT),
            )
            for i in range(n_pwm)
        ]
        self.leds = [
            comp.newpin(f"led.{i:02d}", HAL_BIT, HAL_OUT) for i in range(board.firmware.num_leds)
        ]
        self.has_bit = comp.newpin("watchdog.has-bit", HAL_BIT, HAL_OUT)
        self.drop_one_in = comp.newpin("drop-one-in", HAL_U32, HAL_IN)
        self.is_mute = comp.newpin("is-mute", HAL_BIT, HAL_IN)
        self.published = [(-1, -1)] * len(board.port_ddr)  # (levels, directions) per port
        comp.ready()

    def take_inputs(self) -> None:
        board = self.board
        board.set_field_inputs([pin.get() for pin in self.io_in])
        for i, (counts, index) in enumerate(self.encoder):
            board.encoder_counts[i] = counts.get()
            board.encoder_index[i] = index.get()
        board.drop_one_in = self.drop_one_in.get()
        board.is_mute = self.is_mute.get()

    def publish(self) -> None:
        """The board's side of the connectors; pins are written only when they change."""
        board = self.board
        width = board.port_width
        for port in range(len(board.port_ddr)):
            levels, ddr = board.port_levels(port), board.port_ddr[port]
            old_levels, old_ddr = self.published[port]
            changed = (levels ^ old_levels) | (ddr ^ old_ddr)
            if not changed:
                continue
            self.published[port] = (levels, ddr)
            for bit in range(width):
                io = port * width + bit
                if io < board.num_pins and changed >> bit & 1:
                    self.io_out[io].set(bool(levels >> bit & 1))
                    self.io_is_output[io].set(bool(ddr >> bit & 1))
        for i, (position, rate) in enumerate(self.step):
            position.set(board.step_position(i))
            rate.set(board.step_rate_hz(i))
        for i, (duty, enable) in enumerate(self.pwm):
            duty.set(board.pwm_duty(i))
            enable.set(board.pwm_enable(i))
        for i, led in enumerate(self.leds):
            led.set(board.led(i))
        self.has_bit.set(board.has_bit)

    def close(self) -> None:
        self.comp.exit()


def _make_realtime() -> None:
    """A board answers within microseconds: where permitted, run at a realtime priority
    below the realtime host's threads, so other programs cannot delay the answers."""
    with contextlib.suppress(OSError, AttributeError):
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(SIM_PRIORITY))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hm2_sim", description=__doc__.split("\n\n")[0])
    parser.add_argument("--board", default="7i96s", choices=sorted(FIRMWARES))
    parser.add_argument("--ip", default="127.0.0.1", help="address to answer on")
    parser.add_argument("--port", type=int, default=lbp16.UDP_PORT)
    parser.add_argument("--hal", default="", metavar="NAME", help="field pins as component NAME")
    args = parser.parse_args(argv)
    try:
        server = SimServer(SimBoard(FIRMWARES[args.board]), args.ip, args.port, args.hal)
    except OSError as exc:
        print(f"hm2_sim: cannot answer on {args.ip}:{args.port}: {exc.strerror}", file=sys.stderr)
        return 1

    def stop(*_: object) -> None:
        server.is_stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    _make_realtime()
    print(f"hm2_sim: {args.board} answering on {args.ip}:{args.port}", file=sys.stderr, flush=True)
    try:
        server.serve_forever()
    finally:
        server.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
