#!/usr/bin/env python3
"""Trajectory-planner benchmark: runs the shared benchmark programs through the default
planner at a 1 ms servo period on the limits of LinuxCNC's sim ``axis_mm.ini`` and prints
JSON with, per program: cycle time (next to LinuxCNC 2.9's), peak axis velocity and
acceleration (and their ratio to the limits), the largest distance from the programmed
polyline, and the planner's time per servo period (queueing the period's moves plus
``step``): ``planner_us_per_period`` is this thread's CPU time, which other processes do
not inflate; ``planner_wall_us_per_period`` is wall time.

A tiny reader here, not the interpreter, understands just what these programs use
(G0/G1/G2/G3 with X Y Z I J K F (P turns), G17/G18/G19, G61, G61.1 and G64 [P]), so the
planner alone is measured; the O-word programs are left to motion_bench.py. Every program
starts at X0 Y0 Z10, as the reference bench does.

    .venv/bin/python scripts/bench/tp_bench.py [--programs circle_g64 ...] [--adds-per-period N]
"""

from __future__ import annotations

import argparse
import gc
import json
import re
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from motion.tp import TermCond, TrajectoryPlanner

PROGRAMS = Path("/work/shared/reference/programs")
LCNC_CYCLE_S = {  # LinuxCNC 2.9 sim, same machine, ../shared/reference/README.md
    "circle_g64": 14.350,
    "arc_spiral": 24.462,
    "circle_g61": 21.975,
    "corners_g64p": 33.367,
    "bigprog_50k": 89.792,
}
AXIS_VEL = 30.48
AXIS_ACC = 508.0
TRAJ_VEL = 53.34
PERIOD = 0.001
START = (0.0, 0.0, 10.0)
WORD = re.compile(r"([A-Z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")


PLANES = {17: ((0, 1), 2), 18: ((2, 0), 1), 19: ((1, 2), 0)}  # (in-plane axes, normal axis)
ARC_WORDS = "IJK"


def read_program(path: Path) -> list[dict]:
    """Moves of a program of G0/G1/G2/G3 (G17/G18/G19, I J K offsets, P turns), F, G61,
    G61.1 and G64 [P]: dicts with end, vel, rapid, term, tolerance, and for arcs centre,
    normal and turns."""
    pos = list(START)
    feed = 0.0
    motion = 0
    plane = 17
    term, tolerance = TermCond.BLEND, 0.0
    moves = []
    for raw in path.read_text().splitlines():
        text = re.sub(r"\(.*?\)", "", raw.upper()).strip()
        target = list(pos)
        offsets = [0.0, 0.0, 0.0]
        turns = 1
        has_axis = False
        for letter, value in WORD.findall(text):
            num = float(value)
            if letter == "G":
                if num in (0, 1, 2, 3):
                    motion = int(num)
                elif num in (17, 18, 19):
                    plane = int(num)
                elif num == 61:  # exact path (LinuxCNC's canon: TC_TERM_COND_EXACT)
                    term = TermCond.EXACT
                elif abs(num - 61.1) < 1e-6:  # exact stop
                    term = TermCond.STOP
                elif num == 64:
                    term, tolerance = TermCond.BLEND, 0.0
            elif letter == "P":
                if motion in (2, 3):
                    turns = int(num)
                else:
                    tolerance = num
            elif letter == "F":
                feed = num / 60.0
            elif letter in "XYZ":
                target["XYZ".index(letter)] = num
                has_axis = True
            elif letter in ARC_WORDS:
                offsets[ARC_WORDS.index(letter)] = num
        if not has_axis:
            continue
        move = {
            "end": target,
            "vel": TRAJ_VEL if motion == 0 else feed,
            "rapid": motion == 0,
            "term": term,
            "tolerance": tolerance,
        }
        if motion in (2, 3):
            (a, b), n = PLANES[plane]
            centre = list(pos)
            centre[a] += offsets[a]
            centre[b] += offsets[b]
            normal = [0.0, 0.0, 0.0]
            normal[n] = 1.0 if motion == 3 else -1.0
            move.update(centre=centre, normal=normal, turns=turns - 1)
        moves.append(move)
        pos = target
    return moves


def dense_path(moves: list[dict]) -> tuple[np.ndarray, list[int]]:
    """The programmed path as a fine polyline (arcs split into 0.5 degree chords) and the
    index of each move's first point."""
    points = [np.array(START)]
    firsts = []
    for m in moves:
        firsts.append(len(points) - 1)
        start, end = points[-1], np.array(m["end"])
        if "centre" not in m:
            points.append(end)
            continue
        centre, normal = np.array(m["centre"]), np.array(m["normal"])
        rel0 = start - centre
        axial0 = rel0 @ normal
        e1 = rel0 - axial0 * normal
        r = np.linalg.norm(e1)
        e1 /= r
        e2 = np.cross(normal, e1)
        rel1 = end - centre
        angle = np.arctan2(rel1 @ e2, rel1 @ e1)
        angle = angle if angle > 1e-12 else angle + 2 * np.pi
        angle += 2 * np.pi * m["turns"]
        axial1 = rel1 @ normal
        for t in np.linspace(0, 1, max(2, int(np.degrees(angle) * 2)))[1:]:
            phi = angle * t
            axial = axial0 + (axial1 - axial0) * t
            points.append(centre + r * (np.cos(phi) * e1 + np.sin(phi) * e2) + axial * normal)
    firsts.append(len(points) - 1)
    return np.array(points), firsts


