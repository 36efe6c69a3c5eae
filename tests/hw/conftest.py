"""A simulated 7I96S served from a thread of the test process, on a loopback address of
its own (127.42.x.y) so tests never meet another board or each other."""

from __future__ import annotations

import itertools
import os
import threading
from collections.abc import Iterator
from dataclasses import dataclass

import pytest

from hal.hm2.firmware import SEVEN_I96S
from hal.hm2.sim import SimBoard, SimServer

_addresses = itertools.count(1)


def free_loopback_ip() -> str:
    n = next(_addresses)
    return f"127.42.{os.getpid() % 250 + 1}.{n % 250 + 1}"


class FakeClock:
    """The board's time, moved on by the test: runs are the same every time."""

    def __init__(self) -> None:
        self.ns = 1_000_000_000

    def __call__(self) -> int:
        return self.ns

    def advance(self, ns: int) -> None:
        self.ns += ns


@dataclass
class Served:
    ip: str
    board: SimBoard
    server: SimServer


def serve(clock=None) -> Served:
    board = SimBoard(SEVEN_I96S, clock) if clock else SimBoard(SEVEN_I96S)
    ip = free_loopback_ip()
    server = SimServer(board, ip, 27181)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    return Served(ip, board, server)


@pytest.fixture
def sim_board() -> Iterator[Served]:
    served = serve()
    yield served
    served.server.close()


@pytest.fixture
def fake_clock() -> FakeClock:
    return FakeClock()
