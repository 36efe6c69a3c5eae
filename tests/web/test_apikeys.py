"""Named API keys (cnc/apikeys.py, ``cnc api-key``) and the server's access with them:
the keys file keeps hashes only, a revoked key stops working at once, a wrong key is
refused, a read key watches, HTTP POST one-shot calls, another site's page refused."""

from __future__ import annotations

import json
import stat
from pathlib import Path

import pytest

from cnc.apikeys import ApiKeyError, Identity, KeyStore, keys_file_for, main
from cnc.ui.web.server import Access
from cnc.ui.web.settings import Settings
from tests.web.conftest import API_WS, is_result, page, receive_until


def test_a_key_is_shown_once_and_kept_only_as_a_hash(tmp_path: Path) -> None:
    store = KeyStore(keys_file_for(tmp_path / "mill.ini"))
    key = store.create("dashboard", ["read"])
    operator = store.create("cell-3", ["operate", "read"])
    text = store.path.read_text()
    assert store.path == tmp_path / "api_keys.json"
    secret = key.split("_", 2)[2]  # (the secret itself may hold "_": urlsafe base64)
    assert key not in text and secret not in text  # the secret is nowhere
    assert stat.S_IMODE(store.path.stat().st_mode) == 0o600
    records = json.loads(text)["keys"]
    assert [(r["name"], r["scopes"]) for r in records] == [
        ("dashboard", ["read"]), ("cell-3", ["read", "operate"])
    ]  # fmt: skip
    fresh = KeyStore(store.path)  # another process: the file alone
    assert fresh.identify(key) == Identity("dashboard", frozenset({"read"}))
    assert fresh.identify(operator) == Identity("cell-3", frozenset({"read", "operate"}))
    assert fresh.identify(key[:-1] + ("A" if key[-1] != "A" else "B")) is None
    assert fresh.identify("cnc_00000000_" + "x" * 43) is None
    assert fresh.identify("secret") is None
    store.revoke("dashboard")
    assert fresh.identify(key) is None  # re-read: the file changed
    assert fresh.identify(operator) is not None


@pytest.mark.parametrize(
    ("name", "scopes", "reason"),
    [
        ("a b", ["read"], "a key's name is letters"),
        ("ok", ["admin"], "unknown scope 'admin'"),
        ("ok", [], "give at least one scope"),
        ("taken", ["read"], "a key named 'taken' exists already"),
    ],
)
def test_a_bad_name_or_scope_is_refused(tmp_path: Path, name, scopes, reason) -> None:
    store = KeyStore(tmp_path / "api_keys.json")
    store.create("taken", ["read"])
    with pytest.raises(ApiKeyError, match=reason):
        store.create(name, scopes)


def test_a_damaged_keys_file_is_named_and_admits_nobody(tmp_path: Path) -> None:
    store = KeyStore(tmp_path / "api_keys.json")
    key = store.create("a", ["read"])
    store.path.write_text('{"version": 1, "keys": [{"name": "a"}]}\n')
    with pytest.raises(ApiKeyError, match=r"api_keys.json: key 1: needs name, scopes"):
        store.records()
    assert store.identify(key) is None


def test_the_command_line_creates_lists_and_revokes(tmp_path: Path, capsys) -> None:
    ini = str(tmp_path / "mill.ini")
    assert main(["create", "mes", "--scope", "read", "--scope", "configure", "--ini", ini]) == 0
    key = capsys.readouterr().out.strip()
    assert KeyStore(tmp_path / "api_keys.json").identify(key).name == "mes"  # type: ignore[union-attr]
    assert main(["list", "--ini", ini]) == 0
    assert capsys.readouterr().out.split()[:2] == ["mes", "read,configure"]
    assert main(["revoke", "mes", "--ini", ini]) == 0
    assert main(["revoke", "mes", "--ini", ini]) == 1
    assert "no key named 'mes'" in capsys.readouterr().err


