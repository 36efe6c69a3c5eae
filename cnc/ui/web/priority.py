"""The web server's scheduling: a STOP or E-stop from a page reaches the safety board at
once, however busy the computer is.

A page's STOP is read by the server's event loop, which writes it on the safety board
(hub.on_the_safety_board); motion takes it from there within a servo period. So the loop
must run when a message arrives. Measured with ``scripts/bench/ui_bench.py --parts stop``
(2 cores, Chromium drawing a 200,000-line preview in software on the same box, its drawing
process at niceness -8): an ordinary thread, even at niceness -10, sometimes waited 100 to
500 ms for a CPU, and so did the STOP behind it; the event loop as the lowest realtime
priority (SCHED_FIFO 1) took it to the board within 25 ms.

- The **event loop thread** runs SCHED_FIFO at ``LOOP_RT_PRIORITY``: above every ordinary
  program, below motion's and HAL's threads (which keep the machine moving and braking).
  Its work is light (status to the pages, small answers); what is heavy runs elsewhere.
  ``SCHED_RESET_ON_FORK``: threads and processes it starts are ordinary again.
  Starting a thread would make it wait for the new one: jobs are watched without one
  (``watch_jobs_without_threads``).
- **Worker threads** (commands that wait for the machine, file reads) run at niceness
  ``WORKER_NICE``: ahead of other programs, so one holding Python's interpreter lock is
  not left waiting for a CPU while the loop waits for the lock.
- **Jobs** (preview, estimate, filters) run niced below everything (``JOB_NICE``), each in
  a session of its own (see ``_lowered_to``); a job's time estimate, minutes of CPU for a
  long program, lower still (``ESTIMATE_NICE``). Turning a 1M-line preview in software
  while the estimate ran (``--parts load``): the job took 35-39 ms of CPU a frame niced
  in the server's session, 13 ms in its own at 15; the view turned at 17-20 fps, now 25.

Without the privilege (CAP_SYS_NICE, or RLIMIT_RTPRIO / RLIMIT_NICE from
/etc/security/limits.conf) the server runs as it was started and says so once.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import sys

LOOP_RT_PRIORITY = 1
WORKER_NICE = -10
# absolute, whatever the server's: below the server and task, iocontrol, yet not starved
# on a busy box
JOB_NICE = 5
ESTIMATE_NICE = 15


def raise_loop_priority() -> str | None:
    """Called by the event loop's thread before any other thread starts. Returns what
    could not be done, for the log, or None."""
    try:
        os.sched_setscheduler(
            0, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK, os.sched_param(LOOP_RT_PRIORITY)
        )
        return None
    except OSError as exc:
        reason = exc.strerror
    with contextlib.suppress(OSError):  # second best: ahead of ordinary programs
        os.setpriority(os.PRIO_PROCESS, 0, WORKER_NICE)
    return (
        f"cannot run the event loop at realtime priority ({reason}): on a busy computer "
        "a STOP from a page may wait for a CPU (allow it with CAP_SYS_NICE or an rtprio "
        "limit in /etc/security/limits.conf)"
    )


def watch_jobs_without_threads() -> None:
    """The loop learns of its jobs' ends through pidfds, not a thread each (Python 3.11's
    way): starting a thread makes the realtime loop wait until the new, ordinary thread
    has run once, which on a busy computer may wait for a CPU (seen: 35 ms). Python 3.12
    does this itself; kernels before 5.3 keep the threads."""
    if sys.version_info >= (3, 12) or not hasattr(os, "pidfd_open"):
        return
    try:
        os.close(os.pidfd_open(os.getpid()))
    except OSError:
        return
    asyncio.set_child_watcher(asyncio.PidfdChildWatcher())


def raise_worker_priority() -> None:
    """A worker thread's initializer: niceness WORKER_NICE (Linux: per thread), if
    allowed."""
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, WORKER_NICE)


def at_job_priority() -> None:
    """Take the niceness of jobs (in a job, or as a [FILTER] program's preexec_fn)."""
    _lowered_to(JOB_NICE)


def at_estimate_priority() -> None:
    """Take the niceness of a job's time estimate (after its preview, which a page waits
    for; nobody waits for the estimate)."""
    _lowered_to(ESTIMATE_NICE)


def _lowered_to(nice: int) -> None:
    """This process at niceness ``nice``, and in a session of its own whose scheduling
    group has it too. With the kernel's autogroup scheduling (on in Debian's kernels:
    /proc/sys/kernel/sched_autogroup_enabled) niceness orders only the processes of one
    session, and sessions share the CPUs alike: a job niced within the server's session
    took as much CPU as the browser drawing beside it. (Lowering is always allowed; the
    kernel may refuse a second group change within a second: then the group keeps the
    niceness it has.)"""
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, nice)
    with contextlib.suppress(OSError):
        if os.getsid(0) != os.getpid():
            os.setsid()
        with open("/proc/self/autogroup", "w") as group:
            group.write(str(nice))
