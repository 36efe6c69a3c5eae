"""Our components export LinuxCNC 2.9's pins, parameters and functions (same names, types,
directions and initial values), checked against a recorded LinuxCNC output."""

from __future__ import annotations

from pathlib import Path

from tests.hal.halrun_util import FILES, run_cnc


def _objects(text: str) -> set[tuple[str, ...]]:
    """(kind, type, dir, value, name) of pins and params, (funct, fp, name) of functions;
    owner ids, addresses and the per-function timing objects are left out."""
    found: set[tuple[str, ...]] = set()
    section = ""
    for line in text.splitlines():
        words = line.split()
        if line.startswith(("Component Pins:", "Parameters:", "Exported Functions:")):
            section = words[0]
        elif words and words[0].isdigit():
            if section == "Component" and not words[4].endswith(".time"):
                found.add(("pin", *words[1:5]))
            elif section == "Parameters" and ".tmax" not in words[4]:
                found.add(("param", *words[1:5]))
            elif section == "Exported":
                found.add(("funct", words[3], words[5]))
    return found


def test_components_match_linuxcnc(tmp_path: Path) -> None:
    result = run_cnc("halrun", "-f", str(FILES / "lcnc_components.hal"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    ours = _objects(result.stdout)
    theirs = _objects((FILES / "lcnc_components_output.txt").read_text())
    assert len(theirs) > 300
    assert sorted(theirs - ours) == []
    assert sorted(ours - theirs - OUR_ADDITIONS) == []


# What our components have beyond LinuxCNC's (a LinuxCNC HAL file never names them):
# sim_spindle also simulates M19 orientation for motion's spindle.N.orient pins.
OUR_ADDITIONS = {
    ("pin", "bit", "IN", "FALSE", "sim-spindle.0.orient"),
    ("pin", "float", "IN", "0", "sim-spindle.0.orient-angle"),
    ("pin", "bit", "OUT", "FALSE", "sim-spindle.0.is-oriented"),
}


def test_list_save_and_script_show_are_linuxcncs_byte_for_byte(tmp_path: Path) -> None:
    """``list``, every kind of ``save`` and ``show`` in script mode (-s), with aliases, I/O
    pins, a rounded thread period and hex u32 values (files/README.md)."""
    result = run_cnc("halrun", "-s", "-f", str(FILES / "lcnc_save_list.hal"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout == (FILES / "lcnc_save_list_output.txt").read_text()
