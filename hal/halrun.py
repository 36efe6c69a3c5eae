"""halrun: start a realtime host, run a HAL file (or an interactive halcmd), tear down.

``cnc halrun [-I] [halcmd options] [-f] [FILE]``, ``cnc halrun -U``. Like LinuxCNC's halrun,
everything the file loaded is unloaded at the end, the host exits and HAL's shared memory is
removed, so a HAL file plus its expected output makes a test. ``-I`` runs an interactive
halcmd after the file. ``-U`` forcibly cleans up a HAL left behind by a crash: it releases
the HAL mutex, stops the realtime host and the user space components of this instance
(``$CNC_INSTANCE``) and removes HAL's shared memory and semaphores.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from pathlib import Path

from hal.core import Hal, HalError, release_hal_mutex, remove_hal_objects
from hal.halcmd import VERBOSITY_ERRORS, HalCmd, make_session, parse_options, run_session
from hal.rtapi_app import HostClient, release_if_unused
from nml.shmem import is_process_alive

STOP_TIMEOUT_S = 3.0


def hal_processes() -> set[int]:
    """Pids of the realtime host and of every component's process of this instance's HAL."""
    pids: set[int] = set()
    with contextlib.suppress(OSError, ValueError):  # no host, or one that does not answer
        pids.add(int(HostClient().request({"cmd": "ping"}, timeout=1)["pid"]))
    with contextlib.suppress(HalError):
        hal = Hal(is_creating=False)
        try:
            pids.update(comp["pid"] for comp in hal.meta["comps"].values())
        finally:
            hal.close()
    pids.discard(os.getpid())
    return {pid for pid in pids if pid > 0}


def stop_processes(pids: set[int]) -> None:
    """SIGTERM, then SIGKILL whatever is still alive after STOP_TIMEOUT_S."""
    for pid in pids:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGTERM)
    deadline = time.monotonic() + STOP_TIMEOUT_S
    while any(is_process_alive(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    for pid in pids:
        if is_process_alive(pid):
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, signal.SIGKILL)


def force_cleanup() -> None:
    """halrun -U: leave no HAL of this instance behind, whatever state it is in."""
    release_hal_mutex()  # a crashed program may hold it; everything below needs it free
    stop_processes(hal_processes())
    remove_hal_objects()


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if "-U" in args:
        force_cleanup()
        return 0
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
    is_ini = bool(opts["file"]) and opts["file"].endswith(".ini")
    if is_ini and not opts["ini"]:
        opts["ini"] = opts["file"]  # its values serve the HAL files' [SECTION]KEY
    if opts["release_mutex"]:
        release_hal_mutex()
    try:
        session = make_session(opts)
    except Exception as exc:  # a bad INI file names file:line
        print(f"halrun: {exc}", file=sys.stderr)
        return 1
    if session.host.is_running():  # leave it alone: the teardown below is for our own host
        print(
            "halrun: Realtime already running.  Use 'halrun -U' to stop existing realtime session.",
            file=sys.stderr,
        )
        session.leave_hal()
        session.hal.close()
        return 1
    status = 0
    try:
        try:
            session.host.ensure(stderr=sys.stderr)
        except HalError as exc:
            print(f"halrun: {exc}", file=sys.stderr)
            return 1
        if is_ini:
            status = run_twopass_ini(session, opts["file"])
        elif opts["file"]:
            status = run_session(session, opts, [])
        if is_interactive or not opts["file"]:
            session.is_keep_going = True
            session.is_quit = False
            status = max(status, run_session(session, {**opts, "file": None}, []))
    finally:
        # the teardown is quiet, as LinuxCNC's halrun runs it with a plain halcmd
        session.verbosity, session.is_echo = VERBOSITY_ERRORS, False
        session.run_words(["stop"])
        session.run_words(["unload", "all"])
        session.leave_hal()
        session.host.stop()
        release_if_unused(session.hal)
        session.hal.close()
    return status


def run_twopass_ini(session: HalCmd, filename: str) -> int:
    """``halrun FILE.ini``: the INI file's ``[HAL]HALFILE`` entries, in two passes; as
    LinuxCNC's halrun, only for an INI file that sets ``[HAL]TWOPASS``."""
    from cnc.halfiles import find_halfiles, run_halfiles

    ini = session.ini
    twopass = ini.find("HAL", "TWOPASS")
    if twopass is None:
        print("halrun: An INI file may only be used if it specifies [HAL]TWOPASS")
        return 1
    try:
        halfiles = find_halfiles(ini, Path(filename).absolute().parent, [])
        is_ok = run_halfiles(session, ini, halfiles, say=lambda _: None, twopass=twopass or "on")
    except HalError as exc:
        print(f"halrun: {exc}", file=sys.stderr)
        return 1
    return 0 if is_ok else 1
