"""``loadrt trivkins [coordinates=XYZ] [kinstype=1|B|F]``: trivial kinematics for motmod."""

from typing import Any

from motion.motmod import load_kinematics_module


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    load_kinematics_module(host, "trivkins", args)
