"""The work offsets table: G54..G59.3 (with their XY rotation) and G92, per axis.

The values of every coordinate system live in the interpreter's parameters (#5221.. for
G54, 20 apart; #5211.. for G92), which task writes to [RS274NGC]PARAMETER_FILE whenever
the interpreter synchronises (after each MDI command, at a program's end): that file is
read here. The active system's offsets and G92 come from the status instead, which is
never late. Values are in machine units, as the parameters hold them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from nml.axes import AXIS_LETTERS

SYSTEMS = ("G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3")
G92_BASE = 5211  # X; 5210 is "G92 in effect"
G5X_BASE = 5221  # G54 X; each system 20 further; X..W then the rotation (R)
G5X_STEP = 20


def read_parameters(path: Path | None) -> dict[int, float]:
    """``<number> <value>`` lines of a .var file; an unreadable file or line is skipped
    (this is a display: the interpreter reports a bad file itself)."""
    found: dict[int, float] = {}
    if path is None:
        return found
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return found
    for line in text.splitlines():
        words = line.split()
        if len(words) >= 2 and words[0].isdigit():
            try:
                value = float(words[1])
            except ValueError:
                continue
            if math.isfinite(value):
                found[int(words[0])] = value
    return found


def offsets_table(parameters: dict[int, float], status: Any, axes: str) -> dict[str, Any]:
    """{"axes": "XYZ", "active": "G54", "systems": [{"name", "values": [...], "rotation"}],
    "g92": [...]}; ``status`` a polled stat (or None: the file alone)."""
    indexes = [AXIS_LETTERS.index(letter) for letter in axes]
    systems = []
    for number, name in enumerate(SYSTEMS):
        base = G5X_BASE + G5X_STEP * number
        systems.append(
            {
                "name": name,
                "values": [parameters.get(base + index, 0.0) for index in indexes],
                "rotation": parameters.get(base + 9, 0.0),
            }
        )
    g92 = [parameters.get(G92_BASE + index, 0.0) for index in indexes]
    active = None
    if status is not None:
        number = status.g5x_index - 1
        if 0 <= number < len(SYSTEMS):
            active = SYSTEMS[number]
            systems[number]["values"] = [round(status.g5x_offset[i], 6) for i in indexes]
            systems[number]["rotation"] = round(status.rotation_xy, 6)
        g92 = [round(status.g92_offset[i], 6) for i in indexes]
    return {"axes": axes, "active": active, "systems": systems, "g92": g92}
