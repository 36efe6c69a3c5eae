"""Drive one realtime component in-process: make an instance, set inputs, run periods."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from hal.api import RtComponent, set_shared_hal
from hal.core import Hal
from hal.rtapi_app import Host

PERIOD = 1_000_000


class Bench:
    """Instances of one module plus its functions, run by hand instead of by a thread."""

    def __init__(self, hal: Hal, module: str, args: str = "") -> None:
        self.host = Host(hal, is_rt=False)
        self.host.loadrt(module, args.split())
        self.hal = hal
        self.instances: list[Any] = self.host.modules[module.split("/")[-1]].instances

    @property
    def inst(self) -> RtComponent:
        return self.instances[0]

    def run(self, periods: int = 1, period: int = PERIOD, functs: list[str] | None = None) -> None:
        names = functs or list(self.host.functs)
        for _ in range(periods):
            for name in names:
                self.host.functs[name].call(period)

    def value(self, name: str) -> Any:
        found = self.hal.find_pin(name)
        if found:
            return self.hal.pin_value(found[1])
        param = self.hal.find_param(name)
        assert param is not None, name
        return self.hal.read_slot(param[1]["type"], param[1]["slot"])


@contextmanager
def bench(module: str, args: str = "") -> Iterator[Bench]:
    hal = Hal()
    try:
        yield Bench(hal, module, args)
    finally:
        set_shared_hal(None)
        hal.destroy()
        hal.close()
