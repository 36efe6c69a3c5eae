"""Run from line: where a program may start, and what its skipped lines leave behind.

Task starts a program at line N by interpreting lines 1..N-1 without carrying them out, as
LinuxCNC does, so modal state, offsets and tool are those of line N. Two cases cannot be
known that way and are refused: a start line inside a subroutine definition (its
parameters come from a call) or inside a loop body (which iteration?).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence

from nml import emc

# o<name> or oNNN, then the keyword; LinuxCNC's O-words are case-insensitive and may hold
# spaces ("o 100 while"), comments are stripped by the interpreter but rarely used here
_OWORD = re.compile(
    r"^\s*(?:/\s*)?(?:n\s*\d+\s*)?o\s*(<[^>]*>|[\d\s]+)\s*"
    r"(sub|endsub|while|endwhile|do|repeat|endrepeat)\b",
    re.IGNORECASE,
)
_OPENERS = {"sub": "endsub", "while": "endwhile", "do": "while", "repeat": "endrepeat"}

# What a skipped line's messages may set that the run needs: kept, the last of each kind.
STATE_MESSAGES = (
    emc.EMC_TRAJ_SET_OFFSET,  # G43/G49: the tool length offset motion reports
    emc.EMC_TRAJ_SET_G5X,
    emc.EMC_TRAJ_SET_G92,
    emc.EMC_TRAJ_SET_ROTATION,
    emc.EMC_TRAJ_SET_TERM_COND,  # G61/G64
    emc.EMC_TRAJ_SET_FO_ENABLE,
    emc.EMC_TRAJ_SET_SO_ENABLE,
    emc.EMC_TRAJ_SET_FH_ENABLE,
    emc.EMC_TRAJ_SET_SPINDLESYNC,
)


def enclosing_block(
    lines: Sequence[str], line: int, progress: Callable[[], None] | None = None
) -> str | None:
    """Why the program cannot start at ``line`` (1-based), or None: the subroutine or
    loop whose body holds it, e.g. "the body of o100 while (lines 12-30)". ``progress``
    is called every 10,000 lines (a large program takes a while)."""
    stack: list[tuple[str, str, int]] = []  # (o-name, keyword, line) of open blocks
    spans: list[tuple[str, str, int, int]] = []
    for number, text in enumerate(lines, start=1):
        if progress is not None and not number % 10_000:
            progress()
        if "o" not in text and "O" not in text:
            continue  # (most lines: no O-word, no regular expression)
        match = _OWORD.match(text)
        if match is None:
            continue
        name = re.sub(r"\s+", "", match.group(1)).lower()
        keyword = match.group(2).lower()
        opened = stack[-1] if stack and stack[-1][0] == name else None
        if opened is not None and _OPENERS[opened[1]] == keyword:
            stack.pop()
            spans.append((name, opened[1], opened[2], number))
        elif keyword in _OPENERS:
            stack.append((name, keyword, number))
    for name, keyword, first, last in spans:
        if first < line <= last:
            what = "the subroutine" if keyword == "sub" else f"the body of o{name} {keyword}"
            if keyword == "sub":
                what += f" o{name}"
            return f"{what} (lines {first}-{last})"
    return None
