#!/usr/bin/env python3
"""Python API benchmark: the cost of ``cnc.stat().poll()`` on a full EMC_STAT (JSON).

    python scripts/bench/api_bench.py [--polls N]

Creates the controller's buffers (configs/common/cnc.nml) in a private instance, writes one
EMC_STAT, then times ``poll()`` (which copies the status and nothing else) and, for
reference, reading one tuple attribute after a poll. Keys: poll_us_median, poll_us_p99,
poll_and_position_us_median.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))
os.environ["CNC_INSTANCE"] = f"apibench{os.getpid()}"

import cnc  # noqa: E402
from nml import emc  # noqa: E402
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config  # noqa: E402
from nml.ipcnames import remove_instance_objects  # noqa: E402


def percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def timed(action, count: int) -> list[float]:  # type: ignore[no-untyped-def]
    clock = time.perf_counter
    samples = []
    for _ in range(count):
        start = clock()
        action()
        samples.append((clock() - start) * 1e6)
    return samples


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--polls", type=int, default=20000)
    args = parser.parse_args()
    try:
        with Nml(load_config(), "cnc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR]) as nml:
            status = emc.EMC_STAT()
            status.motion.traj.position.tran.x = 1.0
            nml[EMC_STATUS].write(status)
            s = cnc.stat()
            timed(s.poll, 1000)  # warm up
            polls = timed(s.poll, args.polls)
            with_position = timed(lambda: (s.poll(), s.position), args.polls // 4)
            s.close()
    finally:
        remove_instance_objects()
    print(
        json.dumps(
            {
                "poll_us_median": round(statistics.median(polls), 3),
                "poll_us_p99": round(percentile(polls, 0.99), 3),
                "poll_and_position_us_median": round(statistics.median(with_position), 3),
            }
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
