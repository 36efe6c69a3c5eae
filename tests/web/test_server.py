"""cnc ui web: status push, commands and their results, notices, access rules (GUI-*)."""

from __future__ import annotations

import asyncio
import json
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import aiohttp
import pytest

import cnc
from cnc.api import safety
from cnc.ui.web.server import HUB, STATIC, Access
from cnc.ui.web.settings import Settings
from tests.web.conftest import API_WS, PageSocket, is_result, is_status_with, page, receive_until

pytestmark = pytest.mark.asyncio


def without_serial(command: dict) -> tuple[str, dict]:
    """A command's type and fields, without those the API fills in itself (serial, tag,
    a continuous jog's lease)."""
    hidden = ("serial_number", "tag", "lease_slot", "lease_pid")
    fields = {k: v for k, v in command["fields"].items() if k not in hidden}
    return command["type"], fields


async def test_first_status_is_complete_and_changes_follow(fake_task, web) -> None:
    fake_task()
    client = await web()
    async with page(client) as socket:
        config = await receive_until(socket, lambda m: m["type"] == "config")
        assert config["data"]["axes"] == "XYZ" and config["data"]["is_control"] is True
        first = await receive_until(socket, is_status_with("is_connected", True))
        status = first["data"]
        assert status["axes"] == "XYZ"
        # Actual position (only X set by the fake task) minus the G54 offset X10.
        assert status["work"] == [2.5, 0.0, 0.0] and status["machine"] == [12.5, 0.0, 0.0]
        assert status["homed"] == [True, True, False]
        assert status["task_state"] == "ESTOP" and status["is_estop"] is True
        assert status["gcodes"].startswith("G1 G17 G40 G21") and status["tool"] == 3
        await socket.send_json({"cmd": "estop", "on": False, "id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        change = await receive_until(socket, is_status_with("task_state", "ESTOP_RESET"))
        assert change["data"]["is_estop"] is False
        assert "work" not in change["data"]  # only what changed


async def test_commanded_position_when_the_ini_asks_for_it(fake_task, web) -> None:
    fake_task()
    client = await web(Settings(cycle_time_s=0.02, is_position_actual=False))
    async with page(client) as socket:
        status = (await receive_until(socket, is_status_with("is_connected", True)))["data"]
        assert status["work"] == [2.5, -3.25, 40.0]
        assert status["machine"] == [12.5, -3.25, 40.0]


async def test_commands_reach_the_task_and_results_come_back(fake_task, web) -> None:
    task = fake_task()
    client = await web()
    async with page(client) as socket:
        await socket.send_json({"cmd": "mdi", "text": "G0 X1", "id": 7})
        history = await receive_until(socket, lambda m: m["type"] == "history")
        assert history["lines"] == ["G0 X1"]  # sent to every page, before the result
        result = await receive_until(socket, is_result(7))
        assert result["status"] == "DONE"
        await socket.send_json({"cmd": "feedrate", "percent": "75,5", "id": 8})
        assert (await receive_until(socket, is_result(8)))["status"] == "DONE"
        await socket.send_json(
            {
                "cmd": "jog",
                "action": "increment",
                "axis": "y",
                "direction": -1,
                "speed": 120,
                "distance": 0.5,
                "id": 9,
            }
        )
        assert (await receive_until(socket, is_result(9)))["status"] == "DONE"
    received = [without_serial(task.next_command()) for _ in range(5)]
    assert received == [
        ("EMC_TASK_SET_MODE", {"mode": cnc.MODE_MDI}),
        ("EMC_TASK_PLAN_EXECUTE", {"command": "G0 X1"}),
        ("EMC_TRAJ_SET_SCALE", {"scale": 0.755}),
        ("EMC_TASK_SET_MODE", {"mode": cnc.MODE_MANUAL}),
        ("EMC_JOG_INCR", {"joint_or_axis": 1, "incr": 0.5, "vel": -2.0, "jjogmode": 1}),
    ]


async def test_a_refused_command_is_an_error_result_and_a_notice_to_every_page(
    fake_task, web
) -> None:
    fake_task("--fail", "G1 X1")
    client = await web()
    async with page(client) as first, page(client) as second:
        for socket in (first, second):
            await receive_until(socket, is_status_with("is_connected", True))
        await first.send_json({"cmd": "mdi", "text": "G1 X1", "id": 1})
        result = await receive_until(first, is_result(1))
        assert result["status"] == "ERROR" and result["is_reported"] is True
        assert result["message"] == "mdi: the controller refused mdi"
        for socket in (first, second):
            notice = await receive_until(socket, lambda m: m["type"] == "notice")
            assert notice == {"type": "notice", "kind": "error", "text": "failed: G1 X1"}


def _call(method: str, **params: object) -> str:
    return json.dumps({"jsonrpc": "2.0", "method": method, "params": params, "id": 1})


@pytest.mark.parametrize(
    ("request_text", "code", "expected"),
    [
        ("not json", -32700, "parse error"),
        ('{"cmd": "mdi", "id": 1}', -32600, "invalid request"),
        (_call("frobnicate"), -32601, "method not found: 'frobnicate'"),
        (_call("feedrate", percent="1,2,3"), -32000, "feedrate: 'percent': '1,2,3' is not"),
        (_call("estop", on="yes"), -32602, "estop: 'on' must be of kind bool"),
        (_call("estop"), -32602, "estop: 'on' is required"),
        (_call("flood", on=True, colour="blue"), -32602, "flood: unknown parameter 'colour'"),
        (_call("jog", action="start", axis="Q"), -32000, "jog: unknown axis 'Q'"),
        (_call("mdi", text=""), -32000, "mdi: 'text' must be a non-empty text"),
    ],
)
async def test_a_bad_request_gets_an_error_and_the_server_goes_on(
    fake_task, web, request_text: str, code: int, expected: str
) -> None:
    task = fake_task()
    client = await web()
    async with client.ws_connect(API_WS) as socket:
        await socket.send_str(request_text)
        answer = await socket.receive_json()
        assert answer["jsonrpc"] == "2.0" and answer["error"]["code"] == code
        assert answer["error"]["message"].startswith(expected)
        await socket.send_str(_call("flood", on=True))
        assert await socket.receive_json() == {
            "jsonrpc": "2.0",
            "id": 1,
            "result": {"message": "DONE"},
        }
    assert task.next_command()["type"] == "EMC_COOLANT_FLOOD_ON"  # nothing before it


async def test_two_pages_both_receive_status(fake_task, web) -> None:
    fake_task()
    client = await web()
    async with page(client) as first, page(client) as second:
        await first.send_json({"cmd": "machine", "on": True, "id": 1})
        for socket in (first, second):
            await receive_until(socket, is_status_with("task_state", "ON"))


async def test_a_page_that_disconnects_mid_command_changes_nothing(fake_task, web) -> None:
    task = fake_task()
    client = await web()
    socket = PageSocket(await client.ws_connect(API_WS))
    await socket.send_json({"cmd": "mdi", "text": "G0 X5", "id": 1})
    await socket.close()
    async with page(client) as other:  # a marker: the next command task sees
        await asyncio.sleep(0.2)
        await other.send_json({"cmd": "mist", "on": True, "id": 2})
        await receive_until(other, is_result(2))
    kinds = [task.next_command()["type"] for _ in range(3)]
    assert kinds == ["EMC_TASK_SET_MODE", "EMC_TASK_PLAN_EXECUTE", "EMC_COOLANT_MIST_ON"]


async def test_a_continuous_jog_of_a_page_that_goes_away_is_stopped(fake_task, web) -> None:
    task = fake_task()
    client = await web()
    async with page(client) as socket:
        request = {"cmd": "jog", "action": "start", "axis": "X", "direction": 1, "speed": 60}
        await socket.send_json(request | {"id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
    # Read in a thread: the server, in this event loop, is still handling the close.
    kinds = [without_serial(await asyncio.to_thread(task.next_command)) for _ in range(2)]
    assert kinds == [  # the fake task is in manual mode already
        ("EMC_JOG_CONT", {"joint_or_axis": 0, "vel": 1.0, "jjogmode": 1}),
        ("EMC_JOG_STOP", {"joint_or_axis": 0, "jjogmode": 1}),
    ]


async def test_programs_are_listed_and_opened_from_the_program_prefix(
    fake_task, web, tmp_path: Path
) -> None:
    task = fake_task()
    (tmp_path / "part.ngc").write_text("G0 X1\nM2\n")
    (tmp_path / "notes.txt").write_text("not a program\n")
    client = await web(Settings(cycle_time_s=0.02, program_prefix=tmp_path))
    assert (await (await client.get("/api/files")).json()) == {"files": ["part.ngc"]}
    async with page(client) as socket:
        await socket.send_json({"cmd": "open", "file": "../part.ngc", "id": 1})
        assert (await receive_until(socket, is_result(1)))[
            "message"
        ] == "open: no program '../part.ngc'"
        await socket.send_json({"cmd": "open", "file": "part.ngc", "id": 2})
        assert (await receive_until(socket, is_result(2)))["status"] == "DONE"
    received = [without_serial(task.next_command()) for _ in range(3)]
    assert received == [
        ("EMC_TASK_SET_MODE", {"mode": cnc.MODE_AUTO}),
        ("EMC_TASK_PLAN_CLOSE", {}),  # program_open closes the open program first
        ("EMC_TASK_PLAN_OPEN", {"file": str(tmp_path / "part.ngc")}),
    ]


async def test_the_page_and_its_assets_are_served(web) -> None:
    """Every asset the page loads is served, and none comes from elsewhere (no CDN)."""
    client = await web()
    page = await client.get("/")
    text = await page.text()
    assert page.status == 200 and "/static/js/app.js" in text
    scripts = sorted(p.name for p in (STATIC / "js").glob("*.js"))
    assert "app.js" in scripts and "program-worker.js" in scripts
    for asset in ["style.css", *(f"js/{name}" for name in scripts)]:
        response = await client.get(f"/static/{asset}")
        assert response.status == 200, asset
        text += await response.text()
    assert "http://" not in text and "https://" not in text  # no CDN


# ------------------------------------------------------------------ access
async def test_requests_without_the_token_get_401(web) -> None:
    client = await web(access=Access("secret", "look"))
    assert (await client.get("/")).status == 401
    assert (await client.get("/?token=wrong")).status == 401
    assert (await client.get(API_WS)).status == 401
    assert (await client.get("/api/config")).status == 401
    assert (await client.get("/?token=secret")).status == 200
    headers = {"Authorization": "Bearer secret"}
    assert (await client.get("/api/config", headers=headers)).status == 200


async def test_a_read_only_token_watches_but_every_command_is_refused(fake_task, web) -> None:
    task = fake_task()
    client = await web(access=Access("secret", "look"))
    async with page(client, API_WS + "?token=look") as socket:
        config = await receive_until(socket, lambda m: m["type"] == "config")
        assert config["data"]["is_control"] is False
        await receive_until(socket, is_status_with("is_connected", True))
        await socket.send_json({"cmd": "estop", "on": False, "id": 1})
        result = await receive_until(socket, is_result(1))
        assert result == {
            "type": "result",
            "id": 1,
            "status": "ERROR",
            "message": "estop: needs the operate scope (read-only-token has not)",
            "code": -32001,
        }
    async with page(client, API_WS + "?token=secret") as socket:
        await socket.send_json({"cmd": "flood", "on": True, "id": 2})
        assert (await receive_until(socket, is_result(2)))["status"] == "DONE"
    assert task.next_command()["type"] == "EMC_COOLANT_FLOOD_ON"  # nothing before it


async def test_a_websocket_from_another_sites_page_is_refused(web) -> None:
    client = await web()
    response = await client.get(API_WS, headers={"Origin": "http://example.com"})
    assert response.status == 403


async def test_without_a_controller_the_page_is_told_and_commands_fail(web) -> None:
    client = await web()
    async with page(client) as socket:
        status = await receive_until(socket, lambda m: m["type"] == "status")
        assert status["data"]["is_connected"] is False
        await socket.send_json({"cmd": "flood", "on": True, "id": 1})
        result = await receive_until(socket, is_result(1))
        assert result["status"] == "ERROR" and "not running" in result["message"]


async def test_an_uploaded_program_is_saved_in_the_program_prefix(web, tmp_path: Path) -> None:
    folder = tmp_path / "nc"
    folder.mkdir()
    client = await web(Settings(program_prefix=folder), Access("secret", "look"))
    form = aiohttp.FormData()
    form.add_field("file", b"G0 X1\nM2\n", filename="new.ngc")
    response = await client.post("/api/upload?token=secret", data=form)
    assert response.status == 200 and await response.json() == {"file": "new.ngc"}
    assert (folder / "new.ngc").read_text() == "G0 X1\nM2\n"
    form = aiohttp.FormData()
    form.add_field("file", b"G0 X2\n", filename="../escape.ngc")
    assert (await client.post("/api/upload?token=secret", data=form)).status == 200
    assert not (tmp_path / "escape.ngc").exists()  # only a name inside the folder is used
    assert len(list(folder.iterdir())) == 2


@pytest.mark.parametrize(
    ("token", "filename", "headers", "status"),
    [
        ("look", "a.ngc", {}, 403),  # read-only
        ("secret", "a.exe", {}, 400),  # not a program
        ("secret", "a.ngc", {"Origin": "http://example.com"}, 403),  # another site's page
    ],
)
async def test_an_upload_is_refused(
    web, tmp_path: Path, token: str, filename: str, headers: dict, status: int
) -> None:
    folder = tmp_path / "nc"
    folder.mkdir()
    client = await web(Settings(program_prefix=folder), Access("secret", "look"))
    form = aiohttp.FormData()
    form.add_field("file", b"G0 X1\n", filename=filename)
    response = await client.post(f"/api/upload?token={token}", data=form, headers=headers)
    assert response.status == status
    assert list(folder.iterdir()) == []


async def test_a_tool_edit_rewrites_the_tool_table_and_has_iocontrol_reload_it(
    fake_task, web, tmp_path: Path
) -> None:
    task = fake_task()
    table = tmp_path / "tool.tbl"
    table.write_text("T1 P1 Z10 D6 ;end mill\nT2 P2 Y0.5 Z20 D3 ;drill\n")
    client = await web(Settings(cycle_time_s=0.02, tool_table=table))
    async with page(client) as socket:
        edit = {"cmd": "tool_set", "tool": 2, "z": "1,5", "diameter": "6,35", "id": 1}
        await socket.send_json(edit | {"comment": "new\ndrill"})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        # LinuxCNC's tool editors: the whole file, then EMC_TOOL_LOAD_TOOL_TABLE
        assert table.read_text() == (
            "T1   P1   D+6.000000 Z+10.000000 ;end mill\n"
            "T2   P2   D+6.350000 Y+0.500000 Z+1.500000 ;new drill\n"
        )
        assert without_serial(task.next_command()) == ("EMC_TOOL_LOAD_TOOL_TABLE", {"file": ""})
        await socket.send_json(edit | {"tool": 9, "id": 2})
        refused = await receive_until(socket, is_result(2))
        assert refused["status"] == "ERROR"
        assert refused["message"] == f"tool_set: no tool 9 in {table}"
        table.write_text("T1 P1 Z10\nT2 P2 Z1 K7\n")
        await socket.send_json(edit | {"id": 3})
        refused = await receive_until(socket, is_result(3))
        assert refused["message"].startswith(f"tool_set: {table}:2: ")
        assert table.read_text() == "T1 P1 Z10\nT2 P2 Z1 K7\n"  # left as it was
    assert (await (await client.get("/api/tools")).json()) == {"tools": []}  # no iocontrol


async def test_no_tool_edit_without_a_tool_table_file(fake_task, web) -> None:
    fake_task()
    client = await web()
    async with page(client) as socket:
        await socket.send_json({"cmd": "tool_set", "tool": 1, "z": 1, "diameter": 2, "id": 1})
        refused = await receive_until(socket, is_result(1))
    assert refused["message"] == "tool_set: the INI file names no [EMCIO]TOOL_TABLE"


async def test_a_macro_runs_its_lines_in_order_and_mdi_lines_are_kept(
    fake_task, web, tmp_path: Path
) -> None:
    task = fake_task()
    history = tmp_path / "history.txt"
    history.write_text("G0 X0\n")
    macros = [{"label": "Zero", "commands": "G0 Z25; X0 Y0"}]
    client = await web(Settings(cycle_time_s=0.02, macros=macros, mdi_history_file=history))
    async with page(client) as socket:
        config = await receive_until(socket, lambda m: m["type"] == "config")
        assert config["data"]["mdi_history"] == ["G0 X0"]
        assert config["data"]["macros"] == macros
        await socket.send_json({"cmd": "macro", "index": 0, "id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        await socket.send_json({"cmd": "mdi", "text": "G1 X2 F100", "id": 2})
        assert (await receive_until(socket, is_result(2)))["status"] == "DONE"
    lines = [task.next_command()["fields"].get("command") for _ in range(4)]
    assert lines == [None, "G0 Z25", "X0 Y0", "G1 X2 F100"]  # after the switch to MDI
    assert history.read_text() == "G0 X0\nG1 X2 F100\n"


async def test_a_filtered_program_is_opened_as_the_filters_output(
    fake_task, web, tmp_path: Path
) -> None:
    task = fake_task()
    (tmp_path / "square.py").write_text("print('G0 X1')\nprint('M2')\n")
    (tmp_path / "broken.py").write_text("raise SystemExit('no luck')\n")
    filters = {".py": sys.executable}
    settings = Settings(cycle_time_s=0.02, program_prefix=tmp_path, filters=filters)
    settings.extensions = (".ngc", ".py")
    client = await web(settings)
    async with page(client) as socket:
        await socket.send_json({"cmd": "open", "file": "square.py", "id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        await socket.send_json({"cmd": "open", "file": "broken.py", "id": 2})
        failed = await receive_until(socket, is_result(2))
        assert failed["status"] == "ERROR" and failed["message"].endswith("failed (1): no luck")
    opened = [task.next_command() for _ in range(3)][-1]["fields"]["file"]
    assert Path(opened).read_text() == "G0 X1\nM2\n"


async def test_a_stop_is_not_queued_behind_busy_workers(fake_task, web, monkeypatch) -> None:
    task = fake_task()
    client = await web()
    hub = client.app[HUB]
    monkeypatch.setattr(hub, "executor", ThreadPoolExecutor(1))
    blocker = threading.Event()
    hub.executor.submit(blocker.wait)  # every ordinary worker is busy
    try:
        async with page(client) as socket:
            await socket.send_json({"cmd": "abort", "id": 1})
            assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
    finally:
        blocker.set()
        hub.executor.shutdown()
    assert task.next_command()["type"] == "EMC_TASK_ABORT"


async def test_an_abort_is_on_the_safety_board_before_any_worker_takes_it(
    fake_task, web, monkeypatch
) -> None:
    """The hub puts the abort on the board in its event loop; the command a worker sends
    later carries that request's stamp, so task acts on it once."""
    task = fake_task()
    client = await web()
    hub = client.app[HUB]
    requested = []
    monkeypatch.setattr(safety, "request_abort", lambda: requested.append(4242) or 4242)
    monkeypatch.setattr(hub, "urgent_executor", ThreadPoolExecutor(1))
    blocker = threading.Event()
    hub.urgent_executor.submit(blocker.wait)  # even the stop workers are busy
    try:
        async with page(client) as socket:
            await socket.send_json({"cmd": "abort", "id": 1})
            for _ in range(500):
                if requested:
                    break
                await asyncio.sleep(0.01)
            assert requested == [4242]
            assert task.received() == []  # no worker has sent anything yet
            blocker.set()
            assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
    finally:
        blocker.set()
        hub.urgent_executor.shutdown()
    assert without_serial(task.next_command()) == ("EMC_TASK_ABORT", {"request": 4242})


@pytest.mark.parametrize(
    ("request_fields", "expected"),
    [
        (
            {"cmd": "touch_off", "axis": "x", "value": "1,5"},
            [("EMC_TASK_SET_MODE", {"mode": cnc.MODE_MDI}),
             ("EMC_TASK_PLAN_EXECUTE", {"command": "G10 L20 P0 X1.500000"})],
        ),
        (
            {"cmd": "feedrate", "percent": 500},  # clamped to MAX_FEED_OVERRIDE (120 %)
            [("EMC_TRAJ_SET_SCALE", {"scale": 1.2})],
        ),
        (
            {"cmd": "spindle_override", "percent": 10},  # clamped to the minimum (50 %)
            [("EMC_TRAJ_SET_SPINDLE_SCALE", {"spindle": 0, "scale": 0.5})],
        ),
        ({"cmd": "spindle", "action": "forward", "speed": "2 000"},  # within the INI's range
         [("EMC_SPINDLE_ON", {"spindle": 0, "speed": 2000.0, "factor": 0.0, "xoffset": 0.0,
                              "wait_for_spindle_at_speed": 0})]),
        ({"cmd": "home", "joint": 2}, [("EMC_JOINT_HOME", {"joint": 2})]),
        ({"cmd": "unhome"}, [("EMC_JOINT_UNHOME", {"joint": -1})]),
        ({"cmd": "block_delete", "on": True},
         [("EMC_TASK_PLAN_SET_BLOCK_DELETE", {"state": True})]),
        ({"cmd": "run", "line": 12},
         [("EMC_TASK_SET_MODE", {"mode": cnc.MODE_AUTO}), ("EMC_TASK_PLAN_RUN", {"line": 12})]),
    ],
)  # fmt: skip
async def test_page_commands_become_these_task_commands(
    fake_task, web, request_fields: dict, expected: list
) -> None:
    task = fake_task()
    client = await web()
    async with page(client) as socket:
        await socket.send_json(request_fields | {"id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
    assert [without_serial(task.next_command()) for _ in expected] == expected


async def test_commands_of_one_kind_reach_the_task_in_the_order_the_page_sent_them(
    fake_task, web
) -> None:
    """A slider dragged to 40 % and reset to 100 % at once must end at 100 %: the server's
    worker threads may not swap two commands of one kind from one page."""
    task = fake_task()
    client = await web()
    percents = [40, 100, 55, 100, 70, 100]
    async with page(client) as socket:
        for number, percent in enumerate(percents, 1):
            await socket.send_json({"cmd": "feedrate", "percent": percent, "id": number})
        for number in range(1, len(percents) + 1):
            assert (await receive_until(socket, is_result(number)))["status"] == "DONE"
    sent = [await asyncio.to_thread(task.next_command) for _ in percents]
    assert [without_serial(c) for c in sent] == [
        ("EMC_TRAJ_SET_SCALE", {"scale": percent / 100}) for percent in percents
    ]
