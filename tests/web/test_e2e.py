"""cnc ui web end to end without a browser: a real machine (``cnc run --headless``), the
server as its own process, and the test as a page on its websocket.

- A [DISPLAY] MESSAGE_* dialog (GUI-018) pops up when another HAL component drives its pin
  (LinuxCNC's userspace API), and the answer comes back on the -response pin.
- A tool edit rewrites the tool table file, iocontrol reloads it (stat.tool_table shows it)
  and the interpreter uses it (M6, G43).
"""

from __future__ import annotations

import asyncio
import shutil
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import aiohttp
import pytest

import cnc
from hal.api import HAL_BIT, HAL_OUT, component
from hal.core import Hal
from tests.conftest import Processes
from tests.hal.halrun_util import REPO
from tests.task.test_machine import Machine, launched
from tests.web.conftest import free_port, is_result, page, receive_until, start_server

SIM = REPO / "configs" / "sim"


@pytest.fixture
def hal(machine: Machine) -> Iterator[Hal]:
    """This test's attachment to the machine's HAL (never creating one)."""
    attached = Hal(is_creating=False)
    yield attached
    attached.close()


def pin(hal: Hal, name: str) -> Any:
    found = hal.find_pin(name)
    assert found is not None, f"no pin {name}"
    return hal.pin_value(found[1])


async def talk(url: str, request: dict[str, Any]) -> dict[str, Any]:
    """Send one command as a page does; its result."""
    async with aiohttp.ClientSession() as session, page(session, url + "api/v1/ws") as socket:
        await socket.send_json(request | {"id": 1})
        return await receive_until(socket, is_result(1))


@pytest.mark.slow
def test_a_hal_pin_pops_up_a_dialog_a_tool_edit_reaches_iocontrol_and_a_probe_finds_an_edge(
    machine: Machine, page_url: str, hal: Hal
) -> None:
    """One machine for all (a machine takes seconds to start)."""
    answer_the_door_dialog(page_url, hal)
    edit_a_tool(machine, page_url)
    probe_an_edge(machine, page_url, hal)


def answer_the_door_dialog(page_url: str, hal: Hal) -> None:
    driver = component("driver", hal=hal)  # as a postgui HAL file would net it
    driver.newpin("door-open", HAL_BIT, HAL_OUT)
    driver.ready()
    hal.new_signal("door-open", HAL_BIT)
    hal.link("driver.door-open", "door-open")
    hal.link("web.messages.door", "door-open")

    async def run() -> None:
        async with (
            aiohttp.ClientSession() as session,
            page(session, page_url + "api/v1/ws") as socket,
        ):
            driver["door-open"] = True
            shown = await receive_until(socket, lambda m: m["type"] == "dialog")
            assert shown == {
                "type": "dialog",
                "name": "door",
                "kind": "yesno",
                "title": "Door",
                "text": "Is the door closed?",
                "details": "The interlock switch reports it open.",
                "icon": "WARNING",
            }
            assert pin(hal, "web.messages.door-waiting") == 1
            assert pin(hal, "web.messages.door-response") == 0
            await socket.send_json({"cmd": "answer", "name": "door", "is_yes": True, "id": 2})
            assert (await receive_until(socket, is_result(2)))["status"] == "DONE"
            closed = await receive_until(socket, lambda m: m["type"] == "dialog_close")
            assert closed["name"] == "door"

    try:
        asyncio.run(run())
        assert pin(hal, "web.messages.door-response") == 1
        assert pin(hal, "web.messages.door-waiting") == 0
    finally:
        driver.exit()


def edit_a_tool(machine: Machine, page_url: str) -> None:
    edit = {"cmd": "tool_set", "tool": 2, "z": "1,5", "diameter": "6,35", "comment": "drill"}
    result = asyncio.run(talk(page_url, edit))
    assert result["status"] == "DONE", result
    assert (machine.folder / "test.tbl").read_text() == (
        "T1   P1   D+6.000000 Z+10.000000 ;6 mm end mill\nT2   P2   D+6.350000 Z+1.500000 ;drill\n"
    )
    machine.until(lambda s: [(t.id, t.zoffset, t.diameter) for t in s.tool_table[1:3]] == [
        (1, 10.0, 6.0), (2, 1.5, 6.35)
    ])  # fmt: skip
    machine.ready_to_move()
    for line in ("T2 M6", "G43 G0 X1"):  # the interpreter's copy follows iocontrol's table
        machine.command.mdi(line)
        assert machine.command.wait_complete(20) == cnc.RCS_DONE, line
    machine.until(lambda s: s.tool_offset[2] == 1.5)


