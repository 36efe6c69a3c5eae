"""``cnc top``: a live full-screen view of the controller's status, like LinuxCNC's
linuxcnctop.

    cnc top [INI_OR_NML] [--interval S] [--once]

Shows task state and mode, the program and its lines, positions (work, machine, to go) and
joints, offsets, the tool, overrides, spindle, coolant, the active G and M codes and the
last operator messages. It refreshes every ``--interval`` seconds, else every
``[DISPLAY]CYCLE_TIME`` of the INI file, else every 0.1 s; q (or Ctrl-C) quits. While the
controller is not up it shows why and keeps trying. ``--once`` prints one plain-text
snapshot and exits (status 1 if the controller is not up). Without a terminal (a pipe, a
log) it prints the view as plain text whenever it changes, until a signal ends it.

It can be a machine's display: ``[DISPLAY]DISPLAY = top`` makes the launcher run
``cnc top INI_FILE``; quitting it shuts the machine down.
"""

from __future__ import annotations

import argparse
import contextlib
import curses
import locale
import signal
import sys
import time
from collections.abc import Iterable
from typing import Any

import cnc
from cnc.ui import formatting as fmt
from cnc.ui.controller import Controller, Message

DEFAULT_INTERVAL_S = 0.1
LOG_INTERVAL_S = 2.0  # without a terminal: at most one printed view per this many seconds
MESSAGES_SHOWN = 4  # the last operator messages, at the bottom of the screen
QUIT_KEYS = {ord("q"), ord("Q")}


def display_interval(cycle_time: str | None) -> float | None:
    """The refresh period from ``[DISPLAY]CYCLE_TIME``: values >= 1 are milliseconds,
    smaller ones seconds (GUI-007); None if absent or not a positive number."""
    try:
        value = float(cycle_time)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None
    if not value > 0:
        return None
    return value / 1000 if value >= 1 else value


def status_screen(
    s: fmt.Status, messages: Iterable[Message], title: str, height: int | None = None
) -> list[str]:
    """The lines of the view for a polled status; with ``height``, the status part is cut
    so that the messages at the bottom always show."""
    body = [
        title,
        *fmt.state_lines(s),
        *fmt.program_lines(s),
        *fmt.side_by_side(fmt.position_lines(s), fmt.joint_lines(s)),
        *fmt.offset_lines(s),
        *fmt.tool_lines(s),
        *fmt.override_lines(s),
        *fmt.spindle_lines(s),
        *fmt.active_codes(s),
    ]
    recent = list(messages)[-MESSAGES_SHOWN:]
    tail = [f"Messages: {'' if recent else 'none'}".rstrip()]
    tail += [f"  {message.stamped()}" for message in recent]
    if height is not None:
        body = body[: max(1, height - len(tail))]
    return body + tail


def waiting_screen(reason: str, title: str) -> list[str]:
    """The lines shown while the controller is not up."""
    return [title, "", "Waiting for the controller to start ...", f"  {fmt.clean(reason)}"]


def _title(controller: Controller) -> str:
    where = controller.source or "running machine"
    return f"cnc top  {where}  {time.strftime('%Y-%m-%d %H:%M:%S')}   (q quits)"


def snapshot(controller: Controller, height: int | None = None) -> tuple[bool, list[str]]:
    """(whether the controller is up, the lines of the view) after a fresh poll."""
    try:
        status = controller.poll()
        controller.read_messages()
    except cnc.error as exc:
        controller.reset()  # a controller started (again) later has new buffers
        return False, waiting_screen(str(exc), _title(controller))
    try:
        return True, status_screen(status, controller.history, _title(controller), height)
    except Exception as exc:  # as the machine's display, a crash would shut the machine down
        return True, [_title(controller), f"cannot show the status: {type(exc).__name__}: {exc}"]


def _draw(screen: Any, lines: list[str]) -> None:
    height, width = screen.getmaxyx()
    encoding = getattr(screen, "encoding", None) or "utf-8"
    screen.erase()
    for row, line in enumerate(lines[:height]):
        text = line.ljust(width)[:width].encode(encoding, "replace").decode(encoding)
        style = curses.A_REVERSE if row == 0 else curses.A_NORMAL
        with contextlib.suppress(curses.error):  # writing the bottom-right cell "fails"
            screen.addstr(row, 0, text, style)
    screen.refresh()


def _run(screen: Any, controller: Controller, interval: float) -> None:
    with contextlib.suppress(curses.error):  # some terminals cannot hide the cursor
        curses.curs_set(0)
    deadline = time.monotonic()
    while True:
        _draw(screen, snapshot(controller, screen.getmaxyx()[0])[1])
        # Refresh at a steady rate: the wait is what is left of this period.
        deadline = max(deadline + interval, time.monotonic())
        screen.timeout(max(0, round((deadline - time.monotonic()) * 1000)))
        if screen.getch() in QUIT_KEYS:
            return


def _log(controller: Controller, interval: float) -> int:
    """Without a terminal (a log, a pipe, a service): the view as plain text whenever it
    changes, at most once per LOG_INTERVAL_S, until a signal ends it (as the machine's
    display it must not exit early: that would shut the machine down)."""
    print("cnc top: not a terminal: the status is printed when it changes", file=sys.stderr)
    shown: list[str] = []
    while True:
        _, lines = snapshot(controller)
        if lines[1:] != shown[1:]:  # the first line holds the clock
            print("\n".join(lines) + "\n", flush=True)
            shown = lines
            time.sleep(max(interval, LOG_INTERVAL_S))
        else:
            time.sleep(interval)


def _stop_on_sigterm(signum: int, frame: object) -> None:
    raise SystemExit(0)  # unwinds curses.wrapper, which restores the terminal


def _positive_seconds(text: str) -> float:
    try:
        value = fmt.parse_float(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"'{text}' is not a positive number of seconds")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cnc top", description="Live view of the controller's status (like linuxcnctop)."
    )
    parser.add_argument(
        "source", nargs="?", metavar="INI_OR_NML", help="machine to watch (default: running)"
    )
    parser.add_argument(
        "--interval", type=_positive_seconds, metavar="S", help="refresh period in seconds"
    )
    parser.add_argument(
        "--once", dest="is_once", action="store_true", help="print one snapshot and exit"
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        controller = Controller(args.source)
    except cnc.error as exc:
        print(f"cnc top: {exc}", file=sys.stderr)
        return 2
    try:
        if args.is_once:
            is_up, lines = snapshot(controller)
            print("\n".join(lines), file=sys.stdout if is_up else sys.stderr)
            return 0 if is_up else 1
        interval = args.interval or display_interval(controller.ini_value("DISPLAY", "CYCLE_TIME"))
        signal.signal(signal.SIGTERM, _stop_on_sigterm)
        if not (sys.stdin.isatty() and sys.stdout.isatty()):
            return _log(controller, interval or DEFAULT_INTERVAL_S)
        with contextlib.suppress(locale.Error):  # LANG may name a locale not installed
            locale.setlocale(locale.LC_ALL, "")  # curses writes text in the locale's code
        curses.wrapper(_run, controller, interval or DEFAULT_INTERVAL_S)
        return 0
    except KeyboardInterrupt:
        return 0
    except curses.error as exc:
        print(f"cnc top: cannot use this terminal: {exc}", file=sys.stderr)
        return 2
    finally:
        controller.close()


if __name__ == "__main__":
    sys.exit(main())
