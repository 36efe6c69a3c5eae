"""scripts/bench/motion_bench.py end to end: our machine runs a short program and the JSON
report has the figures the motion issue asks for (no timing is checked here)."""

from __future__ import annotations

import json
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
BENCH = REPO / "scripts" / "bench" / "motion_bench.py"

# exact stop at every corner: the commanded path never leaves the programmed square
SQUARE = """G21 G90 G61
G1 X2 Y0 Z10 F1200
G1 X2 Y2
G1 X0 Y2
G0 X0 Y0
M2
"""
LATENESS_KEYS = {"p50_us", "p99_us", "p999_us", "max_us", "overruns"}


def test_quick_run_reports_every_figure(procs, tmp_path, cnc_instance):
    program = tmp_path / "square.ngc"
    program.write_text(SQUARE)
    proc = procs.python(
        str(BENCH), "--quick", "--no-lcnc", "--programs", str(program),
        "--instance", cnc_instance,
    )  # fmt: skip
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    report = json.loads(out)
    lateness = report["lateness"]
    assert set(lateness) >= LATENESS_KEYS
    assert set(lateness["loaded"]) >= LATENESS_KEYS
    assert lateness["periods"] > 0
    assert report["planner_us_per_period"]["p50"] > 0
    assert isinstance(report["host_memory_growth_mib"], float)
    floor = report["machine_floor"]  # the empty C loop, when a C compiler is there
    if floor is not None:
        assert set(floor) >= LATENESS_KEYS and set(floor["loaded"]) >= LATENESS_KEYS
        assert floor["periods"] > 0
    square = report["programs"]["square"]
    assert square["ours_is_ok"] and "ours_messages" not in square, square
    assert square["lcnc_s"] is None
    assert square["ours_s"] > 0
    # it moved, within the machine's limits, on the programmed path (MOT-012 style limits)
    assert 0 < square["max_vel_ratio"] <= 1.0 + 1e-6
    assert 0 < square["max_acc_ratio"] <= 1.0 + 1e-3
    assert square["max_path_dev_mm"] < 1e-4
