"""The nine world axes, in the order of every pose, axis mask and [AXIS_L] section (KIN-002):
the one table of axis letters, with no imports, for any process (INI checks, UIs, motion)."""

AXIS_LETTERS = "XYZABCUVW"
NUM_AXES = len(AXIS_LETTERS)
