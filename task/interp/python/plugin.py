"""The ``[PYTHON]`` plug-in: user Python code the interpreter calls (PY-001..PY-007, PY-027).

One plug-in per interpreter. It reads ``[PYTHON]`` (TOPLEVEL, PATH_PREPEND, PATH_APPEND,
LOG_LEVEL, RELOAD_ON_CHANGE), puts the folders on the module path as LinuxCNC does (each
PATH_PREPEND inserted at the front in turn, each PATH_APPEND appended, then this package's
``glue`` folder, so a configuration's own ``stdglue.py`` wins over ours), and executes the
TOPLEVEL file in a namespace of its own that already holds the built-in modules
(``interpreter``, ``emccanon``, and ``emctask`` in task) and ``this`` (the interpreter).

Callables are looked up as LinuxCNC does: ``remap.<name>`` means the name ``remap`` bound in
the TOPLEVEL's namespace (TOPLEVEL must ``import remap``), ``__init__`` and ``__delete__``
are TOPLEVEL's own functions. Without a TOPLEVEL the plug-in still runs ``;py,`` statements.

The modules TOPLEVEL imports are forgotten again when the plug-in closes (and, with
RELOAD_ON_CHANGE, when one of their files changes), so that a new plug-in, or the same one
after an edit, imports them afresh.
"""

from __future__ import annotations

import builtins
import importlib
import os
import sys
import threading
import traceback
from collections.abc import Callable
from pathlib import Path

from . import emccanon, interpreter

GLUE_FOLDER = str(Path(__file__).with_name("glue"))
MODULES = {"interpreter": interpreter, "emccanon": emccanon}
# configuring a plug-in changes sys.path and sys.modules: one at a time in a process
_CONFIGURE_LOCK = threading.Lock()
# the modules TOPLEVEL files imported and the module path entries added, of every plug-in of
# the process: a new plug-in starts without those of plug-ins not closed (another
# configuration's remap.py, stdglue.py or folders must not stand for its own)
_USER_MODULES: set[str] = set()
_USER_PATHS: list[str] = []


class PluginError(Exception):
    """A ``[PYTHON]`` setting that cannot work, or a TOPLEVEL that failed; ``str()`` names
    the file and line."""


class UserCodeError(Exception):
    """An exception raised by user code: ``cause`` is ``Type: message``, ``text`` the
    whole traceback (as LinuxCNC logs it)."""

    def __init__(self, exc: BaseException) -> None:
        self.cause = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        tb = exc.__traceback__
        while tb is not None and tb.tb_frame.f_code.co_filename == __file__:
            tb = tb.tb_next  # the plug-in's own frames: not the user's business
        # LinuxCNC joins the traceback's parts with newlines: a blank line between them
        self.text = "\n".join(traceback.format_exception(type(exc), exc, tb))
        super().__init__(self.cause)


