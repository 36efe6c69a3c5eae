"""cnc offers what LinuxCNC 2.9's ``linuxcnc`` module offers, with the same shapes.

``linuxcnc_module.json`` was recorded from LinuxCNC's own module by ``record_linuxcnc.py``:
its integer constants, the type of every stat attribute (tuple lengths, dict keys and value
types included), the command methods and the fields of ``tool``.
"""

from __future__ import annotations

import json
from pathlib import Path

import cnc
from tests.api.record_linuxcnc import describe

LINUXCNC = json.loads(Path(__file__).with_name("linuxcnc_module.json").read_text())


def test_constants_have_linuxcncs_names_and_values() -> None:
    ours = {name: getattr(cnc, name, None) for name in LINUXCNC["constants"]}
    assert ours == LINUXCNC["constants"]


def test_stat_attributes_have_linuxcncs_names_and_shapes() -> None:
    s = cnc.stat()  # not connected, as when recorded: every value zero
    ours = {name: json.loads(json.dumps(describe(getattr(s, name)))) for name in LINUXCNC["stat"]}
    assert ours == LINUXCNC["stat"]


def test_command_has_linuxcncs_methods_and_tool_its_fields() -> None:
    c = cnc.command()
    assert [name for name in LINUXCNC["command"] if not hasattr(c, name)] == []
    assert list(cnc.tool._fields) == LINUXCNC["tool"]
