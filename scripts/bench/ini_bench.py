#!/usr/bin/env python3
"""INI reading benchmark: what checking a machine's files costs each process (JSON).

    python scripts/bench/ini_bench.py [--repeat N]

Times, in milliseconds (median of N runs): reading configs/sim/mill.ini (``IniFile.load``),
checking it against the schema (``load_config``, as task, iocontrol and halui do), the
launcher's whole start-up check with the tool table and .var file (``check_machine``),
checking every LinuxCNC sample INI file where LinuxCNC is installed (``samples_ms``, all of
them), and one ``inivar`` lookup as a process: ours (``cnc inivar``) and LinuxCNC's.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from cnc.ini import IniError, IniFile  # noqa: E402
from cnc.inischema import check_machine, load_config  # noqa: E402

MILL = REPO / "configs" / "sim" / "mill.ini"
SAMPLES = Path("/usr/share/doc/linuxcnc/examples/sample-configs")


def median_ms(action, repeat: int) -> float:  # type: ignore[no-untyped-def]
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        samples.append((time.perf_counter() - start) * 1000)
    return round(statistics.median(samples), 3)


def check_samples() -> None:
    for path in SAMPLES.rglob("*.ini"):
        with contextlib.suppress(IniError):  # the few refused by design
            load_config(path)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=50)
    repeat = parser.parse_args().repeat
    inivar = ["-ini", str(MILL), "-var", "MAX_LIMIT", "-sec", "AXIS_Z"]
    ours = [sys.executable, "-m", "cnc", "inivar", *inivar]
    result = {
        "ini_load_ms": median_ms(lambda: IniFile.load(MILL), repeat),
        "load_config_ms": median_ms(lambda: load_config(MILL), repeat),
        "check_machine_ms": median_ms(lambda: check_machine(MILL), repeat),
        "cnc_inivar_process_ms": median_ms(
            lambda: subprocess.run(ours, capture_output=True, check=True), max(repeat // 10, 3)
        ),
    }
    if SAMPLES.is_dir():
        result["samples"] = len(list(SAMPLES.rglob("*.ini")))
        result["samples_ms"] = median_ms(check_samples, 3)
    linuxcnc = shutil.which("inivar", path="/usr/bin")
    if linuxcnc:
        result["linuxcnc_inivar_process_ms"] = median_ms(
            lambda: subprocess.run([linuxcnc, *inivar], capture_output=True, check=True),
            max(repeat // 10, 3),
        )
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
