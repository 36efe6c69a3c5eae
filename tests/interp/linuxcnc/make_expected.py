#!/usr/bin/env python3
"""Record what LinuxCNC 2.9's rs274 prints for every case of cases.txt (see README.md).

    python3 tests/interp/linuxcnc/make_expected.py [name ...]

Each case runs in a scratch copy of its folder as
``PYTHONUNBUFFERED=1 rs274 <options> </dev/null`` with stdout, stderr and the exit status
saved to ``expected/<name>.out``, ``.err``, ``.rc`` (``/`` in names becomes ``__``; the
scratch folder's path is SCRATCH in them, a printed process id PID).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))

from tests.interp.linuxcnc.cases import EXPECTED, cases


def main(names: list[str]) -> int:
    EXPECTED.mkdir(exist_ok=True)
    for case in cases():
        if names and case.name not in names:
            continue
        with tempfile.TemporaryDirectory() as scratch:
            folder = case.prepare(Path(scratch))
            if folder is None:
                print(f"{case.name}: its files are not on this machine", file=sys.stderr)
                return 1
            command = ["rs274", *case.args]
            if case.args[0] == "@python":  # a script using LinuxCNC's Python modules
                command = ["/usr/bin/python3", *case.args[1:]]
            result = subprocess.run(
                command,
                cwd=folder,
                capture_output=True,
                stdin=subprocess.DEVNULL,
                env={**os.environ, "PYTHONUNBUFFERED": "1", **case.linuxcnc_env()},
                timeout=120,
                check=False,
            )
            out = case.normalize(result.stdout.decode("latin-1"), folder)
            err = case.normalize(result.stderr.decode("latin-1"), folder)
        case.recorded(".out").write_bytes(out.encode("latin-1"))
        case.recorded(".err").write_bytes(err.encode("latin-1"))
        case.recorded(".rc").write_text(f"{result.returncode}\n")
        print(f"{case.name}: exit status {result.returncode}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
