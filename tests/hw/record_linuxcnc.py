"""Record what LinuxCNC's own hm2_eth makes of the simulated 7I96S (run as root).

    .venv/bin/python tests/hw/record_linuxcnc.py

LinuxCNC's hm2_eth pins the board's MAC in the ARP table, which the loopback device
refuses, so the simulator and LinuxCNC run in two network namespaces joined by a veth
pair (10.10.10.1 <-> 10.10.10.10, the board's default address; nothing leaves them).
LinuxCNC runs as the normal user ``cnc``. The output, ``fixtures/lcnc_hm2_eth_7i96s.txt``,
lists every pin, parameter, alias and function LinuxCNC's driver made, with types and
directions; ``test_hm2_names.py`` checks ours against it.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
FIXTURE = Path(__file__).with_name("fixtures") / "lcnc_hm2_eth_7i96s.txt"
HOST_NS, BOARD_NS = "cnc-hm2-host", "cnc-hm2-board"
BOARD_IP = "10.10.10.10"
BOARD_MAC = "00:60:1b:96:00:01"  # hal.hm2.sim.BOARD_MAC: the board answers with it
HAL = """loadrt hostmot2
loadrt hm2_eth board_ip={ip} config="num_encoders=1 num_pwmgens=1 num_stepgens=5"
show pin
show param
show funct
show alias
"""


def sh(*args: str) -> None:
    subprocess.run(args, check=True)


def setup() -> None:
    for ns in (HOST_NS, BOARD_NS):
        sh("ip", "netns", "add", ns)
        sh("ip", "-n", ns, "link", "set", "lo", "up")
    sh("ip", "link", "add", "hm2-h", "type", "veth", "peer", "name", "hm2-b")
    sh("ip", "link", "set", "hm2-h", "netns", HOST_NS)
    sh("ip", "link", "set", "hm2-b", "netns", BOARD_NS)
    sh("ip", "-n", BOARD_NS, "link", "set", "hm2-b", "address", BOARD_MAC)
    sh("ip", "-n", HOST_NS, "addr", "add", "10.10.10.1/24", "dev", "hm2-h")
    sh("ip", "-n", BOARD_NS, "addr", "add", f"{BOARD_IP}/24", "dev", "hm2-b")
    for ns, dev in ((HOST_NS, "hm2-h"), (BOARD_NS, "hm2-b")):
        sh("ip", "-n", ns, "link", "set", dev, "up")


def teardown() -> None:
    for ns in (HOST_NS, BOARD_NS):
        subprocess.run(["ip", "netns", "del", ns], check=False)


def objects(text: str) -> list[str]:
    """'pin NAME TYPE DIR', 'param ...', 'alias ALIAS NAME', 'funct NAME' lines, sorted."""
    lines, section = [], ""
    for line in text.splitlines():
        if line.rstrip().endswith(":") and not line.startswith(" "):
            section = line.strip().rstrip(":").replace(" ", "")  # "ComponentPins" ...
            continue
        if section in ("ComponentPins", "Parameters"):
            m = re.match(r"\s*\d+\s+(bit|float|s32|u32)\s+(IN|OUT|I/O|RW|RO)\s+\S+\s+(\S+)", line)
            if m:
                kind = "pin" if section == "ComponentPins" else "param"
                lines.append(f"{kind} {m.group(3)} {m.group(1)} {m.group(2)}")
        elif section == "ParameterAliases":
            m = re.match(r"\s*(hm2\S+)\s+(hm2\S+)", line)
            if m:
                lines.append(f"alias {m.group(1)} {m.group(2)}")
        elif section == "ExportedFunctions":
            m = re.match(r"\s*\d+\s+\S+\s+\S+\s+(YES|NO)\s+\d+\s+(\S+)", line)
            if m:
                lines.append(f"funct {m.group(2)}")
    return sorted(lines)


def main() -> int:
    teardown()
    setup()
    sim = subprocess.Popen(
        ["ip", "netns", "exec", BOARD_NS, sys.executable, "-m", "hal.hm2.sim", "--ip", BOARD_IP],
        cwd=REPO,
    )
    try:
        time.sleep(1.0)
        with tempfile.NamedTemporaryFile("w", suffix=".hal", delete=False) as hal_file:
            hal_file.write(HAL.format(ip=BOARD_IP))
        Path(hal_file.name).chmod(0o644)
        for _ in range(5):  # LinuxCNC's start-up waits 1.6 ms per answer: retry a busy moment
            run = subprocess.run(
                ["ip", "netns", "exec", HOST_NS, "su", "cnc", "-c", f"halrun -f {hal_file.name}"],
                capture_output=True, text=True, cwd="/tmp", check=False,
            )  # fmt: skip
            if run.returncode == 0:
                break
        else:
            print(run.stdout, run.stderr, file=sys.stderr)
            return 1
        header = [
            "# What LinuxCNC 2.9's hm2_eth makes of the simulated 7I96S (hal.hm2.sim),",
            '# config="num_encoders=1 num_pwmgens=1 num_stepgens=5".',
            "# Made by: .venv/bin/python tests/hw/record_linuxcnc.py (as root)",
        ]
        FIXTURE.write_text("\n".join([*header, *objects(run.stdout)]) + "\n")
        print(f"wrote {FIXTURE}")
        return 0
    finally:
        sim.terminate()
        sim.wait(5)
        teardown()


if __name__ == "__main__":
    sys.exit(main())
