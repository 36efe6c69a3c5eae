"""sim_axis_hardware: simulated home and limit switches for axes X, X2, Y, Y2, Z, A, U, V
(the panelui and stepconf sims). For each axis L:

- ``Lhomesw-out`` is true within +-``Lhomesw-hyst``/2 of ``Lhomesw-pos``;
- ``Lmaxsw-out`` is true strictly between ``Lmaxsw-lower`` + ``limit-offset`` and
  ``Lmaxsw-upper``, ``Lminsw-out`` strictly between ``Lminsw-lower`` and ``Lminsw-upper``
  - ``limit-offset``; ``Lbothsw-out`` is either, except while any axis is homing;
- ``L{max,min,both}sw-homesw-out`` add the home switch (not for A, as in LinuxCNC);
- ``homesw-all`` (any home switch while homing), ``limitsw-all``, ``limitsw-homesw-all``.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, funct, pin

AXES = ("X", "X2", "Y", "Y2", "Z", "A", "U", "V")
# (LinuxCNC's update leaves A's combined outputs alone)
COMBINED_AXES = tuple(axis for axis in AXES if axis != "A")


def _is_near(target: float, position: float, hysteresis: float) -> bool:
    distance, half = position - target, 0.5 * hysteresis
    return not (distance < -half or distance > half)


def _is_between(position: float, upper: float, lower: float) -> bool:
    return not (position >= upper or position <= lower)


# per axis, the attribute names the update reads and writes (made once)
_NAMES = [
    (
        axis in COMBINED_AXES,
        *(
            f"{axis}{word}"
            for word in (
                "current_pos", "homesw_pos", "homesw_hyst", "maxsw_upper", "maxsw_lower",
                "minsw_upper", "minsw_lower", "homesw_out", "maxsw_out", "minsw_out",
                "bothsw_out", "maxsw_homesw_out", "minsw_homesw_out", "bothsw_homesw_out",
            )
        ),
    )
    for axis in AXES
]  # fmt: skip
_HOMING = [f"{axis}homing" for axis in AXES]


def _update(self: Any, period: int) -> None:
    offset = self.limit_offset
    is_homing = any(getattr(self, name) for name in _HOMING)
    any_home = any_limit = False
    for (
        is_combined, position, home_pos, hyst, max_upper, max_lower, min_upper, min_lower,
        home_out, max_out, min_out, both_out, max_home_out, min_home_out, both_home_out,
    ) in _NAMES:  # fmt: skip
        where = getattr(self, position)
        home = _is_near(getattr(self, home_pos), where, getattr(self, hyst))
        high = _is_between(where, getattr(self, max_upper), getattr(self, max_lower) + offset)
        low = _is_between(where, getattr(self, min_upper) - offset, getattr(self, min_lower))
        both = (high or low) and not is_homing
        setattr(self, home_out, home)
        setattr(self, max_out, high)
        setattr(self, min_out, low)
        setattr(self, both_out, both)
        any_home = any_home or home
        any_limit = any_limit or both
        if is_combined:
            setattr(self, max_home_out, high or home)
            setattr(self, min_home_out, low or home)
            setattr(self, both_home_out, both or home)
    self.homesw_all = any_home and is_homing
    self.limitsw_all = any_limit
    self.limitsw_homesw_all = (any_home and is_homing) or any_limit


def _declarations() -> dict[str, Any]:
    members: dict[str, Any] = {}

    def declare(attr: str, spec: str, default: float = 0.0) -> None:
        members[attr] = pin(spec, attr.replace("_", "-"), default=default)

    for axis in AXES:
        declare(f"{axis}current_pos", "float in")
        declare(f"{axis}homesw_pos", "float in", 1.0)
        for word in ("maxsw_upper", "maxsw_lower", "minsw_upper", "minsw_lower"):
            declare(f"{axis}{word}", "float in")
        declare(f"{axis}homesw_hyst", "float in", 0.025)
        declare(f"{axis}homing", "bit in")
        for word in ("homesw_out", "maxsw_out", "minsw_out", "bothsw_out"):
            declare(f"{axis}{word}", "bit out")
        for word in ("maxsw_homesw_out", "minsw_homesw_out", "bothsw_homesw_out"):
            declare(f"{axis}{word}", "bit out")
    for word in ("homesw_all", "limitsw_all", "limitsw_homesw_all"):
        declare(word, "bit out")
    declare("limit_offset", "float in", 0.01)
    members["update"] = funct("update")(_update)
    return members


SimAxisHardware = type("SimAxisHardware", (RtComponent,), _declarations())
COMPONENT = SimAxisHardware
