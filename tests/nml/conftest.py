"""Fixtures of the NML tests."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from nml.config import NmlConfig
from nml.shmem import ShmBuffer


@pytest.fixture
def opened(cfg: NmlConfig) -> Iterator[Callable[..., ShmBuffer]]:
    """Open connections to the test module's ``cfg`` buffers; all closed at teardown."""
    buffers: list[ShmBuffer] = []

    def open_buffer(process: str, buffer: str = "q") -> ShmBuffer:
        connection = ShmBuffer(cfg.buffers[buffer], cfg.process(process, buffer))
        buffers.append(connection)
        return connection

    yield open_buffer
    for connection in reversed(buffers):
        connection.close()
