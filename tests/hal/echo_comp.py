"""A userspace component for tests: ``echo.out`` follows ``2 * echo.in``; ``echo.count``
counts updates. Run as ``python tests/hal/echo_comp.py [name [--crash]]``; stops on SIGTERM;
with ``--crash`` it kills itself (SIGKILL, no cleanup) after 50 ms of being ready."""

import os
import signal
import sys
import time

from hal.api import HAL_FLOAT, HAL_IN, HAL_OUT, HAL_S32, component


def main() -> None:
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    comp = component(sys.argv[1] if len(sys.argv) > 1 else "echo")
    comp.newpin("in", HAL_FLOAT, HAL_IN)
    comp.newpin("out", HAL_FLOAT, HAL_OUT)
    comp.newpin("count", HAL_S32, HAL_OUT)
    comp.ready()
    is_crashing = "--crash" in sys.argv
    started = time.monotonic()
    try:
        while True:
            if is_crashing and time.monotonic() - started > 0.05:
                os.kill(os.getpid(), signal.SIGKILL)
            comp["out"] = 2 * comp["in"]
            comp["count"] = comp["count"] + 1
            time.sleep(0.002)
    finally:
        comp.exit()


if __name__ == "__main__":
    main()
