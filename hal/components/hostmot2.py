"""hostmot2: LinuxCNC's HostMot2 driver core (``loadrt hostmot2``).

As in LinuxCNC it makes no pins and no functions: it is what the board drivers
(``hm2_eth``) build on, and they refuse to load without it. Its options are accepted for
LinuxCNC's HAL files: ``debug_idrom``, ``debug_module_descriptors``,
``debug_pin_descriptors``, ``debug_modules`` (print what the boards describe) and
``use_serial_numbers``, ``sserial_baudrate`` (smart-serial, not driven yet).
"""

from __future__ import annotations

from typing import Any

from hal.core import HalError

OPTIONS = (
    "debug_idrom",
    "debug_module_descriptors",
    "debug_pin_descriptors",
    "debug_modules",
    "use_serial_numbers",
    "sserial_baudrate",
)


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    unknown = set(args) - set(OPTIONS)
    if unknown:
        raise HalError(f"hostmot2: unknown argument '{sorted(unknown)[0]}'")
    for key, value in args.items():
        try:
            int(value, 0)
        except ValueError:
            raise HalError(f"hostmot2: {key} must be a number, not '{value}'") from None
    host.hostmot2_debug = {key: int(value, 0) for key, value in args.items()}
    print("hm2: loading Mesa HostMot2 driver version 0.15 (cnc)", flush=True)
