"""A CNC machine controller with LinuxCNC's architecture, written in Python.

The public Python API (``cnc.stat``, ``cnc.command``, ``cnc.error_channel``) lives here once
the task/launcher issue lands; the other packages are the processes:
``nml`` (message buffers), ``hal``, ``motion``, ``task`` (with the RS274NGC interpreter),
``iocontrol``.
"""

import sys
import types

# The Python API (``import cnc as linuxcnc``, see cnc/README.md) is loaded on first use by
# __getattr__ below, so that ``import cnc`` stays cheap (``cnc rs274`` starts in milliseconds).
# The name ``cnc.ini`` is the INI module, made callable as LinuxCNC's ``linuxcnc.ini`` class;
# it too is loaded on first use, and made callable however it is imported: the import system
# binds a submodule to its package with setattr, which _Package intercepts.


class _IniModule(types.ModuleType):
    """The module ``cnc.ini``, which ``cnc.ini(path)`` also calls to open a file."""

    def __call__(self, path: str) -> object:
        from cnc.api.inifile import ini

        return ini(path)


class _Package(types.ModuleType):
    def __setattr__(self, name: str, value: object) -> None:
        if name == "ini" and isinstance(value, types.ModuleType):
            value.__class__ = _IniModule
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


def __getattr__(name: str) -> object:  # PEP 562: the API on first use
    if name.startswith("__"):  # probes such as __wrapped__: not API names
        raise AttributeError(f"module 'cnc' has no attribute '{name}'")
    if name == "ini":
        import importlib  # binds cnc.ini, made callable by _Package.__setattr__

        return importlib.import_module("cnc.ini")
    from cnc.api import lookup

    value = lookup(name)
    if name != "nmlfile":  # the running machine's NML file can change: never cached
        globals()[name] = value
    return value


def __dir__() -> list[str]:
    from cnc.api import public_names

    return sorted({*globals(), *public_names()})
