"""halrun: start a realtime host, run a HAL file (or an interactive halcmd), tear down.

``cnc halrun [-I] [-k] [-s] [-i INI] [-f] [FILE]``. Like LinuxCNC's halrun, everything the
file loaded is unloaded at the end, the host exits and HAL's shared memory is removed, so a
HAL file plus its expected output makes a test.
"""

from __future__ import annotations

import sys

from hal.core import HalError
from hal.halcmd import make_session, parse_options, run_session
from hal.rtapi_app import release_if_unused


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    is_interactive = "-I" in args
    args = [a for a in args if a != "-I"]
    try:
        opts, rest = parse_options(args)
    except HalError as exc:
        print(f"halrun: {exc}", file=sys.stderr)
        return 2
    if opts.get("help"):
        print(__doc__)
        return 0
    if rest and not opts["file"]:
        opts["file"], rest = rest[0], rest[1:]
    if rest:
        print(f"halrun: too many arguments <{' '.join(rest)}>", file=sys.stderr)
        return 1
    try:
        session = make_session(opts)
    except Exception as exc:  # a bad INI file names file:line
        print(f"halrun: {exc}", file=sys.stderr)
        return 1
    status = 0
    try:
        if session.host.is_running():
            print("halrun: a realtime host is already running for this instance", file=sys.stderr)
            return 1
        try:
            session.host.ensure(stderr=sys.stderr)
        except HalError as exc:
            print(f"halrun: {exc}", file=sys.stderr)
            return 1
        if opts["file"]:
            status = run_session(session, opts, [])
        if is_interactive or not opts["file"]:
            session.is_keep_going = True
            session.is_quit = False
            status = max(status, run_session(session, {**opts, "file": None}, []))
    finally:
        session.run_words(["stop"])
        session.run_words(["unload", "all"])
        session.host.stop()
        release_if_unused(session.hal)
        session.hal.close()
    return status
