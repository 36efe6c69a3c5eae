"""A machine whose INI names a LinuxCNC NML file ([EMC]NML_FILE = tcp.nml, as LinuxCNC's
tests/linuxcncrsh-tcp): it starts, runs MDI, reports motion's errors, and ``cnc rsh``
(linuxcncrsh) serves a client on it."""

from __future__ import annotations

import socket
import time

import cnc
from tests.nml.test_linuxcnc_nml_files import LINUXCNC_TCP_NML


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def connect(port: int, timeout: float = 20) -> socket.socket:
    deadline = time.monotonic() + timeout
    while True:
        try:
            return socket.create_connection(("127.0.0.1", port), timeout=timeout)
        except ConnectionRefusedError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)


def test_a_machine_on_a_linuxcnc_nml_file_runs_and_serves_linuxcncrsh(start_machine, procs) -> None:
    machine = start_machine(files={"tcp.nml": LINUXCNC_TCP_NML}, EMC=["NML_FILE = tcp.nml"])
    c = machine.command
    machine.messages(0.1)
    c.mdi("M64 P9")  # motion has 4 outputs: motion refuses, on its own emcError line
    assert c.wait_complete() == cnc.RCS_ERROR
    texts = " ".join(text for _, text in machine.messages())
    assert "digital output 9 does not exist" in texts

    port = free_port()
    ini = str(machine.folder / "mill.ini")
    procs.python("-m", "cnc", "rsh", "--port", str(port), "--", "-ini", ini)
    with connect(port) as client:
        client.sendall(
            b"hello EMC tester 1.0\r\nset enable EMCTOO\r\nset set_wait done\r\n"
            b"set mode mdi\r\nset mdi g0 x1 y2\r\nget abs_cmd_pos x\r\nquit\r\n"
        )
        reply = b""
        while chunk := client.recv(4096):
            reply += chunk
    lines = reply.decode().split("\r\n")
    assert "HELLO ACK EMCNETSVR 1.1" in lines
    assert "ABS_CMD_POS 0 1.000000" in lines, lines  # (axis 0: X)
    machine.stat.poll()
    assert machine.stat.position[:2] == (1.0, 2.0)
