"""A CNC machine controller with LinuxCNC's architecture, written in Python.

The public Python API (``cnc.stat``, ``cnc.command``, ``cnc.error_channel``) lives here once
the task/launcher issue lands; the other packages are the processes:
``nml`` (message buffers), ``hal``, ``motion``, ``task`` (with the RS274NGC interpreter),
``iocontrol``.
"""

# The Python API (``import cnc as linuxcnc``, see cnc/README.md) is loaded on first use by
# __getattr__ below, so that ``import cnc`` stays cheap. Only cnc.ini is set up now: the name
# ``cnc.ini`` is the INI module, made callable as LinuxCNC's ``linuxcnc.ini`` class.
from cnc import ini as _ini_module
from cnc.api.inifile import make_callable as _make_callable

_make_callable(_ini_module)


def __getattr__(name: str) -> object:  # PEP 562: the API on first use
    if name.startswith("__"):  # probes such as __wrapped__: not API names
        raise AttributeError(f"module 'cnc' has no attribute '{name}'")
    from cnc.api import lookup

    value = lookup(name)
    if name != "nmlfile":  # the running machine's NML file can change: never cached
        globals()[name] = value
    return value


def __dir__() -> list[str]:
    from cnc.api import public_names

    return sorted({*globals(), *public_names()})
