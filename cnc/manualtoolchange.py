"""``hal_manualtoolchange`` without a dialog: what ``loadusr hal_manualtoolchange`` runs here.

LinuxCNC's ``hal_manualtoolchange`` (loaded by ``axis_manualtoolchange.hal`` and many sample
configs) shows a dialog asking the operator to insert the tool, and answers iocontrol's
tool-change handshake when the operator clicks. This stand-in has the same component and
pins, and answers at once, printing which tool to insert, so a machine using it runs headless
and M6 completes:

- ``hal_manualtoolchange.number`` (s32 in): the tool to insert;
- ``hal_manualtoolchange.change`` (bit in): a change is requested;
- ``hal_manualtoolchange.changed`` (bit out): follows ``change`` (the change is confirmed);
- ``hal_manualtoolchange.change_button`` (bit in): accepted, as LinuxCNC's external
  confirmation button; nothing waits for it here.
"""

from __future__ import annotations

import signal
import sys
import time

from hal.api import HAL_BIT, HAL_IN, HAL_OUT, HAL_S32, component

NAME = "hal_manualtoolchange"
POLL_S = 0.01  # LinuxCNC's polls its pins at 100 Hz too


def main(argv: list[str] | None = None) -> int:
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))  # `unload` sends SIGTERM
    comp = component(NAME)
    comp.newpin("number", HAL_S32, HAL_IN)
    comp.newpin("change", HAL_BIT, HAL_IN)
    comp.newpin("changed", HAL_BIT, HAL_OUT)
    comp.newpin("change_button", HAL_BIT, HAL_IN)
    comp.ready()
    try:
        while True:
            is_requested = bool(comp["change"])
            if is_requested and not comp["changed"]:
                print(
                    f"{NAME}: insert tool {comp['number']} (confirmed at once: no dialog here)",
                    file=sys.stderr,
                    flush=True,
                )
            comp["changed"] = is_requested
            time.sleep(POLL_S)
    except KeyboardInterrupt:
        return 0
    finally:
        comp.exit()


if __name__ == "__main__":
    sys.exit(main())
