"""Operator messages on their way to ``emcError``, never making their writer wait.

Task, motion, iocontrol and the launcher each post their messages here. A message is written
at once when the buffer's lock is free (the oldest queued messages make room if it is full:
readers are told how many they missed); while a reader holds the lock (a stuck UI), messages
wait here, up to ``limit``, and go out with the writer's next ``flush()``. The writer never
blocks: a realtime period or a task cycle must not wait behind a UI.
"""

from __future__ import annotations

import logging
from collections import deque

from nml import emc
from nml.errors import NmlError, NmlTimeoutError
from nml.shmem import ShmBuffer

log = logging.getLogger("nml")


class Outbox:
    def __init__(self, channel: ShmBuffer, limit: int = 1000) -> None:
        self.channel = channel
        self.pending: deque[emc.NMLmsg] = deque()
        self.limit = limit
        self.dropped = 0  # lost here while the channel stayed blocked

    def post(self, msg: emc.NMLmsg) -> None:
        if len(self.pending) >= self.limit:
            self.pending.popleft()
            self.dropped += 1
        self.pending.append(msg)
        self.flush()

    def error(self, text: str) -> None:
        self.post(emc.EMC_OPERATOR_ERROR(error=emc.fit_text(text)))

    def text(self, text: str) -> None:
        self.post(emc.EMC_OPERATOR_TEXT(text=emc.fit_text(text)))

    def flush(self) -> None:
        """Write what is pending, as far as the buffer's lock is free this instant."""
        if self.dropped and self.pending:
            count, self.dropped = self.dropped, 0
            self.pending.appendleft(
                emc.EMC_OPERATOR_ERROR(
                    error=f"{count} operator message(s) were lost: the error channel stayed "
                    "blocked by a stuck reader"
                )
            )
        while self.pending:
            try:
                self.channel.write(self.pending[0], timeout=0.0, is_oldest_dropped=True)
            except NmlTimeoutError:
                return  # a reader holds the lock: next flush
            except NmlError as exc:  # (cannot be encoded, buffer gone): said, not retried
                log.error("cannot write to %s: %s", self.channel.name, exc)
            self.pending.popleft()
