"""``cnc latency-test``: can this computer run the machine? LinuxCNC's latency-test, in text.

    cnc latency-test [BASE-PERIOD [SERVO-PERIOD]] [--seconds S] [--json]

Runs the realtime host's threads (default a 25 µs base thread and a 1 ms servo thread,
as LinuxCNC's; one period given: a servo thread only; times take the suffixes s, ms, us,
ns, and plain numbers below 1000 are µs) with nothing in them, first on an idle computer,
then with a busy process on every other CPU, and prints each thread's max jitter (how far
the time between two periods strayed from the period) and max lateness (how long after
its deadline a period started), then what the figures mean for the machine and what to
change when they are poor. Abuse the computer while it runs (move windows, copy files,
play a video): the worst case is what counts. The host's settings come from
``$CNC_HAL_*`` as for ``cnc run`` (hal/README.md).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from typing import Any

DEFAULT_BASE_NS = 25_000
DEFAULT_SERVO_NS = 1_000_000

# LinuxCNC's bands for the worst jitter, in µs, and what they mean
GOOD_FOR_STEPPING_US = 20.0
STEPPING_LIMIT_US = 50.0
CARD_LIMIT_US = 500.0


def parse_time(text: str) -> int:
    """A period as latency-test takes it: 25us, 1ms, 50000 (ns), 25 (µs: under 1000)."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*(s|ms|us|µs|ns)?\s*", text)
    if not match:
        raise ValueError(f"not a time: '{text}' (use e.g. 25us, 1ms, 50000)")
    value, unit = float(match.group(1)), match.group(2)
    if unit is None:
        unit = "us" if value < 1000 else "ns"
    scale = {"s": 1e9, "ms": 1e6, "us": 1e3, "µs": 1e3, "ns": 1.0}[unit]
    return round(value * scale)


def verdict(jitter_us: float) -> str:
    """What the worst jitter means for a machine (LinuxCNC's bands)."""
    if jitter_us < GOOD_FOR_STEPPING_US:
        return (
            f"GOOD: under {GOOD_FOR_STEPPING_US:g} µs. Software stepping (stepgen in a base "
            "thread) will give smooth motion; a step card works as well."
        )
    if jitter_us < STEPPING_LIMIT_US:
        return (
            f"USABLE for software stepping: {GOOD_FOR_STEPPING_US:g}-{STEPPING_LIMIT_US:g} µs. "
            "Expect a lower maximum step rate (slower rapids with microstepping or fine "
            "screws); a card that makes the steps (a Mesa card) avoids the limit."
        )
    if jitter_us < CARD_LIMIT_US:
        return (
            f"NEEDS A STEP CARD: {STEPPING_LIMIT_US:g}-{CARD_LIMIT_US:g} µs is too much for "
            "software stepping, but fine for a 1 ms servo thread driving a card that makes "
            "the step pulses itself (a Mesa 7I96S, 7I76E, 7I92 ...)."
        )
    return (
        f"NOT USABLE: over {CARD_LIMIT_US:g} µs the servo thread itself is late; no card "
        "helps. Fix the computer first (below), or use another one."
    )


ADVICE = """What to change when the figures are poor, most effective first:
  1. Give the realtime threads a CPU of their own: add  isolcpus=N nohz_full=N rcu_nocbs=N
     (N = the last CPU) to the kernel command line: GRUB_CMDLINE_LINUX in
     /etc/default/grub, then  sudo update-grub  and reboot. The threads go there by
     themselves (CNC_HAL_CPU=N picks another).
  2. Keep interrupts off that CPU: stop irqbalance or ban the CPU from it
     (IRQBALANCE_BANNED_CPUS), and check /proc/interrupts: an interrupt counting up on
     that CPU (network card, USB, graphics) can be moved with  /proc/irq/NUMBER/smp_affinity.
  3. Run a PREEMPT_RT kernel (Debian: sudo apt install linux-image-rt-amd64, then boot it).
  4. In the BIOS: turn off power-saving C-states, SpeedStep/Cool'n'Quiet, hyper-threading
     and legacy USB emulation (SMI interrupts), and any "green" or turbo settings.
  5. Use the onboard Ethernet port for a Mesa card only, and a different graphics card or
     driver if moving windows makes the figures jump."""


