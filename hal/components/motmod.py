"""``loadrt motmod``: the motion controller; it lives in motion/motmod.py."""

from motion.motmod import rtapi_app_main

__all__ = ["rtapi_app_main"]
