"""``cnc.error`` (LinuxCNC's ``linuxcnc.error``), in a module of its own: the API's modules
raise it, and the package (``cnc/api/__init__.py``) only names it, so imports flow one way."""


class error(RuntimeError):  # noqa: N818  (LinuxCNC's name: linuxcnc.error)
    """The controller cannot be reached, or refused a request (``linuxcnc.error``)."""
