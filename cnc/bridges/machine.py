"""The machine as every bridge publishes it: named values read from ``cnc.stat``, the
operator messages of ``cnc.error_channel``, and the machine's identification.

``MachineView.poll()`` returns the values that changed since the last poll (all of them the
first time, and again after the controller came back), so a bridge publishes on change,
never a fixed flood. Positions are rounded to ``PLACES`` digits, so a change below what a
display shows is no change. The names are the MQTT bridge's topics below the machine's root
(``cnc/<machine>/state``) and the OPC UA bridge's variables (``opcua.py`` maps them).
"""

from __future__ import annotations

import math
import os
import platform
import socket
import time
from dataclasses import dataclass
from typing import Any

import cnc
from cnc.ini import IniFile
from cnc.ui import formatting as fmt

PLACES = 4  # digits kept after '.' for positions, speeds and overrides
OFFLINE = "OFFLINE"  # "state" while the controller is not running
PROGRAM_STATES = ("IDLE", "RUNNING", "PAUSED")


@dataclass(frozen=True)
class Message:
    """One operator message: ``kind`` is error, text or display."""

    time: float  # time.time() when the bridge read it
    kind: str
    text: str

    @property
    def is_alarm(self) -> bool:
        return self.kind == "error"

    def as_dict(self) -> dict[str, Any]:
        return {"time": round(self.time, 3), "kind": self.kind, "text": self.text}


def machine_name(ini: IniFile, section: str) -> str:
    """The name of the machine in topics and the OPC UA address space: ``[section]
    MACHINE_NAME``, else ``[EMC]MACHINE``, else the instance; characters MQTT reserves
    (``/ + #``) and blanks become ``_``."""
    name = (
        (ini.find(section, "MACHINE_NAME") or "").strip()
        or (ini.find("EMC", "MACHINE") or "").strip()
        or os.environ.get("CNC_INSTANCE", "main")
    )
    return "".join("_" if c in "/+#" or c.isspace() or not c.isprintable() else c for c in name)


def _rounded(value: object) -> float | None:
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return None
    return round(x, PLACES) if math.isfinite(x) else None


def program_state(s: Any) -> str:
    """IDLE, RUNNING or PAUSED: the program (or MDI line) of task's interpreter."""
    if s.interp_state == cnc.INTERP_IDLE:
        return "IDLE"
    if s.task_paused or s.paused or s.interp_state == cnc.INTERP_PAUSED:
        return "PAUSED"
    return "RUNNING"


def read_values(s: Any) -> dict[str, Any]:
    """The published values of a polled ``cnc.stat``, JSON-ready."""
    axes = fmt.axes(s)
    machine, work = fmt.pose(s.actual_position), fmt.work_position(s)
    spindle = fmt.item(s.spindle, 0, {})
    spindle = spindle if isinstance(spindle, dict) else {}
    joints = fmt.count(s.joints, len(s.homed))
    return {
        "state": fmt.name_of(fmt.TASK_STATES, s.task_state),
        "estop": s.task_state == cnc.STATE_ESTOP,
        "mode": fmt.name_of(fmt.TASK_MODES, s.task_mode),
        "program/state": program_state(s),
        "program/file": s.file,
        "program/line": int(s.motion_line or s.current_line),
        "position": {letter: _rounded(machine[i]) for i, letter in axes},
        "work_position": {letter: _rounded(work[i]) for i, letter in axes},
        "homed": [bool(h) for h in s.homed[:joints]],
        "feed/override": _rounded(s.feedrate),
        "feed/rapid_override": _rounded(s.rapidrate),
        "feed/velocity": _rounded(s.current_vel * 60.0),  # units per minute
        "spindle/speed": _rounded(spindle.get("speed", 0.0)),
        "spindle/direction": int(spindle.get("direction", 0)),
        "spindle/override": _rounded(spindle.get("override", 1.0)),
        "tool": int(s.tool_in_spindle),
    }


def identification(ini_path: str, ini: IniFile, name: str) -> dict[str, Any]:
    """What the machine is (published once, retained): OPC 40501's Identification."""
    axes = "".join((ini.find("TRAJ", "COORDINATES") or "").split())
    return {
        "name": name,
        "machine": (ini.find("EMC", "MACHINE") or "").strip(),
        "manufacturer": "cnc (LinuxCNC-compatible controller)",
        "software_revision": _software_revision(),
        "linuxcnc_version": "2.9",
        "host": socket.gethostname(),
        "os": platform.platform(terse=True),
        "ini": ini_path,
        "instance": os.environ.get("CNC_INSTANCE", "main"),
        "coordinates": axes,
        "joints": int((ini.find("KINS", "JOINTS") or "0").strip() or 0),
        "linear_units": (ini.find("TRAJ", "LINEAR_UNITS") or "").strip(),
    }


def _software_revision() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("cnc-controller")
    except PackageNotFoundError:
        return "unknown"


class MachineView:
    """The running machine (found from the INI file) as changes of named values and
    operator messages; the controller may stop and start again under it."""

    def __init__(self, ini_path: str) -> None:
        self.ini_path = ini_path
        self.stat = cnc.stat(ini_path)
        self.errors = cnc.error_channel(ini_path)
        self.values: dict[str, Any] = {}
        self.is_online = False

    def poll(self) -> dict[str, Any]:
        """The values that changed since the last call ({"state": "OFFLINE"} once the
        controller has stopped)."""
        try:
            self.stat.poll()
            values = read_values(self.stat)
        except cnc.error:
            if not self.is_online and self.values:
                return {}
            self.is_online = False
            self.values = {"state": OFFLINE}
            return dict(self.values)
        if not self.is_online:  # (again): everything is news
            self.is_online = True
            self.values = {}
        changed = {key: value for key, value in values.items() if self.values.get(key) != value}
        self.values.update(changed)
        return changed

    def messages(self) -> list[Message]:
        """The operator messages that arrived since the last call."""
        found = []
        while True:
            try:
                message = self.errors.poll()
            except cnc.error:
                break
            if message is None:
                break
            kind, text = message
            found.append(Message(time.time(), fmt.MESSAGE_KINDS.get(kind, "error"), text))
        return found

    def close(self) -> None:
        self.stat.close()
        self.errors.close()
