"""``cnc hal watch|sample|stream``: look at HAL values, record them, play them back.

- ``cnc hal watch [-n COUNT] [-i SECONDS] NAME...``: print pins, parameters or signals
  (``name value`` lines) every interval, like halmeter; ``-n 1`` prints once.
- ``cnc hal sample [-c CHAN] [-n COUNT] [-t] [FILE]``: like halsampler, copy rows from a
  loaded ``sampler`` channel to FILE (or stdout), one line of values per thread period.
  ``cnc hal sample -T THREAD [-n COUNT] [-t] [-o FILE] PIN...`` does the wiring itself: it
  loads a private sampler, connects it to the pins, records, then removes everything.
- ``cnc hal stream [-c CHAN] [FILE]``: like halstreamer, feed lines of values into a loaded
  ``streamer`` channel. ``cnc hal stream -T THREAD [-i FILE] PIN...`` wires a private
  streamer to the given input pins, plays the file once, then removes everything.
- ``cnc hal realtime start|stop|restart|status``: LinuxCNC's ``realtime`` script (``stop``
  ends the realtime host and removes the instance's HAL).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import signal
import sys
import time
from collections.abc import Iterator
from typing import Any, TextIO

from hal.core import (
    HAL_BIT,
    HAL_FLOAT,
    HAL_OUT,
    TYPE_NAMES,
    Hal,
    HalError,
    format_value,
    remove_hal_objects,
)
from hal.fifo import Fifo, decode, encode

_CFG_LETTER = {"float": "f", "bit": "b", "s32": "s", "u32": "u", "s64": "l", "u64": "k"}
POLL_S = 0.005
_FIELD = re.compile(r"\S+")


def _value_of(hal: Hal, name: str) -> str:
    found = hal.find_pin(name)
    if found:
        return format_value(found[1]["type"], hal.pin_value(found[1]), is_show=False)
    found = hal.find_param(name)
    if found:
        item = found[1]
        return format_value(item["type"], hal.read_slot(item["type"], item["slot"]), is_show=False)
    sig = hal.meta["sigs"].get(name)
    if sig:
        return format_value(sig["type"], hal.read_slot(sig["type"], sig["slot"]), is_show=False)
    raise HalError(f"pin, parameter or signal '{name}' not found")


def watch(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="cnc hal watch", description="show HAL values live")
    parser.add_argument("-n", "--count", type=int, default=0, help="updates (0: until ^C)")
    parser.add_argument("-i", "--interval", type=float, default=0.2, help="seconds")
    parser.add_argument("names", nargs="+")
    opts = parser.parse_args(argv)
    hal = Hal(is_creating=False)
    try:
        shown = 0
        while True:
            for name in opts.names:
                print(f"{name} {_value_of(hal, name)}", flush=True)
            shown += 1
            if opts.count and shown >= opts.count:
                return 0
            time.sleep(opts.interval)
    except KeyboardInterrupt:
        return 0
    finally:
        hal.close()


def _format_row(row: Any, types: list[int], is_tagged: bool) -> str:
    values = decode(row[1:], types)
    # halsampler's tag counts from 0 (the FIFO numbers rows from 1)
    words = [str(int(row[0]) - 1)] if is_tagged else []
    # halsampler's layout: floats with six decimals, each value followed by a space
    words += [f"{v:f}" if isinstance(v, float) else str(v) for v in values]
    return "".join(f"{word} " for word in words)


def read_samples(fifo: Fifo, out: TextIO, count: int, is_tagged: bool) -> int:
    """Copy rows until ``count`` (0: forever); prints 'overrun' where rows were lost, as
    halsampler does."""
    done = 0
    last_sample = 0
    while not count or done < count:
        if not fifo.count():
            time.sleep(POLL_S)
            continue
        row = fifo.get()
        assert row is not None
        last_sample += 1
        if int(row[0]) != last_sample:
            print("overrun", file=out)
            last_sample = int(row[0])
        print(_format_row(row, fifo.types, is_tagged), file=out)
        done += 1
    out.flush()
    return done


@contextlib.contextmanager
def _private_channel(
    module: str, thread: str, pins: list[str], hal: Hal, depth: int
) -> Iterator[tuple[str, list[int]]]:
    """Load a private sampler/streamer, net it to ``pins``, addf it; undo it all afterwards."""
    from hal.rtapi_app import HostClient  # (here only: a plain sample/stream starts faster)

    host = HostClient()
    if not host.is_running():
        raise HalError("no realtime host is running")
    tag = f"{module[:2]}{os.getpid()}"
    types = []
    for name in pins:
        found = hal.find_pin(name)
        if found is None:
            raise HalError(f"pin '{name}' not found")
        types.append(found[1]["type"])
    cfg = "".join(_CFG_LETTER[TYPE_NAMES[t]] for t in types)
    host.call(
        {"cmd": "loadrt", "name": module, "comp": tag, "args": [f"depth={depth}", f"cfg={cfg}"]}
    )
    channel = f"{tag}.0"
    made_sigs = []
    try:
        for index, name in enumerate(pins):
            pin = hal.find_pin(name)
            assert pin is not None
            sig = pin[1]["sig"]
            if sig is None:
                sig = f"{tag}-{index}"
                hal.new_signal(sig, pin[1]["type"])
                made_sigs.append(sig)
                # the signal starts with the pin's value, so linking changes nothing
                hal.q[hal.meta["sigs"][sig]["slot"]] = hal.q[hal.ptr[pin[1]["slot"]]]
                if module == "streamer" and pin[1]["dir"] == HAL_OUT:
                    raise HalError(f"pin '{name}' is an output: it cannot be streamed into")
                hal.link(pin[0], sig)
            hal.link(f"{channel}.pin.{index}", sig)
        hal.add_funct(channel, thread)
        yield channel, types
    finally:
        with contextlib.suppress(HalError):
            hal.del_funct(channel, thread)
        with contextlib.suppress(HalError):
            host.call({"cmd": "unloadrt", "name": tag})
        for sig in made_sigs:
            with contextlib.suppress(HalError):
                hal.delete_signal(sig)


def sample(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="cnc hal sample", description="record HAL values")
    parser.add_argument("-c", "--channel", default="0", help="sampler channel (halsampler -c)")
    parser.add_argument("-n", "--count", type=int, default=0, help="samples (0: until ^C)")
    parser.add_argument(
        "-t", "--tag", dest="is_tagged", action="store_true", help="print sample numbers"
    )
    parser.add_argument("-T", "--thread", help="record PINs every period of THREAD")
    parser.add_argument("-o", "--output", help="file (default: stdout)")
    parser.add_argument("args", nargs="*", help="FILE, or PINs with -T")
    opts = parser.parse_args(argv)
    hal = Hal(is_creating=False)
    out: TextIO = sys.stdout
    try:
        if opts.thread:
            if opts.output:
                out = open(opts.output, "w", encoding="utf-8")  # noqa: SIM115
            with _private_channel("sampler", opts.thread, opts.args, hal, 16384) as (ch, _):
                fifo = Fifo.open(ch)
                try:
                    read_samples(fifo, out, opts.count, opts.is_tagged)
                finally:
                    fifo.close()
        else:
            if opts.args:
                out = open(opts.args[0], "w", encoding="utf-8")  # noqa: SIM115
            fifo = Fifo.open(f"sampler.{opts.channel}")
            try:
                read_samples(fifo, out, opts.count, opts.is_tagged)
            finally:
                fifo.close()
    except HalError as exc:
        print(f"cnc hal sample: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 0
    finally:
        if out is not sys.stdout:
            out.close()
        hal.close()
    return 0


def parse_stream_line(line: str, types: list[int]) -> list[int | float]:
    """One line of values as halstreamer reads it: whitespace-separated fields, one per
    column, each followed by whitespace (so a last line without its newline is cut short,
    as LinuxCNC finds it); what follows is ignored. ValueError(field index, cause) when
    bad."""
    fields = list(_FIELD.finditer(line))
    values: list[int | float] = []
    for index, hal_type in enumerate(types):
        if index >= len(fields):
            missing = "bit value not 0 or 1" if hal_type == HAL_BIT else "premature end of line"
            raise ValueError(index, missing)
        word = fields[index].group()
        try:
            if hal_type == HAL_FLOAT:
                values.append(float(word))
            elif hal_type == HAL_BIT:
                if word not in ("0", "1"):
                    raise ValueError(index, "bit value not 0 or 1")
                values.append(int(word))
            else:
                values.append(int(word, 10))
        except ValueError as exc:
            if exc.args and isinstance(exc.args[0], int):
                raise
            raise ValueError(index, "bad character") from None
        if fields[index].end() == len(line):
            raise ValueError(index, "premature end of line")
    return values


def write_stream(fifo: Fifo, lines: TextIO) -> int:
    """Push every line of values into the FIFO, waiting while it is full; returns rows
    sent. As halstreamer: lines starting with ``#`` are comments, a bad line is reported
    on stderr (lines counted from 0) and skipped."""
    sent = 0
    for number, line in enumerate(lines):
        if line.startswith("#"):
            continue
        try:
            values = parse_stream_line(line, fifo.types)
        except ValueError as exc:
            field, cause = exc.args
            print(f"line {number}, field {field}: {cause}, skipping the line", file=sys.stderr)
            continue
        while not fifo.is_writable():
            time.sleep(POLL_S)
        fifo.put(encode(values, fifo.types))
        sent += 1
    return sent


def stream(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="cnc hal stream", description="play values into HAL")
    parser.add_argument("-c", "--channel", default="0", help="streamer channel")
    parser.add_argument("-T", "--thread", help="play into PINs, one line per period of THREAD")
    parser.add_argument("-i", "--input", help="file (default: stdin)")
    parser.add_argument("args", nargs="*", help="FILE, or PINs with -T")
    opts = parser.parse_args(argv)
    hal = Hal(is_creating=False)
    source = opts.input or (opts.args[0] if opts.args and not opts.thread else None)
    lines: TextIO = sys.stdin
    try:
        if source:
            lines = open(source, encoding="utf-8")  # noqa: SIM115
        if opts.thread:
            with _private_channel("streamer", opts.thread, opts.args, hal, 4096) as (ch, _):
                fifo = Fifo.open(ch)
                try:
                    write_stream(fifo, lines)
                    while fifo.count():
                        time.sleep(POLL_S)  # wait until the thread has played everything
                finally:
                    fifo.close()
        else:
            fifo = Fifo.open(f"streamer.{opts.channel}")
            try:
                write_stream(fifo, lines)
            finally:
                fifo.close()
    except (HalError, OSError) as exc:
        print(f"cnc hal stream: {exc}", file=sys.stderr)
        return 1
    finally:
        if lines is not sys.stdin:
            lines.close()
        hal.close()
    return 0


def realtime(argv: list[str]) -> int:
    """``cnc hal realtime start|stop|restart|status``: LinuxCNC's ``realtime`` script.

    As with LinuxCNC's userspace realtime, ``start`` has nothing to do (the first
    ``loadrt`` starts the realtime host); ``stop`` makes the host unload everything and
    exit, then removes the instance's HAL shared memory and semaphores (programs still
    attached keep their mapping); ``status`` exits 0 while a host runs, else 1.
    """
    from hal.rtapi_app import HostClient  # (here only: the other tools start faster)

    command = argv[0] if argv else ""
    host = HostClient()
    if command == "status":
        return 0 if host.is_running() else 1
    if command in ("stop", "restart"):
        if host.is_running():
            host.stop()
        remove_hal_objects()
        return 0
    if command == "start":
        return 0
    print("usage: cnc hal realtime start|stop|restart|status", file=sys.stderr)
    return 2


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    tools = {"watch": watch, "sample": sample, "stream": stream, "realtime": realtime}
    if not args or args[0] not in tools:
        print(__doc__, file=sys.stderr if args else sys.stdout)
        return 2 if args else 0
    # a plain `kill` still unwires what sample/stream wired
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    try:
        return tools[args[0]](args[1:])
    except HalError as exc:
        print(f"cnc hal {args[0]}: {exc}", file=sys.stderr)
        return 1
