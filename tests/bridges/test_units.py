"""The bridges' parts without a machine: mqtt-publisher's command line, the OPC UA values
derived from the machine's, the MQTT command checks, the launcher's restarts."""

from __future__ import annotations

import asyncio
import shutil
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from cnc.bridges import mqtt, supervisor
from cnc.bridges.mqtt_publisher import parse_arguments
from cnc.bridges.opcua import item_state


def test_mqtt_publisher_takes_linuxcnc_s_command_line() -> None:
    opts, keys = parse_arguments(
        ["", "--mqtt-broker=b.local", "--mqtt-user=u", "keys=a,b", "other", "keys=c"]
    )
    assert (opts.mqtt_broker, opts.mqtt_port, opts.mqtt_user) == ("b.local", 1883, "u")
    assert opts.mqtt_prefix == "devices/linuxcnc/machine"
    assert not opts.dryrun
    assert keys == ["a", "b", "c"]  # an empty word ([MQTT]DRYRUN =) is no argument
    with pytest.raises(SystemExit) as exited:
        parse_arguments(["--dryrun"])  # no keys= at all: the usage, status 1
    assert exited.value.code == 1


def test_opcua_item_state_follows_opc_40001() -> None:
    assert item_state("OFFLINE", None) == "NotAvailable"
    assert item_state("ESTOP", "IDLE") == "OutOfService"
    assert item_state("ON", "RUNNING") == "Executing"
    assert item_state("ON", "PAUSED") == "NotExecuting"
    assert item_state("OFF", "IDLE") == "NotExecuting"


def test_mqtt_commands_check_their_fields() -> None:
    calls = []
    command = SimpleNamespace(
        mode=lambda m: calls.append(("mode", m)), feedrate=lambda v: calls.append(("feed", v))
    )
    mqtt.COMMANDS["mode"](command, {"mode": "mdi"})
    mqtt.COMMANDS["feed_override"](command, {"value": 0.5})
    assert calls == [("mode", 3), ("feed", 0.5)]
    with pytest.raises(mqtt.CommandError, match="'value' must be a number"):
        mqtt.COMMANDS["feed_override"](command, {"value": True})
    with pytest.raises(mqtt.CommandError, match="'mode' must be one of"):
        mqtt.COMMANDS["mode"](command, {})


def test_a_dead_bridge_is_started_again_later(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    starts = tmp_path / "starts"
    program = [sys.executable, "-c", f"open({str(starts)!r}, 'a').write('x')"]
    monkeypatch.setattr(supervisor, "command_line", lambda section, ini: program)
    monkeypatch.setattr(supervisor, "RESTART_DELAYS_S", (0.0,))
    config = SimpleNamespace(value=lambda section, key: section == "MQTT")
    said: list[str] = []
    bridges = supervisor.BridgeSupervisor(config, "m.ini", tmp_path, said.append)
    bridges.start()
    deadline = time.monotonic() + 60
    while not starts.exists() or len(starts.read_text()) < 3:
        assert time.monotonic() < deadline, said
        bridges.check()
        time.sleep(0.01)
    bridges.stop()
    assert said[0] == "starting the mqtt bridge"
    assert any("ended with status 0; the machine goes on" in line for line in said)


def test_opcua_only_a_client_s_write_sets_an_override(tmp_path: Path) -> None:
    """The bridge writes the machine's override into its node each time it changes; that
    write must not be sent back to the machine (it undid a client's new value when the
    poll ran before task had published it)."""
    from asyncua import ua
    from asyncua.common.callback import ServerItemCallback

    from cnc.bridges.opcua import OpcuaBridge
    from cnc.inischema import load_config
    from tests.bridges.conftest import MACHINE

    shutil.copytree(MACHINE, tmp_path / "machine")
    ini = tmp_path / "machine" / "mill.ini"
    ini.write_text(ini.read_text() + "\n[OPCUA]\nENABLE = 1\nUSERNAME = u\nPASSWORD = p\n")
    bridge = OpcuaBridge(str(ini), load_config(str(ini)))
    sent: list[tuple[str, float]] = []
    bridge._set_override = lambda key, scale: sent.append((key, scale))

    async def scenario() -> None:
        await bridge.setup()
        await bridge.update({"feed/override": 1.0})  # the machine's value, as a poll has it
        assert sent == []
        node, _kind = bridge.nodes["feed/override"]
        write = ua.WriteValue(
            NodeId=node.nodeid,
            AttributeId=ua.AttributeIds.Value,
            Value=ua.DataValue(ua.Variant(50.0, ua.VariantType.Double)),
        )
        params = ua.WriteParameters(NodesToWrite=[write])
        good = [ua.StatusCode(ua.StatusCodes.Good)]
        await bridge._on_write(ServerItemCallback(params, good, None, is_external=True), None)
        assert sent == [("feed/override", 0.5)]

    try:
        asyncio.run(scenario())
    finally:
        bridge.view.close()