def probe_an_edge(machine: Machine, page_url: str, hal: Hal) -> None:
    """The edge helper on the real machine: a part whose face is at machine X 20 (the
    probe input, motion.probe-input, is true beyond it, from a component of this test),
    a 2 mm tip: the edge is X 21 (the tip's centre touches at 20 - but the tip's side is
    1 mm further); confirmed to read X 0 in G54, the G54 X offset is 21."""
    part = component("part", hal=hal)
    part.newpin("probe", HAL_BIT, HAL_OUT)
    part.ready()
    hal.new_signal("probe", HAL_BIT)
    hal.link("part.probe", "probe")
    hal.link("motion.probe-input", "probe")
    x_feedback = hal.find_pin("joint.0.motor-pos-fb")[1]
    is_running = threading.Event()
    is_running.set()

    def touch() -> None:
        while is_running.is_set():
            part["probe"] = hal.pin_value(x_feedback) >= 20.0
            time.sleep(0.0005)

    watcher = threading.Thread(target=touch, daemon=True)
    watcher.start()
    try:
        machine.command.mdi("G49 G54 G0 X0 Y0 Z0")
        assert machine.command.wait_complete(20) == cnc.RCS_DONE

        async def run() -> None:
            url = page_url + "api/v1/ws"
            async with aiohttp.ClientSession() as session, page(session, url) as socket:
                params = {"axis": "X", "direction": 1, "search": 30, "retract": 1,
                          "fast_feed": 300, "slow_feed": 30, "tip_diameter": 2}  # fmt: skip
                await socket.send_json({"cmd": "probe", "kind": "edge", "params": params, "id": 1})
                assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
                done = await receive_until(
                    socket, lambda m: m["type"] == "probe" and m["state"] in ("done", "failed")
                )
                assert done["state"] == "done", done
                assert done["current"] == len(done["steps"]) == 4
                assert done["result"]["axes"]["X"] == pytest.approx(21.0, abs=0.02)
                confirm = {"cmd": "probe_confirm", "system": "G54", "values": {"X": 0}}
                await socket.send_json(confirm | {"id": 2})
                assert (await receive_until(socket, is_result(2)))["status"] == "DONE"

        asyncio.run(run())
        machine.until(lambda s: s.g5x_offset[0] == pytest.approx(21.0, abs=0.02))
    finally:
        is_running.clear()
        watcher.join()
        part.exit()


@pytest.mark.slow
def test_a_homed_gantry_jogs_y_as_one_axis_and_a_stop_stops_what_started(
    procs: Processes, tmp_path: Path
) -> None:
    """Once homed, an axis letter jogs the world axis (teleop, as AXIS in world mode): both
    Y joints of a gantry move together, never racking it; the page's stop names what its
    start moved, so Z stops although Z is joint 3 but axis 2."""
    folder = tmp_path / "gantry"
    shutil.copytree(SIM, folder)
    (folder / "mill.ini").write_text((SIM / "gantry.ini").read_text())
    with launched(procs, folder) as machine:
        machine.ready_to_move()
        machine.until(lambda s: all(s.homed[:4]) and s.inpos)
        server = start_server(procs, machine, port := free_port())
        try:
            url = f"http://127.0.0.1:{port}/"
            before = list(machine.stat.joint_actual_position[:4])
            jog = {"cmd": "jog", "action": "increment", "axis": "Y", "direction": 1}
            assert asyncio.run(talk(url, jog | {"speed": 600, "distance": 2}))["status"] == "DONE"
            machine.until(
                lambda s: (
                    s.joint_actual_position[1] == pytest.approx(before[1] + 2)
                    and s.joint_actual_position[2] == pytest.approx(before[2] + 2)
                    and s.inpos
                )
            )
            assert machine.stat.motion_mode == cnc.TRAJ_MODE_TELEOP
            asyncio.run(start_and_stop_a_continuous_jog(url, "Z"))
            # (the feedback follows the command a servo period later: one more step)
            machine.until(
                lambda s: (
                    s.inpos
                    and s.current_vel == 0
                    and s.joint_actual_position[3] == pytest.approx(s.joint_position[3])
                )
            )
            z = machine.stat.joint_actual_position[3]
            time.sleep(0.3)
            machine.stat.poll()
            assert machine.stat.joint_actual_position[3] == z != before[3]
        finally:
            server.terminate()
            server.communicate(timeout=10)


async def start_and_stop_a_continuous_jog(url: str, axis: str) -> None:
    async with aiohttp.ClientSession() as session, page(session, url + "api/v1/ws") as socket:
        start = {"cmd": "jog", "action": "start", "axis": axis, "direction": -1, "speed": 300}
        await socket.send_json(start | {"id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        await asyncio.sleep(0.2)
        await socket.send_json({"cmd": "jog", "action": "stop", "axis": axis, "id": 2})
        assert (await receive_until(socket, is_result(2)))["status"] == "DONE"
