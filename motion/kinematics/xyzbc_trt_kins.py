"""xyzbc-trt-kins: 5-axis table-rotary-tilting kinematics, tilting table B carrying rotary
table C (motion/kinematics/_trt.py), with tool-centre-point control.

``loadrt xyzbc-trt-kins [coordinates=xyzbc] [sparm=identityfirst]``; pins
``xyzbc-trt-kins.x-rot-point``/``y-``/``z-rot-point``, ``x-offset``, ``z-offset`` and
``tool-offset``. Switchable (``motion.switchkins-type``): type 0 these kinematics, 1
identity (the other way round with ``sparm=identityfirst``), 2 the user type.
"""

from __future__ import annotations

from typing import Any

from motion.kinematics import HalContext, SwitchKins, realtime_module
from motion.kinematics._trt import XyzbcTrt, create_trt


def create(
    coordinates: str = "xyzbc", sparm: str = "", hal: HalContext | None = None
) -> SwitchKins:
    return create_trt("xyzbc-trt-kins", XyzbcTrt, coordinates, sparm, hal)


rtapi_app_main: Any = realtime_module(create)
