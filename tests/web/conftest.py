"""Fixtures of the web UI tests: the UI tests' buffers and fake task, and the server's app.

``web`` starts the app (cnc/ui/web/server.py) against the fake task's buffers in
pytest-aiohttp's test server and returns its client; ``receive_until`` reads a websocket
until a wanted message arrives.
"""

from __future__ import annotations

import asyncio
import weakref
from collections.abc import Callable
from typing import Any

import aiohttp
import pytest

from cnc.ui.web.server import Access, make_app
from cnc.ui.web.settings import Settings
from tests.ui.conftest import controller, fake_task, runtime_dir  # noqa: F401 (fixtures)

WAIT_S = 20.0  # generous: only reached when something is broken


@pytest.fixture
def web(aiohttp_client: Callable[..., Any]) -> Callable[..., Any]:
    """``await web(settings=..., access=...)``: a test client of a running server."""

    async def start(settings: Settings | None = None, access: Access | None = None) -> Any:
        app = make_app(settings or Settings(cycle_time_s=0.02), None, access or Access())
        return await aiohttp_client(app)

    return start


# Messages read from a socket while waiting for another one, by socket: a status change
# may arrive before the result of the command that caused it.
_unread: weakref.WeakKeyDictionary[Any, list[dict[str, Any]]] = weakref.WeakKeyDictionary()


async def receive_until(
    socket: aiohttp.ClientWebSocketResponse, wanted: Callable[[dict[str, Any]], bool]
) -> dict[str, Any]:
    """The first message from the server, not yet taken, for which ``wanted`` is true."""
    unread = _unread.setdefault(socket, [])
    for index, message in enumerate(unread):
        if wanted(message):
            return unread.pop(index)
    try:
        async with asyncio.timeout(WAIT_S):
            while True:
                message = await socket.receive_json()
                if wanted(message):
                    return message
                unread.append(message)
    except TimeoutError:
        raise AssertionError(f"never received the wanted message; saw {unread}") from None


def is_result(number: int) -> Callable[[dict[str, Any]], bool]:
    return lambda message: message["type"] == "result" and message["id"] == number


def is_status_with(key: str, value: Any) -> Callable[[dict[str, Any]], bool]:
    return lambda message: message["type"] == "status" and message["data"].get(key) == value
