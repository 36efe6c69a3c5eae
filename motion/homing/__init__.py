"""Homing, a replaceable module (ARCH-007/008, MOT-043/044).

``load_homing(name)`` returns the ``Homing`` class of homing module ``name`` (default
``homing``, i.e. ``motion.homing.homing``; or a dotted path to a user module). The module
must define ``Homing`` providing every public function of the default; an incomplete one
is refused with an error listing what is missing.
"""

from __future__ import annotations

from motion.homing.homing import HomeState, Homing, HomingConfig, HomingError
from motion.modules import import_module, require

# every public function and status property of the default homing class: a
# replacement must provide them all
REQUIRED_FUNCTIONS = tuple(
    name
    for name, value in vars(Homing).items()
    if not name.startswith("_") and (callable(value) or isinstance(value, property))
)


def load_homing(name: str = "homing") -> type:
    """The ``Homing`` class of homing module ``name`` (``[EMCMOT]HOMEMOD``-like)."""
    module = import_module(name, __name__, "homing")
    require(module, ("Homing",), f"homing module {name!r}")
    require(module.Homing, REQUIRED_FUNCTIONS, f"homing module {name!r}")
    return module.Homing


__all__ = [
    "REQUIRED_FUNCTIONS",
    "HomeState",
    "Homing",
    "HomingConfig",
    "HomingError",
    "load_homing",
]
