"""``cnc nml check|ls|dump``: validate an NML file, list its buffers, print their messages.

``ls`` and ``dump`` look at the live buffers of the current instance (``CNC_INSTANCE``) as an
observer: they take no connection slot and never consume a queued message.
"""

from __future__ import annotations

import argparse
import sys
import warnings

from nml.channels import DEFAULT_NML_FILE, load_config, messages_of
from nml.codec import Encoding, max_encoded_size
from nml.config import BufferConfig, NmlConfig, ProcessConfig, describe_timeout
from nml.errors import NmlConfigError, NmlError
from nml.message import NMLmsg
from nml.shmem import ShmBuffer

OBSERVER = "cnc-nml"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="cnc nml", description=__doc__)
    sub = parser.add_subparsers(dest="verb", required=True)
    check = sub.add_parser("check", help="validate an NML file; errors as file:line: cause")
    check.add_argument("file")
    ls = sub.add_parser("ls", help="buffers, kinds, sizes, encodings, processes, live counts")
    ls.add_argument("file", nargs="?", default=str(DEFAULT_NML_FILE))
    dump = sub.add_parser("dump", help="decode and print a buffer's current or queued messages")
    dump.add_argument("file")
    dump.add_argument("buffer")
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            config = load_config(args.file)
        for warning in caught:
            print(f"warning: {warning.message}", file=sys.stderr)
    except NmlConfigError as exc:
        for error in exc.errors:
            print(error, file=sys.stderr)
        return 1
    if args.verb == "check":
        print(f"{args.file}: {len(config.buffers)} buffers, {len(config.processes)} P lines: OK")
        return 0
    if args.verb == "ls":
        print(list_buffers(config))
        return 0
    return dump_buffer(config, args.buffer)


def _observer(buffer: BufferConfig) -> ProcessConfig:
    return ProcessConfig(OBSERVER, buffer.name, "LOCAL", "localhost", "R", False, 0.0, False, 0)


def _open_live(buffer: BufferConfig) -> ShmBuffer | None:
    try:
        return ShmBuffer(buffer, _observer(buffer), is_observer=True)
    except NmlError:
        return None


def list_buffers(config: NmlConfig) -> str:
    rows = [("BUFFER", "KIND", "SIZE", "ENCODING", "LARGEST MSG", "PROCESSES", "LIVE")]
    for buffer in config.buffers.values():
        encoding = Encoding.from_neut(buffer.is_neutral)
        classes = messages_of(buffer.name)
        largest = max((max_encoded_size(c, encoding) for c in classes), default=0)
        procs = ", ".join(
            f"{p.name}({p.ops}{',master' if p.is_master else ''},c{p.c_num},"
            f"{describe_timeout(p.timeout)})"
            for p in config.processes_of(buffer.name)
        )
        live = "-"
        connection = _open_live(buffer)
        if connection is not None:
            stats = connection.stats()
            pids = [str(pid) for pid, _ in connection.connections()]
            live = f"written {stats['write_count']}, attached {len(pids)}"
            if pids:
                live += f" (pids {' '.join(pids)})"
            if buffer.is_queue:
                live += f", queued {stats['count']}, read {stats['read_count']}"
            connection.close()
        rows.append(
            (
                buffer.name,
                "broadcast" if buffer.is_broadcast else "queue" if buffer.is_queue else "latest",
                str(buffer.size),
                encoding.name.lower(),
                str(largest) if largest else "-",
                procs or "-",
                live,
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
    return "\n".join(
        "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=False)) + row[-1]
        for row in rows
    )


def dump_buffer(config: NmlConfig, name: str) -> int:
    buffer = config.buffers.get(name)
    if buffer is None:
        print(f"{config.path}: no buffer named '{name}'", file=sys.stderr)
        return 1
    connection = _open_live(buffer)
    if connection is None:
        print(f"buffer {name}: not running (no shared memory segment)", file=sys.stderr)
        return 1
    try:
        items: list[NMLmsg | NmlError | None]
        if buffer.is_queue:
            items = list(connection.queued())
        else:
            try:
                items = [connection.peek()]
            except NmlError as exc:
                items = [exc]
        if not items or items == [None]:
            print(f"buffer {name}: empty")
        for item in items:
            if isinstance(item, NmlError):
                print(f"error: {item}")
            elif item is not None:
                print(format_message(item))
    finally:
        connection.close()
    return 0


def format_message(msg: NMLmsg) -> str:
    """``NAME (type N)`` followed by the fields, nested structs indented, zero arrays folded."""
    lines = [f"{msg.NAME} (type {msg.TYPE})"]
    _format_values(msg.to_python(), "  ", lines)
    return "\n".join(lines)


def _format_values(values: dict, indent: str, lines: list[str]) -> None:
    for key, value in values.items():
        if isinstance(value, dict):
            lines.append(f"{indent}{key}:")
            _format_values(value, indent + "  ", lines)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            for index, item in enumerate(value):
                if any(_is_nonzero(v) for v in item.values()):
                    lines.append(f"{indent}{key}[{index}]:")
                    _format_values(item, indent + "  ", lines)
        elif isinstance(value, list):
            last = max((i for i, v in enumerate(value) if v), default=-1)
            shown = value[: last + 1]
            more = f" ... ({len(value)} in all, the rest 0)" if last + 1 < len(value) else ""
            lines.append(f"{indent}{key}: {shown}{more}")
        else:
            lines.append(f"{indent}{key}: {value!r}")


def _is_nonzero(value: object) -> bool:
    if isinstance(value, dict):
        return any(_is_nonzero(v) for v in value.values())
    if isinstance(value, list):
        return any(_is_nonzero(v) for v in value)
    return bool(value)