# ------------------------------------------------------------------ the server with keys
@pytest.fixture
def keys(tmp_path: Path) -> tuple[KeyStore, dict[str, str]]:
    store = KeyStore(tmp_path / "api_keys.json")
    made = {scope: store.create(scope, [scope]) for scope in ("read", "operate", "configure")}
    return store, made


def rpc_call(method: str, **params: object) -> dict:
    return {"jsonrpc": "2.0", "id": 1, "method": method, "params": params}


@pytest.mark.asyncio
async def test_keys_decide_what_each_client_may_do(fake_task, web, keys) -> None:
    """A server on another address (is_open False): keys only; each key its scopes."""
    task = fake_task()
    store, made = keys
    client = await web(access=Access(keys=store, is_open=False))
    assert (await client.get("/")).status == 401
    assert (await client.get(f"/?token={made['read']}x")).status == 401
    bearer = {"Authorization": f"Bearer {made['read']}"}
    assert (await client.get("/api/config", headers=bearer)).status == 200
    async with page(client, f"{API_WS}?token={made['read']}") as socket:
        await receive_until(socket, lambda m: m["type"] == "status")  # it may watch
        await socket.send_json({"cmd": "flood", "on": True, "id": 1})
        refused = await receive_until(socket, is_result(1))
        assert refused["code"] == -32001
        assert refused["message"] == "flood: needs the operate scope (read has not)"
    # HTTP POST one-shot: the operate key commands, the configure key does not
    headers = {"Authorization": f"Bearer {made['operate']}"}
    answer = await client.post("/api/v1/rpc", json=rpc_call("mist", on=True), headers=headers)
    assert answer.status == 200
    assert await answer.json() == {"jsonrpc": "2.0", "id": 1, "result": {"message": "DONE"}}
    assert task.next_command()["type"] == "EMC_COOLANT_MIST_ON"
    headers = {"Authorization": f"Bearer {made['configure']}"}
    answer = await client.post("/api/v1/rpc", json=rpc_call("mist", on=False), headers=headers)
    assert (await answer.json())["error"]["code"] == -32001
    answer = await client.post("/api/v1/rpc", json=rpc_call("api.identity"), headers=headers)
    assert (await answer.json())["result"] == {"name": "configure", "scopes": ["configure"]}
    store.revoke("operate")
    headers = {"Authorization": f"Bearer {made['operate']}"}
    answer = await client.post("/api/v1/rpc", json=rpc_call("mist", on=True), headers=headers)
    assert answer.status == 401


@pytest.mark.asyncio
async def test_loopback_without_a_key_may_do_everything_but_a_wrong_key_is_refused(
    fake_task, web, keys
) -> None:
    fake_task()
    store, _ = keys
    client = await web(access=Access(keys=store, is_open=True))
    answer = await client.post("/api/v1/rpc", json=rpc_call("api.identity"))
    assert (await answer.json())["result"] == {
        "name": "loopback", "scopes": ["configure", "operate", "read"]
    }  # fmt: skip
    wrong = {"Authorization": "Bearer cnc_00000000_" + "x" * 43}
    assert (
        await client.post("/api/v1/rpc", json=rpc_call("api.version"), headers=wrong)
    ).status == 401


@pytest.mark.asyncio
@pytest.mark.parametrize(
    ("headers", "body", "status"),
    [
        ({"Origin": "http://evil.example"}, json.dumps(rpc_call("abort")), 403),  # CSRF
        ({"Content-Type": "text/plain"}, json.dumps(rpc_call("abort")), 415),  # a form
        ({}, json.dumps([{"jsonrpc": "2.0", "method": "api.version"}]), 204),  # no answer
    ],
)  # fmt: skip
async def test_http_calls_from_another_sites_page_are_refused(
    web, headers: dict, body: str, status: int
) -> None:
    client = await web(Settings(cycle_time_s=0.02))
    headers = {"Content-Type": "application/json"} | headers
    assert (await client.post("/api/v1/rpc", data=body, headers=headers)).status == status
