"""Coordinated-mode trajectory planner, a replaceable module (ARCH-007/008).

``load_planner(name)`` returns the planner class of module ``name`` (default ``planner``,
this package's ``motion.tp.planner``; or a dotted path to a user module). The module must
define ``Planner``, a class providing every public function of the default planner; an
incomplete one is refused with an error listing what is missing.
"""

from __future__ import annotations

from motion.modules import import_module, require
from motion.tp.planner import Planner, ProbeType, TermCond, TrajectoryPlanner

# every public function and status property of the default planner: a replacement
# must provide them all (plain attributes set in __init__, such as pos, are not checked)
REQUIRED_FUNCTIONS = tuple(
    name
    for name, value in vars(TrajectoryPlanner).items()
    if not name.startswith("_") and (callable(value) or isinstance(value, property))
)


def load_planner(name: str = "planner") -> type:
    """The ``Planner`` class of trajectory-planner module ``name`` (``[TRAJ]TPMOD``-like)."""
    module = import_module(name, __name__, "trajectory planner")
    require(module, ("Planner",), f"trajectory planner module {name!r}")
    require(module.Planner, REQUIRED_FUNCTIONS, f"trajectory planner module {name!r}")
    return module.Planner


__all__ = [
    "REQUIRED_FUNCTIONS",
    "Planner",
    "ProbeType",
    "TermCond",
    "TrajectoryPlanner",
    "load_planner",
]
