"""Errors of the NML layer. Each message names the buffer (or file:line) and the cause."""


class NmlError(Exception):
    """Base of every NML error."""


class NmlConfigError(NmlError):
    """An NML configuration file is invalid; ``errors`` lists every ``file:line: cause``."""

    def __init__(self, errors: list[str]) -> None:
        super().__init__("\n".join(errors))
        self.errors = errors


class NmlRegistryError(NmlError):
    """A message type number or name is declared twice."""


class NmlTimeoutError(NmlError):
    """A buffer could not be accessed, or had no message/room, within the timeout."""


class NmlAccessError(NmlError):
    """An operation the P line does not allow (ops, max_procs), or a missing buffer."""


class NmlFormatError(NmlError):
    """A message cannot be encoded (too large) or decoded (corrupt, unknown type, layout)."""
