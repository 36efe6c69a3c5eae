"""cnc ui web, issue 18 and issue 14 item 8: the Host check against DNS rebinding, leased
continuous jogs, one notice per event, the offline controller, the open program's
analysis (listing text, toolpath, time estimate), offsets, tools and spindle limits."""

from __future__ import annotations

import asyncio
import shutil
from pathlib import Path

import pytest

import cnc
from cnc.ui.web.notices import Notices
from cnc.ui.web.preview import decode
from cnc.ui.web.server import HUB, HostCheck, make_app
from cnc.ui.web.settings import Settings
from tests.task.test_machine import MACHINE
from tests.web.conftest import API_WS, is_result, is_status_with, page, receive_until
from tests.web.test_server import without_serial


# ------------------------------------------------------------------ DNS rebinding
@pytest.mark.parametrize(
    ("host", "allowed"),
    [
        ("127.0.0.1:8750", True),
        ("localhost:8750", True),
        ("LOCALHOST", True),
        ("shop-pc:8750", True),  # configured
        ("evil.example:8750", False),  # another site's name re-bound to 127.0.0.1
        ("127.0.0.1.evil.example", False),
        ("10.0.0.5:8750", False),  # not the bound address
        ("[::1]:8750", False),
        ("", False),
        ("127.0.0.1:port", False),
    ],
)
def test_the_server_answers_only_its_own_host_names(host: str, allowed: bool) -> None:
    assert HostCheck("127.0.0.1", ("shop-pc",)).is_allowed(host) is allowed


def test_a_server_bound_to_every_address_answers_addresses_but_not_other_names() -> None:
    check = HostCheck("0.0.0.0")
    assert check.is_allowed("192.168.1.20:8750") and check.is_allowed("localhost")
    assert not check.is_allowed("evil.example:8750")


