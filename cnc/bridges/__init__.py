"""Bridges from a running machine to the plant: MQTT and OPC UA.

Each bridge is a process of its own, attached to the status and error buffers as any UI
is (``cnc.stat``, ``cnc.error_channel``, ``cnc.command``), started by the launcher from
its INI section (``[MQTT]ENABLE``, ``[OPCUA]ENABLE``) and restarted by it if it dies: a
bridge carries no safety input or output, so its death changes nothing on the machine.

| module | what it is |
|---|---|
| ``machine.py`` | the machine's values, messages and identification, as both bridges publish them |
| ``mqtt.py`` | ``cnc bridge mqtt INI``: one topic tree per machine, commands when enabled |
| ``opcua.py`` | ``cnc bridge opcua INI``: an OPC UA server shaped as OPC 40501-1 (Machine Tools) |
| ``mqtt_publisher.py`` | LinuxCNC's ``mqtt-publisher`` for ``loadusr``: HAL values to MQTT |
"""

from __future__ import annotations

import importlib
import sys

# [section] -> (bridge name, module); the launcher starts each enabled one
BRIDGES = {"MQTT": ("mqtt", "cnc.bridges.mqtt"), "OPCUA": ("opcua", "cnc.bridges.opcua")}


def command_line(section: str, ini_path: str) -> list[str]:
    """The command that runs the bridge of INI section ``section`` for a machine."""
    return [sys.executable, "-m", BRIDGES[section][1], ini_path]


def main(argv: list[str]) -> int:
    """``cnc bridge mqtt|opcua INI``."""
    modules = dict(BRIDGES.values())
    if not argv or argv[0] not in modules:
        print(f"usage: cnc bridge {'|'.join(modules)} INI", file=sys.stderr)
        return 2
    return int(importlib.import_module(modules[argv[0]]).main(argv[1:]) or 0)
