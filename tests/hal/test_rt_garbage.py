"""Realtime components leave no reference cycles behind (ARCH-017).

The realtime host disables the garbage collector so that no collection pause lands in a
period; a cycle made in a period is then never freed, and the host's memory grows from
inside the servo thread (see hal/README.md). Every component's functions run here for many
periods with the collector off, inputs changing, and must leave nothing to collect.
"""

from __future__ import annotations

import gc
from pathlib import Path

import pytest

from hal.core import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_IO
from tests.hal.comp_harness import bench

# loadrt arguments a module needs
ARGS = {
    "sampler": "cfg=ff",
    "streamer": "cfg=ff",
    "stepgen": "step_type=0,1 ctrl_type=p,v",
    "mux_generic": "config=ff4,bs3,su2",
    "weighted_sum": "wsum_sizes=3",
    "pwmgen": "output_type=0,1,2",
    "modmath": "mod_dir=1",
    "logic": "personality=0x1f03",
    "bitslice": "personality=8",
    "carousel": "pockets=8,6 encoding=gray,counts",
}
# motmod needs a machine (tests/motion/test_rt_garbage.py covers the controller), hm2_eth a
# card (tests/hw/test_hm2_driver.py); threads only makes threads
ELSEWHERE = {"motmod", "threads", "hm2_eth"}
COMPONENTS = sorted(
    path.stem
    for path in (Path(__file__).resolve().parents[2] / "hal" / "components").glob("*.py")
    if not path.stem.startswith("_") and path.stem not in ELSEWHERE
)


@pytest.mark.parametrize("module", COMPONENTS)
def test_component_periods_leave_no_cycles(module: str, collector_off) -> None:
    with bench(module, ARGS.get(module, "")) as comp:
        hal = comp.hal
        inputs = [
            (info["type"], info["slot"])
            for info in hal.meta["pins"].values()
            if info["dir"] in (HAL_IN, HAL_IO) and info["type"] in (HAL_BIT, HAL_FLOAT)
        ]
        gc.collect()
        try:
            for period in range(300):
                for hal_type, slot in inputs:  # bits toggle, floats ramp: branches move
                    value = period // 7 % 2 if hal_type == HAL_BIT else period * 0.01
                    hal.write_slot(hal_type, hal.ptr[slot], value)
                comp.run()
            assert gc.collect() == 0
        finally:
            comp.host.unload_all()  # components with shared memory of their own remove it
