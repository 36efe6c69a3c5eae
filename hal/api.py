"""Writing HAL components: a declarative API for realtime ones, LinuxCNC's API for userspace.

Realtime component (loaded into the host with ``loadrt NAME``; see hal/README.md)::

    from hal.api import RtComponent, funct, param, pin

    class And2(RtComponent):
        in0 = pin("bit in")
        in1 = pin("bit in")
        out = pin("bit out")

        @funct()                       # function named like the instance: and2.0
        def update(self, period: int) -> None:
            self.out = self.in0 and self.in1

Userspace component (its own process)::

    c = component("mycomp")
    c.newpin("out", HAL_FLOAT, HAL_OUT)
    c.ready()
    c["out"] = 1.5

(LinuxCNC's whole Python ``hal`` module, for scripts written for LinuxCNC, is
``hal.pymodule``: ``import hal`` gives it.)
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import sys
import threading
from collections.abc import Callable
from typing import Any, ClassVar

from cnc.stdio import keep_lines_whole
from hal import core
from hal.core import (
    DIRS_BY_NAME,
    HAL_BIT,
    HAL_FLOAT,
    HAL_IN,
    HAL_IO,
    HAL_OUT,
    HAL_RO,
    HAL_RW,
    HAL_S32,
    HAL_S64,
    HAL_U32,
    HAL_U64,
    TYPES_BY_NAME,
    Hal,
    HalError,
    check_name,
)

__all__ = [
    "HAL_BIT",
    "HAL_FLOAT",
    "HAL_IN",
    "HAL_IO",
    "HAL_OUT",
    "HAL_RO",
    "HAL_RW",
    "HAL_S32",
    "HAL_S64",
    "HAL_U32",
    "HAL_U64",
    "HalError",
    "RtComponent",
    "component",
    "funct",
    "module_funct",
    "param",
    "pin",
    "shared_hal",
    "sized",
]

_shared: Hal | None = None
MAX_PERSONALITIES = 64  # halcompile's personality table


def shared_hal() -> Hal:
    """This process's attachment to the HAL of the current instance (created on first use)."""
    global _shared
    if _shared is None:
        _shared = Hal()
    return _shared


def set_shared_hal(hal: Hal | None) -> None:
    """Let a process that made its own ``Hal`` (the host, a test) share it with components."""
    global _shared
    _shared = hal


# ---------------------------------------------------------------- value accessors
# One small class per type and kind, so a component's ``self.x`` costs a descriptor call and
# two memoryview lookups: the pin's pointer entry, then the value slot it points at.
_S32_OFFSET = 1 << 31


class _Accessor:
    __slots__ = ("f", "ptr", "q", "slot", "u")

    def __init__(self, hal: Hal, slot: int) -> None:
        self.f, self.q, self.u, self.ptr, self.slot = hal.f, hal.q, hal.u, hal.ptr, slot