class PythonPlugin:
    """The namespace of a configuration's Python code and the calls into it."""

    def __init__(
        self,
        view: object,
        *,
        toplevel: str | None = None,
        prepend: tuple[str, ...] = (),
        append: tuple[str, ...] = (),
        log_level: int = 0,
        is_reloading: bool = False,
        extra_modules: dict | None = None,
        log: Callable[[str], object] = lambda text: None,
    ) -> None:
        """``view`` is ``self`` of the handlers; ``extra_modules`` more built-in modules
        (task adds ``emctask``); ``log`` takes the plug-in's messages."""
        self.view = view
        self.toplevel = toplevel
        self.prepend = prepend
        self.append = append
        self.log_level = log_level
        self.is_reloading = is_reloading
        self.modules = dict(MODULES, **(extra_modules or {}))
        self.log = log
        self.namespace: dict = {}
        self._added_paths: list[str] = []
        self._own_modules: dict[str, float] = {}  # module name -> its file's mtime
        self._toplevel_mtime = 0.0
        with _CONFIGURE_LOCK:
            for name, module in self.modules.items():
                sys.modules[name] = module
            _remove_paths(_USER_PATHS)
            _USER_PATHS.clear()
            for folder in prepend:
                sys.path.insert(0, folder)
                self._added_paths.append(folder)
            for folder in (*append, GLUE_FOLDER):
                sys.path.append(folder)
                self._added_paths.append(folder)
            _USER_PATHS.extend(self._added_paths)
            _forget_finders(self._added_paths)
            self._initialize()

    @classmethod
    def from_ini(
        cls,
        ini,
        view: object,
        *,
        extra_modules: dict | None = None,
        log: Callable[[str], object] = lambda text: None,
    ) -> PythonPlugin:
        """The plug-in ``[PYTHON]`` of ``ini`` describes (paths relative to the current
        folder, as LinuxCNC has them; the launcher runs everything in the configuration's
        folder)."""
        toplevel = None
        entry = ini.entry("PYTHON", "TOPLEVEL")
        if entry is not None:
            path = os.path.expanduser(entry.value)
            if not os.path.isfile(path):
                raise PluginError(
                    f"{entry.file}:{entry.line}: [PYTHON]TOPLEVEL={entry.value}: no such file"
                )
            toplevel = os.path.realpath(path)
        prepend = tuple(os.path.expanduser(e.value) for e in ini.entries("PYTHON", "PATH_PREPEND"))
        append = tuple(os.path.expanduser(e.value) for e in ini.entries("PYTHON", "PATH_APPEND"))
        log_level = _int_setting(ini, "LOG_LEVEL", 0)
        is_reloading = _int_setting(ini, "RELOAD_ON_CHANGE", 0) > 0
        return cls(
            view,
            toplevel=toplevel,
            prepend=prepend,
            append=append,
            log_level=log_level,
            is_reloading=is_reloading,
            extra_modules=extra_modules,
            log=log,
        )

    # ------------------------------------------------------------ namespace
    def _initialize(self) -> None:
        interpreter.this = self.view
        namespace = {"__name__": "__main__", "__builtins__": builtins, "this": self.view}
        namespace.update(self.modules)
        self.namespace = namespace
        if self.toplevel is None:
            return
        for name in _USER_MODULES:
            sys.modules.pop(name, None)
        _USER_MODULES.clear()
        before = set(sys.modules)
        self._toplevel_mtime = _mtime(self.toplevel)
        try:
            source = Path(self.toplevel).read_text(encoding="utf-8")
            namespace["__file__"] = self.toplevel
            exec(compile(source, self.toplevel, "exec"), namespace)
        except Exception as exc:
            error = UserCodeError(exc)
            raise PluginError(
                f"[PYTHON]TOPLEVEL={self.toplevel}: {error.cause}\n{error.text}"
            ) from None
        finally:
            for name in set(sys.modules) - before:
                self._own_modules[name] = _mtime(getattr(sys.modules[name], "__file__", None))
                _USER_MODULES.add(name)
        self.log_at(1, f"PythonPlugin: {self.toplevel} loaded")

    def _forget_own_modules(self) -> None:
        for name in self._own_modules:
            sys.modules.pop(name, None)
        self._own_modules.clear()

    def reload_if_changed(self) -> None:
        """RELOAD_ON_CHANGE: execute TOPLEVEL afresh (and import its modules afresh) when
        its file or one of its modules' files has changed."""
        if not self.is_reloading or self.toplevel is None:
            return
        changed = _mtime(self.toplevel) != self._toplevel_mtime or any(
            _mtime(getattr(sys.modules.get(name), "__file__", None)) != mtime
            for name, mtime in self._own_modules.items()
        )
        if changed:
            with _CONFIGURE_LOCK:
                self._forget_own_modules()
                self._initialize()
            self.log_at(1, f"PythonPlugin: {self.toplevel} reloaded")

    def close(self) -> None:
        """Forget the modules TOPLEVEL imported and the module path entries added."""
        with _CONFIGURE_LOCK:
            self._forget_own_modules()
            _remove_paths(self._added_paths)
            _forget_finders(self._added_paths)
            self._added_paths.clear()
        if interpreter.this is self.view:
            interpreter.this = None

    def log_at(self, level: int, text: str) -> None:
        if self.log_level >= level:
            self.log(text)

    # ---------------------------------------------------------------- calls
    def find(self, module: str | None, name: str) -> Callable | None:
        """``module.name`` (``module`` None: a TOPLEVEL function) if it is callable."""
        self.reload_if_changed()
        if module is None:
            function = self.namespace.get(name)
        else:
            holder = self.namespace.get(module)
            function = getattr(holder, "__dict__", {}).get(name) if holder is not None else None
        return function if callable(function) else None

    def names(self, module: str) -> list[str]:
        """The callables of ``module`` (as TOPLEVEL binds it), in its own order."""
        holder = self.namespace.get(module)
        if holder is None:
            return []
        return [name for name, value in vars(holder).items() if callable(value)]

    def call(self, function: Callable, *args, **kwargs):
        """Call user code; an exception it raises becomes UserCodeError (logged)."""
        interpreter.this = self.view
        try:
            return function(*args, **kwargs)
        except StopIteration:
            raise  # a generator's end (resuming a handler): not an error of user code
        except Exception as exc:
            error = UserCodeError(exc)
            self.log_at(0, f"call({_qualified(function)}): \n{error.text}")
            raise error from None

    def run(self, statement: str) -> None:
        """A ``;py,`` statement, in the TOPLEVEL namespace."""
        self.reload_if_changed()
        interpreter.this = self.view
        try:
            exec(statement, self.namespace)
        except Exception as exc:
            error = UserCodeError(exc)
            self.log_at(0, f"run_string({statement}): \n{error.text}")
            raise error from None


def _remove_paths(folders: list[str]) -> None:
    """Take the entries out of the module path (one each: the same folder may be there
    for other reasons too)."""
    for folder in folders:
        if folder in sys.path:
            sys.path.remove(folder)


def _forget_finders(folders: list[str]) -> None:
    """Python caches a finder per module path entry, with the folder's listing: a relative
    entry such as ``.`` means another folder after a chdir."""
    for folder in folders:
        sys.path_importer_cache.pop(folder, None)
    importlib.invalidate_caches()


def _qualified(function: Callable) -> str:
    module = getattr(function, "__module__", None) or ""
    name = getattr(function, "__name__", repr(function))
    return f"{module}.{name}" if module and module != "__main__" else name


def _mtime(path: str | None) -> float:
    if not path:
        return 0.0
    try:
        return os.stat(path).st_mtime
    except OSError:
        return -1.0


def _int_setting(ini, key: str, default: int) -> int:
    entry = ini.entry("PYTHON", key)
    if entry is None:
        return default
    try:
        return int(entry.value.split()[0])
    except (ValueError, IndexError):
        raise PluginError(
            f"{entry.file}:{entry.line}: [PYTHON]{key}={entry.value}: not an integer"
        ) from None
