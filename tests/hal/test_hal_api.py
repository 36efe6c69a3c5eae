"""The userspace API, LinuxCNC style: ``import hal``; ``hal.component(...)``."""

from __future__ import annotations

import pytest

import hal
from hal.api import set_shared_hal, shared_hal


@pytest.fixture
def clean_hal():  # type: ignore[no-untyped-def]
    yield shared_hal()
    own = shared_hal()
    set_shared_hal(None)
    own.destroy()
    own.close()


def test_component_pins_params_and_module_functions(clean_hal) -> None:  # type: ignore[no-untyped-def]
    comp = hal.component("ui", prefix="ui.0")
    out = comp.newpin("speed", hal.HAL_FLOAT, hal.HAL_OUT)
    comp.newpin("count", hal.HAL_U32, hal.HAL_IN)
    comp.newparam("gain", hal.HAL_S32, hal.HAL_RW)
    assert hal.component_exists("ui") and not hal.component_is_ready("ui")
    comp.ready()
    assert hal.component_is_ready("ui")
    comp["speed"] = 2.5
    comp["count"] = -1
    comp["gain"] = 7
    assert (comp["speed"], comp["count"], comp["gain"]) == (2.5, 0xFFFFFFFF, 7)
    assert hal.get_value("ui.0.speed") == 2.5 and hal.get_value("ui.0.gain") == 7
    assert out.get_name() == "ui.0.speed" and out.is_pin()
    assert out.get_type() == hal.HAL_FLOAT and out.get_dir() == hal.HAL_OUT
    assert not hal.pin_has_writer("ui.0.count")
    clean_hal.new_signal("sp", hal.HAL_FLOAT)
    clean_hal.link("ui.0.speed", "sp")
    assert hal.get_value("sp") == 2.5
    comp.exit()
    assert not hal.component_exists("ui")
    with pytest.raises(hal.HalError, match="not found"):
        hal.get_value("ui.0.speed")
