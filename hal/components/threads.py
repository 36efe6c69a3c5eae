"""threads: create up to three HAL threads (``loadrt threads name1=NAME period1=NS [fp1=0|1]``).

Like LinuxCNC's, it has no pins or functions of its own and the threads outlive it, so it
can be unloaded and loaded again to make more threads.
"""

from __future__ import annotations

from typing import Any

from hal.core import HalError


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    known = {f"{key}{i}" for key in ("name", "period", "fp") for i in (1, 2, 3)}
    unknown = set(args) - known
    if unknown:
        raise HalError(f"threads: unknown argument '{sorted(unknown)[0]}'")
    made = 0
    for i in (1, 2, 3):
        name = args.get(f"name{i}")
        if not name:
            continue
        try:
            period = int(args.get(f"period{i}", ""))
        except ValueError:
            raise HalError(f"threads: period{i} must be a number of nanoseconds") from None
        fp = args.get(f"fp{i}", "1")
        if fp not in ("0", "1"):
            raise HalError(f"threads: fp{i} must be 0 or 1")
        host.new_thread(name, period, has_fp=fp == "1")
        made += 1
    if not made:
        raise HalError("threads: no thread given (name1=... period1=...)")
