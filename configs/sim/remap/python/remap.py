"""The Python of the remap examples: the standard glue (prologs and epilogs for T, M6, M61,
S, F and cycles) and the G84.2 cycle of cycle.ini."""

from interpreter import INTERP_OK
from stdglue import *  # noqa: F403 (change_prolog, change_epilog, cycle_prolog ...)

_sticky: dict[str, float] = {}  # the words of the G84.2 cycle under way


def g842(self, **words):
    """G84.2 X Y Z R: drill a hole at X Y from R down to Z at the feed rate, back to R.

    A motion code of group 1: a line after it with only X / Y drills the next hole with the
    Z and R given before, until G80 or another motion code."""
    block = self.blocks[self.remap_level]
    remap = block.executing_remap
    if block.g_modes[1] == remap.motion_code:  # the line with G84.2: a new cycle
        _sticky.clear()
    _sticky.update(words)
    for word in "zr":
        if word not in _sticky:
            return f"G84.2 needs a {word.upper()} word"
    if self.feed_rate <= 0.0:
        return "G84.2: set a feed rate (F) first"
    r, z = _sticky["r"], _sticky["z"]
    xy = " ".join(f"{word.upper()}{words[word]:.4f}" for word in "xy" if word in words)
    self.execute(f"G0 Z{r:.4f}")
    if xy:
        self.execute(f"G0 {xy}")
    self.execute(f"G1 Z{z:.4f}")
    self.execute(f"G0 Z{r:.4f}")
    self.motion_mode = remap.motion_code  # the next line with only X / Y drills again
    return INTERP_OK
