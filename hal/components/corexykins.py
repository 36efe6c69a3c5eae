"""``loadrt corexykins``: CoreXY kinematics for motmod (motion/kinematics/corexy.py)."""

from typing import Any

from motion.motmod import load_kinematics_module


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    load_kinematics_module(host, "corexy", args)