def seg_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point to the segment a-b (arrays of the same length)."""
    ab = b - a
    den = np.einsum("ij,ij->i", ab, ab)
    t = np.where(den > 0, np.einsum("ij,ij->i", points - a, ab) / np.where(den > 0, den, 1), 0)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


def queue(tp: TrajectoryPlanner, m: dict, motion_id: int) -> None:
    end = [*m["end"], 0, 0, 0, 0, 0, 0]
    if "centre" in m:
        tp.add_circle(
            end,
            m["centre"],
            m["normal"],
            m["turns"],
            m["vel"],
            TRAJ_VEL,
            AXIS_ACC,
            motion_id=motion_id,
            term=m["term"],
            tolerance=m["tolerance"],
        )
    else:
        tp.add_line(
            end,
            m["vel"],
            TRAJ_VEL,
            AXIS_ACC,
            motion_id=motion_id,
            term=m["term"],
            tolerance=m["tolerance"],
            is_rapid=m["rapid"],
        )


def run(name: str, adds_per_period: int) -> dict:
    moves = read_program(PROGRAMS / f"{name}.ngc")
    limits_v = [AXIS_VEL] * 3 + [1e9] * 6
    limits_a = [AXIS_ACC] * 3 + [1e9] * 6
    tp = TrajectoryPlanner(limits_v, limits_a, PERIOD, max_vel=TRAJ_VEL, max_acc=AXIS_ACC)
    tp.set_position([*START, 0, 0, 0, 0, 0, 0])
    samples = [START]
    ids = [0]
    wall_ns = []
    cpu_ns = []
    k = 0
    perf = time.perf_counter_ns
    cpu = time.thread_time_ns  # CPU time of this thread: excludes time taken by others
    gc.disable()  # the realtime loop keeps the garbage collector out, as motion will
    try:
        while True:
            t0 = perf()
            c0 = cpu()
            added = 0
            while k < len(moves) and added < adds_per_period and not tp.is_full:
                queue(tp, moves[k], k + 1)
                k += 1
                added += 1
            pos = tp.step()
            cpu_ns.append(cpu() - c0)
            wall_ns.append(perf() - t0)
            samples.append((pos[0], pos[1], pos[2]))
            ids.append(tp.motion_id)
            if k >= len(moves) and tp.is_done:
                break
    finally:
        gc.enable()
    path = np.array(samples)
    vel = np.abs(np.diff(path, axis=0)) / PERIOD
    acc = np.abs(np.diff(path, 2, axis=0)) / PERIOD**2
    # deviation: distance to the programmed path around the move being executed
    dense, firsts = dense_path(moves)
    ids = np.clip(np.array(ids), 1, len(moves))
    dev = np.full(len(path), np.inf)
    for n in range(1, len(moves) + 1):
        sel = ids == n
        if not sel.any():
            continue
        lo, hi = firsts[max(n - 2, 0)], firsts[min(n + 1, len(moves))]
        for i in range(lo, hi):
            a = np.broadcast_to(dense[i], (int(sel.sum()), 3))
            b = np.broadcast_to(dense[i + 1], a.shape)
            dev[sel] = np.minimum(dev[sel], seg_distance(path[sel], a, b))
    cpu_us = np.array(cpu_ns) / 1000.0
    wall_us = np.array(wall_ns) / 1000.0
    ours = (len(path) - 1) * PERIOD
    return {
        "ours_s": round(ours, 3),
        "lcnc_s": LCNC_CYCLE_S.get(name),
        "moves": len(moves),
        "segments_per_s": round(len(moves) / ours, 1),
        "max_vel_mm_s": [round(float(v), 3) for v in vel.max(axis=0)],
        "max_acc_mm_s2": [round(float(a), 2) for a in acc.max(axis=0)],
        "max_vel_ratio": round(float(vel.max()) / AXIS_VEL, 4),
        "max_acc_ratio": round(float(acc.max()) / AXIS_ACC, 4),
        "max_path_dev_mm": round(float(dev.max()), 5),
        "planner_us_per_period": _stats(cpu_us),
        "planner_wall_us_per_period": _stats(wall_us),
    }


def _stats(us: np.ndarray) -> dict:
    return {
        "median": round(float(np.median(us)), 1),
        "p99": round(float(np.percentile(us, 99)), 1),
        "p999": round(float(np.percentile(us, 99.9)), 1),
        "max": round(float(us.max()), 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--programs", nargs="*", default=list(LCNC_CYCLE_S))
    parser.add_argument(
        "--adds-per-period",
        type=int,
        default=4,
        help="moves the command handler may queue per servo period",
    )
    args = parser.parse_args()
    result = {
        "servo_period_s": PERIOD,
        "adds_per_period": args.adds_per_period,
        "programs": {name: run(name, args.adds_per_period) for name in args.programs},
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
