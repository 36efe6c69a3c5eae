"""Fixtures for the launcher's tests: a halcmd session on the test's own HAL."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from hal.halcmd import HalCmd
from hal.haltcl import is_available

needs_tcl = pytest.mark.skipif(not is_available(), reason="no Tcl for Python (tkinter)")


@pytest.fixture
def session() -> Iterator[HalCmd]:
    """halcmd on this test's HAL; the realtime host (if a loadrt started one) and the HAL's
    shared memory are removed afterwards."""
    halcmd = HalCmd()
    try:
        yield halcmd
    finally:
        if halcmd.host.is_running():
            halcmd.run_words(["unload", "all"])
            halcmd.host.stop()
        halcmd.hal.close()
        halcmd.hal.destroy()