def _us(value: float | None) -> str:
    return f"{value:>9}" if value is not None else f"{'-':>9}"


def _report_lines(result: dict[str, Any], advice_needed: bool) -> list[str]:
    lines = []
    for name in ("base-thread", "servo-thread"):
        phases = [(label, result[label].get(name)) for label in ("idle", "loaded")]
        if not any(figures for _, figures in phases):
            continue
        period = next(f for _, f in phases if f)["period_ns"]
        lines.append(f"{name} ({period / 1000:g} µs):")
        for label, figures in phases:
            if figures is None:
                continue
            jitter, late = figures["jitter"], figures["lateness"]
            lines.append(
                f"  {label:<7} max jitter {_us(jitter['max_us'])} µs   "
                f"max lateness {_us(late['max_us'])} µs   periods {late['periods']}"
                f"   overruns {late['overruns']}"
            )
    lines.append("")
    lines.append(f"Worst max jitter: {result['worst_jitter_us']} µs")
    lines.append(verdict(result["worst_jitter_us"]))
    if result["other_rt_threads"]:
        lines.append(
            "Note: other realtime threads run on the same CPU "
            f"({', '.join(result['other_rt_threads'])}): stop them and measure again."
        )
    if not result["is_realtime"]:
        lines.append(
            "Note: the threads ran without realtime priority (not root, no CAP_SYS_NICE, "
            "or CNC_HAL_NO_RT=1): allow it (e.g. an rtprio limit in "
            "/etc/security/limits.conf) and measure again."
        )
    if advice_needed:
        lines += ["", ADVICE]
    return lines


def run(periods_ns: list[int], seconds: float) -> dict[str, Any]:
    """The measurement: half the time idle, half loaded."""
    from hal.latency import measure_threads
    from hal.rtapi_app import host_options_from_env

    options = host_options_from_env()
    idle = measure_threads(periods_ns, seconds / 2, is_loaded=False, host_options=options)
    loaded = measure_threads(periods_ns, seconds / 2, is_loaded=True, host_options=options)
    worst = 0.0
    for phase in (idle, loaded):
        for name in ("base-thread", "servo-thread"):
            figures = phase.get(name)
            if figures and figures["jitter"]["max_us"] is not None:
                worst = max(worst, figures["jitter"]["max_us"])
    return {
        "idle": idle,
        "loaded": loaded,
        "worst_jitter_us": worst,
        "verdict": verdict(worst),
        "other_rt_threads": sorted(set(idle["other_rt_threads"]) | set(loaded["other_rt_threads"])),
        "is_realtime": options.get("is_rt", True),
    }


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="cnc latency-test", description=__doc__.split("\n\n")[0])
    parser.add_argument("periods", nargs="*", help="[base-period [servo-period]] (25us 1ms)")
    parser.add_argument("--seconds", type=float, default=10.0, help="total time (10)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args(argv)
    if len(args.periods) > 2:
        parser.error("at most two periods: base-period servo-period")
    try:
        given = [parse_time(text) for text in args.periods]
    except ValueError as exc:
        parser.error(str(exc))
    if not given:
        periods = [DEFAULT_BASE_NS, DEFAULT_SERVO_NS]
    elif len(given) == 1:
        periods = given  # a servo thread only
    else:
        periods = sorted(set(given))  # the shorter is the base thread, as in LinuxCNC
    if any(period < 1000 for period in periods):
        parser.error("periods must be at least 1 µs")
    if args.seconds <= 0:
        parser.error("--seconds must be positive")
    if not args.json:
        print(
            f"Measuring for {args.seconds:g} s (half idle, half with the other CPUs busy): "
            "use the computer meanwhile...",
            flush=True,
        )
    result = run(periods, args.seconds)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print("\n".join(_report_lines(result, result["worst_jitter_us"] >= GOOD_FOR_STEPPING_US)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