@pytest.mark.asyncio
async def test_a_forged_host_and_origin_reach_neither_page_nor_websocket_nor_files(
    fake_task, aiohttp_client, tmp_path: Path
) -> None:
    """DNS rebinding: the attacker's page has Host and Origin evil.example, both agree, so
    the same-origin check alone would let it through."""
    task = fake_task()
    (tmp_path / "part.ngc").write_text("G0 X1\nM2\n")
    settings = Settings(cycle_time_s=0.02, program_prefix=tmp_path, allowed_hosts=("cnc.shop",))
    client = await aiohttp_client(make_app(settings))
    forged = {"Host": "evil.example:8750", "Origin": "http://evil.example:8750"}
    for path in ("/", "/api/files", "/api/tools", "/api/offsets", "/static/app.js"):
        response = await client.get(path, headers=forged)
        assert response.status == 421, path
        assert "WEB_ALLOWED_HOSTS" in await response.text()
    assert (await client.get(API_WS, headers=forged)).status == 421
    assert (await client.post("/api/upload", headers=forged, data=b"x")).status == 421
    named = {"Host": "cnc.shop:8750", "Origin": "http://cnc.shop:8750"}
    assert (await (await client.get("/api/files", headers=named)).json()) == {"files": ["part.ngc"]}
    async with page(client, headers=named) as socket:
        await socket.send_json({"cmd": "flood", "on": True, "id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
    assert task.next_command()["type"] == "EMC_COOLANT_FLOOD_ON"  # the only command


# ------------------------------------------------------------------ leased jogs
@pytest.mark.asyncio
async def test_a_continuous_jog_lasts_while_the_page_holds_it(fake_task, web) -> None:
    task = fake_task()
    client = await web()
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        start = {"cmd": "jog", "action": "start", "axis": "X", "direction": 1, "speed": 60}
        await socket.send_json(start | {"id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        for _ in range(10):  # a second of holding: twice the lease and more
            await socket.send_json({"cmd": "jog", "action": "hold", "axis": "X"})
            await asyncio.sleep(0.1)
        assert [c["type"] for c in task.received()] == ["EMC_JOG_CONT"]  # still jogging
        # the page stops holding (hangs, or a key-up never came): the jog is stopped
        notice = await receive_until(socket, lambda m: m["type"] == "notice")
        assert notice["text"].startswith("jog stopped: the page stopped holding it")
        assert without_serial(await asyncio.to_thread(task.next_command)) == (
            "EMC_JOG_STOP", {"joint_or_axis": 0, "jjogmode": 1}
        )  # fmt: skip
        await socket.send_json({"cmd": "jog", "action": "hold", "axis": "X", "id": 2})
        refused = await receive_until(socket, is_result(2))
        assert refused["message"] == "jog: no continuous jog to hold"


@pytest.mark.asyncio
async def test_a_jog_needs_a_speed_above_zero(fake_task, web) -> None:
    task = fake_task()
    client = await web()
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        jog = {"cmd": "jog", "action": "increment", "axis": "X", "direction": 1, "speed": 0}
        await socket.send_json(jog | {"distance": 1, "id": 1})
        result = await receive_until(socket, is_result(1))
    assert result["message"] == "jog: the jog speed must be above 0"
    assert task.received() == []


# ------------------------------------------------------------------ notices
def test_the_messages_of_one_refused_move_are_one_notice() -> None:
    notices = Notices()
    lines = [
        "Linear move on line 0 would exceed X's positive limit",
        "Linear move on line 0 would exceed joint 0's positive limit",
        "motion refused a command",
    ]
    found = []
    for offset, line in enumerate(lines):
        found += notices.add("error", line, 10.0 + offset * 0.01)
    assert found == [] and notices.due(10.1) == []
    assert notices.due(10.3) == [
        {
            "type": "notice",
            "kind": "error",
            "text": "Linear move would exceed X's positive limit",
            "details": ["Linear move would exceed joint 0's positive limit"],
        }
    ]
    assert notices.add("error", "motion refused a command", 20.0) == []
    assert notices.due(21.0)[0]["text"] == "motion refused a command"  # alone, it stays
    assert notices.add("display", "Part done", 30.0) == [
        {"type": "notice", "kind": "display", "text": "Part done"}
    ]


@pytest.mark.asyncio
async def test_a_refused_mdi_line_is_one_notice_and_no_error_result_notice(fake_task, web) -> None:
    fake_task("--fail", "G1 X1")
    client = await web()
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        await socket.send_json({"cmd": "mdi", "text": "G1 X1", "id": 1})
        result = await receive_until(socket, is_result(1))
        assert result["is_reported"] is True  # the page shows the controller's notice only
        notice = await receive_until(socket, lambda m: m["type"] == "notice")
        assert notice == {"type": "notice", "kind": "error", "text": "failed: G1 X1"}


# ------------------------------------------------------------------ offline
@pytest.mark.asyncio
async def test_commands_are_refused_while_the_controller_is_offline_but_stops_are_tried(
    web,
) -> None:
    client = await web()
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", False))
        await socket.send_json({"cmd": "mdi", "text": "G0 X1", "id": 1})
        result = await receive_until(socket, is_result(1))
        assert result["message"] == "mdi: refused, the controller is offline (not running)"
        await socket.send_json({"cmd": "abort", "id": 2})  # tried: the API says why not
        result = await receive_until(socket, is_result(2))
        assert result["status"] == "ERROR" and "not running" in result["message"]


# ------------------------------------------------------------------ the open program
@pytest.mark.asyncio
async def test_an_opened_program_is_listed_drawn_and_estimated(
    fake_task, aiohttp_client, tmp_path: Path
) -> None:
    """The program task opens is analysed in a worker process: its text and toolpath are
    served for the page, its time estimate comes at the machine's limits (the test mill:
    50 mm/s, 1000 mm/s^2) from where the machine is (the fake task's X12.5 Y-3.25 Z40):
    96.27 mm at 3000 mm/min take 1.875 s, plus 0.05 s to start and 0.05 s to stop."""
    fake_task()
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    (folder / "part.ngc").write_text("G21 G90\nG1 X100 F3000\nM2\n")
    settings = Settings.load(str(folder / "mill.ini"))
    settings.cycle_time_s = 0.02
    client = await aiohttp_client(make_app(settings))
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        await socket.send_json({"cmd": "open", "file": "part.ngc", "id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        done = await receive_until(
            socket, lambda m: m["type"] == "program" and m["estimate"] is not None
        )
    assert done["file"] == str(folder / "part.ngc") and done["name_in_prefix"] == "part.ngc"
    assert done["is_preview_done"] and done["preview_points"] == 2 and done["end_line"] == 3
    assert done["estimate"]["total_s"] == pytest.approx(1.975, abs=0.002)
    number = done["number"]
    text = await client.get(f"/api/program/text?number={number}")
    assert await text.text() == "G21 G90\nG1 X100 F3000\nM2\n"
    data = await (await client.get(f"/api/preview/data?number={number}&from=1")).read()
    assert decode(data) == [[100.0, 0.0, 0.0, 1, 2]]
    stale = await client.get(f"/api/preview/data?number={number + 1}&from=0")
    assert stale.status == 409
    analysis = client.app[HUB].jobs.current
    assert analysis.time_at(2) == pytest.approx(0.0, abs=0.002)  # the first move starts
    assert analysis.time_at(3) == pytest.approx(0.0, abs=0.002)  # M2: no motion of its own


@pytest.mark.asyncio
async def test_an_editor_check_reports_every_error(fake_task, web) -> None:
    fake_task()
    client = await web()
    async with page(client) as socket:
        text = "G21\nG0 X1\nG999\nG1 X2 F100\nM2\n"
        await socket.send_json({"cmd": "check_program", "text": text, "id": 1})
        result = await receive_until(socket, is_result(1))
    assert result["errors"] == [{"line": 3, "message": "G-code out of range"}]


# ------------------------------------------------------------------ offsets, spindle, tools
@pytest.mark.parametrize(
    ("request_fields", "expected"),
    [
        ({"cmd": "select_system", "system": "G59.1"}, "G59.1"),
        ({"cmd": "offset_set", "system": "G55", "axis": "y", "value": -2.5},
         "G10 L2 P2 Y-2.500000"),
        ({"cmd": "offset_set", "system": "G54", "rotation": 30}, "G10 L2 P1 R30.000000"),
        ({"cmd": "offset_clear", "system": "G56"}, "G10 L2 P3 X0 Y0 Z0 R0"),
        ({"cmd": "offset_clear", "system": "G92"}, "G92.1"),
        ({"cmd": "touch_off", "axis": "z", "value": 1, "system": "G58"}, "G10 L20 P5 Z1.000000"),
    ],
)  # fmt: skip
@pytest.mark.asyncio
async def test_work_offset_commands_become_these_mdi_lines(
    fake_task, web, request_fields: dict, expected: str
) -> None:
    task = fake_task()
    client = await web()
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        await socket.send_json(request_fields | {"id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
    received = [without_serial(task.next_command()) for _ in range(2)]
    assert received == [
        ("EMC_TASK_SET_MODE", {"mode": cnc.MODE_MDI}),
        ("EMC_TASK_PLAN_EXECUTE", {"command": expected}),
    ]


@pytest.mark.asyncio
async def test_the_offsets_table_reads_the_parameter_file_and_the_status(
    fake_task, web, tmp_path: Path
) -> None:
    fake_task()
    parameters = tmp_path / "m.var"
    parameters.write_text("5211\t1.5\n5221\t99\n5242\t-4\n5250\t15\n5381\t7\nbad line\n")
    client = await web(Settings(cycle_time_s=0.02, parameter_file=parameters))
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
    table = await (await client.get("/api/offsets")).json()
    assert table["active"] == "G54" and table["axes"] == "XYZ"
    systems = {system["name"]: system for system in table["systems"]}
    assert systems["G54"]["values"] == [10.0, 0.0, 0.0]  # the status: never late
    assert systems["G55"] == {"name": "G55", "values": [0.0, -4.0, 0.0], "rotation": 15.0}
    assert systems["G59.3"]["values"] == [7.0, 0.0, 0.0]
    assert table["g92"] == [0.0, 0.0, 0.0]


@pytest.mark.asyncio
async def test_a_spindle_speed_beyond_the_ini_is_refused_and_faster_stays_within(
    fake_task, web
) -> None:
    task = fake_task()
    settings = Settings(cycle_time_s=0.02)
    settings.spindle = {"increment": 600.0, "default": 500.0, "min": 0.0, "max": 1500.0,
                        "max_reverse": 800.0}  # fmt: skip
    settings.spindle_limit_keys = {"max": "[SPINDLE_0]MAX_FORWARD_VELOCITY",
                                   "max_reverse": "[SPINDLE_0]MAX_REVERSE_VELOCITY"}  # fmt: skip
    client = await web(settings)
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        await socket.send_json({"cmd": "spindle", "action": "forward", "speed": 12000, "id": 1})
        refused = await receive_until(socket, is_result(1))
        assert refused["message"] == (
            "spindle: 12000 rpm is above the maximum, 1500 rpm ([SPINDLE_0]MAX_FORWARD_VELOCITY)"
        )
        await socket.send_json({"cmd": "spindle", "action": "reverse", "speed": 900, "id": 2})
        assert (
            "above the maximum, 800 rpm" in (await receive_until(socket, is_result(2)))["message"]
        )
        # the fake machine turns forward at 1000 rpm: +600 would be 1600, so 1500
        await socket.send_json({"cmd": "spindle", "action": "faster", "id": 3})
        assert (await receive_until(socket, is_result(3)))["status"] == "DONE"
    kind, fields = without_serial(task.next_command())  # (in manual mode already)
    assert (kind, fields["speed"]) == ("EMC_SPINDLE_ON", 1500.0)


@pytest.mark.asyncio
async def test_tools_are_added_and_deleted_in_the_tool_table_file(
    fake_task, web, tmp_path: Path
) -> None:
    task = fake_task()
    table = tmp_path / "tool.tbl"
    table.write_text("T1 P1 Z10 D6 ;end mill\nT2 P2 Z20 D3 ;drill\n")
    client = await web(Settings(cycle_time_s=0.02, tool_table=table))
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        add = {"cmd": "tool_add", "tool": 7, "z": "12,5", "diameter": 4, "comment": "chamfer"}
        await socket.send_json(add | {"id": 1})
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        await socket.send_json(add | {"id": 2})
        assert (await receive_until(socket, is_result(2)))["message"] == (
            f"tool_add: tool 7 is in {table} already"
        )
        await socket.send_json({"cmd": "tool_delete", "tool": 1, "id": 3})
        assert (await receive_until(socket, is_result(3)))["status"] == "DONE"
        await socket.send_json({"cmd": "tool_delete", "tool": 3, "id": 4})  # in the spindle
        assert (await receive_until(socket, is_result(4)))["message"] == (
            "tool_delete: tool 3 is in the spindle"
        )
    assert table.read_text() == (
        "T2   P2   D+3.000000 Z+20.000000 ;drill\nT7   P7   D+4.000000 Z+12.500000 ;chamfer\n"
    )
    kinds = [command["type"] for command in task.received()]
    assert kinds == ["EMC_TOOL_LOAD_TOOL_TABLE", "EMC_TOOL_LOAD_TOOL_TABLE"]


@pytest.mark.asyncio
async def test_the_editor_reads_and_saves_programs_in_the_program_prefix(
    fake_task, web, tmp_path: Path
) -> None:
    fake_task()
    (tmp_path / "part.ngc").write_text("G0 X1\nM2\n")
    client = await web(Settings(cycle_time_s=0.02, program_prefix=tmp_path))
    found = await (await client.get("/api/editor?file=part.ngc")).json()
    assert found == {"file": "part.ngc", "text": "G0 X1\nM2\n"}
    assert (await client.get("/api/editor?file=../x.ngc")).status == 404
    async with page(client) as socket:
        await receive_until(socket, is_status_with("is_connected", True))
        save = {"cmd": "save_program", "file": "new.ngc", "text": "G0 X2\nM2", "id": 1}
        await socket.send_json(save)
        assert (await receive_until(socket, is_result(1)))["status"] == "DONE"
        await socket.send_json(save | {"file": "../escape.ngc", "id": 2})
        assert "not a program name" in (await receive_until(socket, is_result(2)))["message"]
    assert (tmp_path / "new.ngc").read_text() == "G0 X2\nM2\n"
