"""threads: create up to three HAL threads (``loadrt threads name1=NAME period1=NS [fp1=0|1]
[name2=... period2=... fp2=...] [name3=...]``).

As LinuxCNC's: without arguments it makes ``thread1`` with a 1 ms period; thread 2 and 3
exist only when given a name and a period above 0. It has no pins or functions of its own
and the threads outlive it, so it can be unloaded and loaded again to make more threads.
"""

from __future__ import annotations

from typing import Any

from hal.core import HalError

# LinuxCNC's defaults: (name, period in ns) of threads 1, 2 and 3
DEFAULTS = {1: ("thread1", 1_000_000), 2: ("", 0), 3: ("", 0)}


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    known = {f"{key}{i}" for key in ("name", "period", "fp") for i in DEFAULTS}
    unknown = set(args) - known
    if unknown:
        raise HalError(f"threads: unknown argument '{sorted(unknown)[0]}'")
    for i, (default_name, default_period) in DEFAULTS.items():
        name = args.get(f"name{i}", default_name)
        try:
            period = int(args.get(f"period{i}", str(default_period)), 0)
            has_fp = int(args.get(f"fp{i}", "1"), 0) != 0
        except ValueError:
            raise HalError(f"threads: period{i} and fp{i} must be whole numbers") from None
        if name and period > 0:
            host.new_thread(name, period, has_fp=has_fp)
