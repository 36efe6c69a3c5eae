"""``cnc rsh`` start-up: the port listens before the shell attaches to the machine."""

from __future__ import annotations

import socket
import threading

from cnc.ui import rsh


def test_a_client_connecting_while_the_shell_starts_is_served(monkeypatch) -> None:
    """A script that starts right after the machine (LinuxCNC's tests pipe into ``nc``)
    connects before the shell has attached to the machine: it waits, it is not refused."""
    attach = threading.Event()
    real_shell = rsh.RemoteShell

    class SlowShell(real_shell):  # type: ignore[misc, valid-type]
        def __init__(self, ini, options) -> None:
            attach.wait(10)
            self.stat = self.command = self.errors = None
            self.ini = ini
            self.connect_password, self.enable_password = options.connectpw, "x"
            self.server_name = options.name
            self.enabled = None
            self.lock = threading.Lock()
            self.on_shutdown = lambda: None

    servers = []

    class RecordedServer(rsh._Server):
        def __init__(self, *args) -> None:
            super().__init__(*args)
            servers.append(self)

    monkeypatch.setattr(rsh, "RemoteShell", SlowShell)
    monkeypatch.setattr(rsh, "_Server", RecordedServer)
    monkeypatch.setattr("signal.signal", lambda *args: None)  # (main runs in a thread here)
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server = threading.Thread(target=rsh.main, args=(["--port", str(port)],), daemon=True)
    server.start()
    client = None
    for _ in range(500):
        try:
            client = socket.create_connection(("127.0.0.1", port), timeout=10)
            break
        except ConnectionRefusedError:
            threading.Event().wait(0.01)
    assert client is not None, "the port never listened"
    with client:
        client.sendall(b"hello EMC tester 1.0\r\nquit\r\n")
        attach.set()  # only now does the shell attach
        reply = b""
        while chunk := client.recv(1024):
            reply += chunk
    servers[0].shutdown()
    server.join(10)
    assert b"HELLO ACK EMCNETSVR 1.1" in reply
