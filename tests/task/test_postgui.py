"""[HAL]POSTGUI_HALFILE runs once the display's own pins exist (ARCH-010): with DISPLAY = web
and a [DISPLAY] MESSAGE_PINNAME dialog, a postgui file may net ``web.messages.<pin>``."""

from __future__ import annotations

import shutil
import signal
import socket
from pathlib import Path

from hal.core import Hal
from tests.task.test_machine import MACHINE, Machine


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_postgui_file_nets_the_web_displays_message_pin(procs, tmp_path: Path) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    ini = folder / "mill.ini"
    display = (
        f"DISPLAY = web --port {free_port()}\n"
        "MESSAGE_BOLDTEXT = Door open\nMESSAGE_TEXT = Close the door\n"
        "MESSAGE_TYPE = okdialog\nMESSAGE_PINNAME = door\n"
    )
    text = ini.read_text().replace("DISPLAY =\n", display)
    ini.write_text(text.replace("[HAL]\n", "[HAL]\nPOSTGUI_HALFILE = postgui.hal\n"))
    (folder / "postgui.hal").write_text("net door-open web.messages.door\n")
    launcher = procs.python("-m", "cnc", "run", "mill.ini", cwd=folder)
    machine = Machine(launcher, folder)
    try:
        machine.wait_ready()
        hal = Hal(is_creating=False)
        try:
            found = hal.find_pin("web.messages.door")
            assert found is not None
            assert hal.meta["pins"]["web.messages.door"]["sig"] == "door-open"
        finally:
            hal.close()
    finally:
        launcher.send_signal(signal.SIGTERM)
        assert launcher.wait(timeout=30) == 0, launcher.stderr.read()
