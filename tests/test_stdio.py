"""cnc/stdio.py: each printed line is written whole, also under PYTHONUNBUFFERED."""

from __future__ import annotations

import os
import socket
import subprocess
import sys

import pytest

CHILD = """
import sys
from cnc.stdio import keep_lines_whole
if sys.argv[1] == "kept":
    keep_lines_whole()
print("xhc-hb04: waiting for XHC-HB04 device")
sys.stdin.read()  # (stays alive: the line must come out before the process ends)
"""


@pytest.mark.parametrize(
    ("how", "writes"),
    [
        ("kept", [b"xhc-hb04: waiting for XHC-HB04 device\n"]),
        ("left", [b"xhc-hb04: waiting for XHC-HB04 device", b"\n"]),  # as Python does
    ],
)
def test_a_printed_line_is_one_write_under_pythonunbuffered(how: str, writes: list[bytes]) -> None:
    """stdout is a packet socket, so each write the child makes arrives as one packet: the
    line and its newline in one write, where another process's line cannot come between."""
    ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, how],
        stdin=subprocess.PIPE,
        stdout=theirs,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    theirs.close()
    try:
        ours.settimeout(20)
        assert [ours.recv(4096) for _ in writes] == writes
    finally:
        child.communicate(b"", timeout=20)
        ours.close()