class _FloatPin(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> float:
        return self.f[self.ptr[self.slot]]

    def __set__(self, inst: object, value: float) -> None:
        self.f[self.ptr[self.slot]] = float(value)


class _BitPin(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> bool:
        return self.q[self.ptr[self.slot]] != 0

    def __set__(self, inst: object, value: object) -> None:
        self.q[self.ptr[self.slot]] = 1 if value else 0


class _S32Pin(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> int:
        return self.q[self.ptr[self.slot]]

    def __set__(self, inst: object, value: int) -> None:
        self.q[self.ptr[self.slot]] = ((int(value) + _S32_OFFSET) & 0xFFFFFFFF) - _S32_OFFSET


class _U32Pin(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> int:
        return self.u[self.ptr[self.slot]]

    def __set__(self, inst: object, value: int) -> None:
        self.u[self.ptr[self.slot]] = int(value) & 0xFFFFFFFF


class _S64Pin(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> int:
        return self.q[self.ptr[self.slot]]

    def __set__(self, inst: object, value: int) -> None:
        self.q[self.ptr[self.slot]] = core.wrap_value(HAL_S64, value)


class _U64Pin(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> int:
        return self.u[self.ptr[self.slot]]

    def __set__(self, inst: object, value: int) -> None:
        self.u[self.ptr[self.slot]] = int(value) & 0xFFFFFFFFFFFFFFFF


class _FloatParam(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> float:
        return self.f[self.slot]

    def __set__(self, inst: object, value: float) -> None:
        self.f[self.slot] = float(value)


class _BitParam(_Accessor):
    __slots__ = ()

    def __get__(self, inst: object, owner: type | None = None) -> bool:
        return self.q[self.slot] != 0

    def __set__(self, inst: object, value: object) -> None:
        self.q[self.slot] = 1 if value else 0


class _IntParam(_Accessor):
    __slots__ = ("hal_type",)

    def __get__(self, inst: object, owner: type | None = None) -> int:
        return (self.u if self.hal_type in (HAL_U32, HAL_U64) else self.q)[self.slot]

    def __set__(self, inst: object, value: int) -> None:
        stored = core.wrap_value(self.hal_type, value)
        (self.u if self.hal_type in (HAL_U32, HAL_U64) else self.q)[self.slot] = stored


_PIN_ACCESSORS = {
    HAL_FLOAT: _FloatPin,
    HAL_BIT: _BitPin,
    HAL_S32: _S32Pin,
    HAL_U32: _U32Pin,
    HAL_S64: _S64Pin,
    HAL_U64: _U64Pin,
}


def make_accessor(hal: Hal, hal_type: int, slot: int, *, is_pin: bool) -> Any:
    """A descriptor object reading and writing one pin or parameter."""
    if is_pin:
        return _PIN_ACCESSORS[hal_type](hal, slot)
    if hal_type == HAL_FLOAT:
        return _FloatParam(hal, slot)
    if hal_type == HAL_BIT:
        return _BitParam(hal, slot)
    accessor = _IntParam(hal, slot)
    accessor.hal_type = hal_type
    return accessor


class PinArray:
    """``self.in_[i]`` for a pin or parameter declared with ``count=N``."""

    __slots__ = ("_items",)

    def __init__(self, items: list[Any]) -> None:
        self._items = items

    def __len__(self) -> int:
        return len(self._items)

    def __getitem__(self, index: int) -> Any:
        return self._items[index].__get__(None)

    def __setitem__(self, index: int, value: Any) -> None:
        self._items[index].__set__(None, value)


class _ArrayDescriptor:
    __slots__ = ("array",)

    def __init__(self, array: PinArray) -> None:
        self.array = array

    def __get__(self, inst: object, owner: type | None = None) -> PinArray:
        return self.array


# ---------------------------------------------------------------- declarations
class _Decl:
    """A pin or parameter declared in an ``RtComponent`` class body."""

    is_pin: ClassVar[bool] = True

    def __init__(
        self,
        spec: str,
        name: str | None = None,
        *,
        count: int | str | Callable[[dict[str, Any]], int] | None = None,
        default: Any = 0,
        when: Callable[[dict[str, Any]], Any] | None = None,
        doc: str = "",
    ) -> None:
        words = spec.split()
        if len(words) != 2 or words[0] not in TYPES_BY_NAME or words[1] not in DIRS_BY_NAME:
            raise ValueError(f"bad declaration '{spec}': want e.g. 'float in' or 'bit rw'")
        self.hal_type = TYPES_BY_NAME[words[0]]
        self.direction = DIRS_BY_NAME[words[1]]
        self.name = name
        self.count = count
        self.default = default
        #: made only when ``when(options)`` is true (halcompile's ``if personality & 1``)
        self.when = when
        self.doc = doc
        self.attr = ""

    def count_for(self, options: dict[str, Any]) -> int | None:
        """How many pins to make: None for one plain pin, else the array's size."""
        if callable(self.count):
            return int(self.count(options))
        if isinstance(self.count, str):
            return int(options[self.count])
        return self.count

    def __set_name__(self, owner: type, attr: str) -> None:
        self.attr = attr
        if self.name is None:
            self.name = attr.rstrip("_").replace("_", "-")

    def hal_names(self, count: int | None) -> list[str]:
        assert self.name is not None
        if count is None:
            return [self.name]
        pattern = self.name if "{" in self.name else self.name + "{}"
        return [pattern.format(i) for i in range(count)]


def sized(limit: int, size: Callable[[dict[str, Any]], int]) -> Callable[[dict[str, Any]], int]:
    """halcompile's ``name-##[LIMIT : SIZE]`` as a ``count=``: SIZE (a function of the
    options) pins, refused when it is above LIMIT."""

    def count(options: dict[str, Any]) -> int:
        wanted = int(size(options))
        if wanted > limit:
            raise HalError(f"Requested size {wanted} exceeds max size {limit}")
        return max(wanted, 0)

    return count


def pin(spec: str, name: str | None = None, **kwargs: Any) -> Any:
    """Declare a pin: ``pin("float in")``, ``pin("bit out", "is-on")``, ``count=4``.

    ``count`` may name a setup option or be a function of the options (``count=lambda o:
    o["personality"] & 0xff``); ``when=`` (a function of the options) makes the pin only
    when it returns true.
    """
    decl = _Decl(spec, name, **kwargs)
    if decl.direction not in (HAL_IN, HAL_OUT, HAL_IO):
        raise ValueError(f"pin direction must be in, out or io, not '{spec}'")
    return decl


class _ParamDecl(_Decl):
    is_pin = False


def param(spec: str, name: str | None = None, **kwargs: Any) -> Any:
    """Declare a parameter: ``param("float rw")``, ``param("s32 ro", "count")``."""
    decl = _ParamDecl(spec, name, **kwargs)
    if decl.direction not in (HAL_RO, HAL_RW):
        raise ValueError(f"parameter direction must be ro or rw, not '{spec}'")
    return decl


def _target(method: Any) -> Any:
    """The plain function behind a (class)method, where marks must live to be found."""
    return method.__func__ if isinstance(method, classmethod | staticmethod) else method


def funct(name: str = "", *, has_fp: bool = True) -> Callable[[Callable], Callable]:
    """Mark a method ``f(self, period_ns)`` as a HAL function of each instance.

    ``name`` "" gives the function the instance's name (``and2.0``); otherwise it is
    ``<instance>.<name>`` (``pid.0.do-pid-calcs``).
    """

    def mark(method: Callable) -> Callable:
        _target(method)._hal_funct = (name, has_fp)
        return method

    return mark


def module_funct(
    name: str, *, has_fp: bool = True, full_name: str = ""
) -> Callable[[Callable], Callable]:
    """Mark a classmethod ``f(cls, instances, period_ns)`` as one function for all instances,
    named ``<module>.<name>`` (``stepgen.make-pulses``), or ``full_name`` when given
    (weighted_sum's ``process_wsums``)."""

    def mark(method: Callable) -> Callable:
        _target(method)._hal_module_funct = (name, has_fp, full_name)
        return method

    return mark


class RtComponent:
    """Base class of realtime components; see hal/README.md.

    Class attributes: ``pin(...)`` and ``param(...)`` declarations, methods marked with
    ``@funct``/``@module_funct``. Override ``setup(self, **options)`` for per-instance state
    and ``instances(cls, module, args)`` for loadrt arguments other than count/names.
    """

    name: str = ""
    #: instance name prefix when loaded with count=; default: module name with '-' for '_'
    prefix: str = ""
    #: loadrt options besides count/names, with their converters, e.g. {"depth": int}
    options: ClassVar[dict[str, Callable[[str], Any]]] = {}
    #: instances made without count=/names= (LinuxCNC's default_count / default_num_chan)
    default_count: ClassVar[int] = 1
    #: the most instances allowed (LinuxCNC's MAX_CHAN of modules written in C), or None
    max_count: ClassVar[int | None] = None
    #: the loadrt argument giving the count: ``num_chan`` for LinuxCNC's C modules
    #: (``count`` is accepted as well)
    count_option: ClassVar[str] = "count"
    #: one instance named after the module (halcompile's ``option singleton``)
    is_singleton: ClassVar[bool] = False
    #: instances take a number from ``personality=`` (halcompile's ``option personality``)
    has_personality: ClassVar[bool] = False
    default_personality: ClassVar[int] = 0

    def setup(self, **options: Any) -> None:
        """Called once after the instance's pins exist (``self.hal``, ``self.comp`` are set)."""

    def teardown(self) -> None:
        """Called when the module is unloaded: release what ``setup`` acquired."""

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        """(instance name, setup options) for each instance ``loadrt`` asks for.

        As LinuxCNC: ``count=N`` (``num_chan=N`` for the modules written in C, see
        ``count_option``) or ``names=a,b``, not both; neither, ``count=0`` or an empty
        ``names=`` give ``default_count`` instances; ``max_count`` bounds both. A
        singleton has one instance named after the module. With ``has_personality``,
        ``personality=a,b,...`` gives each instance its number (option ``personality``):
        the Nth value, else ``default_personality``, repeating every 64 instances.
        """
        count_keys = set() if cls.is_singleton else {"count", cls.count_option, "names"}
        known = count_keys | set(cls.options) | ({"personality"} if cls.has_personality else set())
        unknown = set(args) - known
        if unknown:
            raise HalError(f"{module}: unknown argument '{sorted(unknown)[0]}'")
        options = {
            key: cls.options[key](value) for key, value in args.items() if key in cls.options
        }
        prefix = cls.prefix or module.removeprefix("hal_").replace("_", "-")
        names = [prefix] if cls.is_singleton else cls._instance_names(module, args, prefix)
        for name in names:
            check_name("instance", name)
        personalities = cls._personalities(module, args.get("personality", ""), len(names))
        return [
            (name, {**options, **({"personality": p} if cls.has_personality else {})})
            for name, p in zip(names, personalities, strict=True)
        ]

    @classmethod
    def _instance_names(cls, module: str, args: dict[str, str], prefix: str) -> list[str]:
        names = [n for n in args.get("names", "").split(",") if n]
        count_text = args.get(cls.count_option) or args.get("count") or "0"
        try:
            count = int(count_text, 0)
        except ValueError:
            raise HalError(f"{module}: {cls.count_option}={count_text} is not a number") from None
        if count and names:
            raise HalError(f"{module}: {cls.count_option}= and names= are mutually exclusive")
        if not count and not names:
            count = cls.default_count
        limit = cls.max_count
        if limit is not None and not 0 < (len(names) or count) <= limit:
            raise HalError(
                f"{module}: ERROR: invalid {cls.count_option if count else 'number of names'}:"
                f" {len(names) or count} (1 to {limit})"
            )
        return names or [f"{prefix}.{i}" for i in range(count)]

    @classmethod
    def _personalities(cls, module: str, text: str, count: int) -> list[int]:
        try:
            given = [int(word, 0) for word in text.split(",") if word]
        except ValueError:
            raise HalError(f"{module}: personality={text} is not a list of numbers") from None
        table = (given + [cls.default_personality] * MAX_PERSONALITIES)[:MAX_PERSONALITIES]
        return [table[i % MAX_PERSONALITIES] for i in range(count)]

    def is_connected(self, attr: str) -> bool:
        """True when the pin declared as ``attr`` is linked to a signal."""
        accessor = type(self).__dict__[attr]
        return accessor.ptr[accessor.slot] != accessor.slot

    @classmethod
    def declarations(cls) -> list[_Decl]:
        found: dict[str, _Decl] = {}
        for klass in reversed(cls.__mro__):
            for attr, value in vars(klass).items():
                if isinstance(value, _Decl):
                    found[attr] = value
        return list(found.values())

    @classmethod
    def create(
        cls, hal: Hal, comp: str, name: str, options: dict[str, Any] | None = None
    ) -> RtComponent:
        """Make one instance: its pins and parameters in HAL, named ``<name>.<pin>`` (or
        just ``<pin>`` when ``name`` is ""), then ``setup``."""
        with hal.edit():  # one metadata update for all of the instance's pins
            return cls._create(hal, comp, name, options)

    @classmethod
    def _create(cls, hal: Hal, comp: str, name: str, options: dict[str, Any] | None) -> RtComponent:
        attrs: dict[str, Any] = {}
        for decl in cls.declarations():
            if decl.when is not None and not decl.when(options or {}):
                attrs[decl.attr] = None  # not made for this instance
                continue
            count = decl.count_for(options or {})
            accessors = []
            for hal_name in decl.hal_names(count):
                full = f"{name}.{hal_name}" if name else hal_name  # "": names of their own
                if decl.is_pin:
                    slot = hal.new_pin(comp, full, decl.hal_type, decl.direction)
                else:
                    slot = hal.new_param(comp, full, decl.hal_type, decl.direction)
                accessor = make_accessor(hal, decl.hal_type, slot, is_pin=decl.is_pin)
                accessor.__set__(None, decl.default)
                accessors.append(accessor)
            if count is None:
                attrs[decl.attr] = accessors[0]
            else:
                attrs[decl.attr] = _ArrayDescriptor(PinArray(accessors))
        bound_class = type(cls.__name__, (cls,), attrs)
        inst = object.__new__(bound_class)
        inst.name = name
        inst.hal = hal
        inst.comp = comp
        inst.setup(**(options or {}))
        return inst

    @classmethod
    def functs(cls) -> list[tuple[str, bool, str, str]]:
        """(name, has_fp, method name, scope) for every marked method. Scope ``instance``:
        the name follows the instance's (``pid.0.do-pid-calcs``); ``module``: the module's
        prefix (``stepgen.make-pulses``); ``global``: the name is complete."""
        found = []
        for attr in dir(cls):
            method = getattr(cls, attr, None)
            if hasattr(method, "_hal_funct"):
                found.append((*method._hal_funct, attr, "instance"))
            elif hasattr(method, "_hal_module_funct"):
                name, has_fp, full_name = method._hal_module_funct
                if full_name:
                    found.append((full_name, has_fp, attr, "global"))
                else:
                    found.append((name, has_fp, attr, "module"))
        return found


# ---------------------------------------------------------------- userspace (LinuxCNC-like)
class Item:
    """A pin or parameter of a userspace component (``c.newpin(...)`` returns one)."""

    def __init__(self, hal: Hal, name: str, hal_type: int, direction: int, slot: int) -> None:
        self.hal, self.name, self.type, self.dir, self.slot = hal, name, hal_type, direction, slot
        self._is_pin = direction in (HAL_IN, HAL_OUT, HAL_IO)

    def get(self) -> Any:
        slot = self.hal.ptr[self.slot] if self._is_pin else self.slot
        value = self.hal.read_slot(self.type, slot)
        return bool(value) if self.type == HAL_BIT else value

    def set(self, value: Any) -> None:
        slot = self.hal.ptr[self.slot] if self._is_pin else self.slot
        self.hal.write_slot(self.type, slot, value)

    def get_name(self) -> str:
        return self.name

    def get_type(self) -> int:
        return self.type

    def get_dir(self) -> int:
        return self.dir

    def is_pin(self) -> bool:
        return self._is_pin


class component:
    """A userspace HAL component: ``component(name)``, ``newpin``, ``ready``, ``c[pin]``."""

    def __init__(self, name: str, prefix: str | None = None, hal: Hal | None = None) -> None:
        self._hal = hal or shared_hal()
        self._name = name
        self._prefix = prefix if prefix is not None else name
        self._items: dict[str, Item] = {}
        self._hal.new_component(name, "user", os.getpid())
        self._is_alive = True
        atexit.register(self.exit)
        _exit_on_sigterm()
        keep_lines_whole()  # (a component program shares halcmd's terminal)

    def newpin(self, name: str, hal_type: int, direction: int) -> Item:
        full = f"{self._prefix}.{name}"
        slot = self._hal.new_pin(self._name, full, hal_type, direction)
        item = Item(self._hal, full, hal_type, direction, slot)
        self._items[name] = item
        return item

    def newparam(self, name: str, hal_type: int, direction: int) -> Item:
        full = f"{self._prefix}.{name}"
        slot = self._hal.new_param(self._name, full, hal_type, direction)
        item = Item(self._hal, full, hal_type, direction, slot)
        self._items[name] = item
        return item

    def getpin(self, name: str) -> Item:
        return self._items[name]

    def getpins(self) -> dict[str, Item]:
        return dict(self._items)

    def ready(self) -> None:
        self._hal.ready(self._name)

    def exit(self) -> None:
        if self._is_alive:
            self._is_alive = False
            # at interpreter exit the HAL may already be gone: nothing left to remove then
            with contextlib.suppress(HalError, ValueError, OSError):
                self._hal.remove_component(self._name)

    def getprefix(self) -> str:
        return self._prefix

    def setprefix(self, prefix: str) -> None:
        self._prefix = prefix

    def __getitem__(self, name: str) -> Any:
        return self._items[name].get()

    def __setitem__(self, name: str, value: Any) -> None:
        self._items[name].set(value)

    def __enter__(self) -> component:
        return self

    def __exit__(self, *exc: object) -> None:
        self.exit()


def _exit_on_sigterm() -> None:
    """Let ``unload`` (SIGTERM) run the exit handlers that remove the component, unless the
    program handles SIGTERM itself."""
    is_main = threading.current_thread() is threading.main_thread()
    if is_main and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
