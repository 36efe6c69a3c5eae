"""Message declarations: one typed class per message, from which every encoding is derived.

A message (or a plain struct inside one) is declared once, as a class with annotated fields
(NML-049 improved: the declaration replaces LinuxCNC's five manual steps)::

    class EMC_TRAJ_LINEAR_MOVE(EMC_TRAJ_CMD_MSG, type_id=220):
        end: EmcPose
        type: i32
        vel: f64
        ...

Field types are the markers below (``f64``, ``i32``, ``string(256)``, ``array(f64, 9)``) or
another ``Struct`` subclass. From the declaration come:

- a fixed binary layout: a little-endian numpy structured dtype. Every message object keeps
  its values in one 0-d array of that dtype, so the fixed encoding is its raw bytes and a
  decoded status is a single copy, with fields converted only when they are read;
- a self-describing msgpack form (``to_python`` / ``from_python``: nested dicts);
- a layout checksum carried in every encoded message, so a process built with a different
  declaration gets a clear error instead of garbage (NML-038).

Classes given a ``type_id`` are entered into the registry (``nml.registry``), which rejects
duplicate numbers and names (NML-050) and maps numbers to names (NML-051).
"""

from __future__ import annotations

import enum
import inspect
import struct
import sys
import zlib
from dataclasses import dataclass
from types import CodeType
from typing import Annotated, Any, ClassVar, get_args, get_origin

import numpy as np

from nml.registry import REGISTRY

# ----------------------------------------------------------------------------- field markers


@dataclass(frozen=True)
class Scalar:
    """A number or boolean stored with a fixed numpy type."""

    code: str
    python: type

    def dtype_entry(self, name: str) -> tuple:
        return (name, self.code)


@dataclass(frozen=True)
class Text:
    """A string stored in ``length`` bytes (UTF-8, NUL padded); longer values are refused."""

    length: int

    def dtype_entry(self, name: str) -> tuple:
        return (name, f"S{self.length}")


@dataclass(frozen=True)
class Array:
    """A fixed-size array of scalars or structs (LinuxCNC's fixed C arrays)."""

    item: Scalar | type[Struct]
    length: int

    def dtype_entry(self, name: str) -> tuple:
        item_dtype = self.item.code if isinstance(self.item, Scalar) else self.item.dtype
        return (name, item_dtype, (self.length,))


@dataclass(frozen=True)
class Nested:
    """A struct field (e.g. ``EmcPose`` inside a move)."""

    struct: type[Struct]

    def dtype_entry(self, name: str) -> tuple:
        return (name, self.struct.dtype)


f64 = Annotated[float, Scalar("<f8", float)]
f32 = Annotated[float, Scalar("<f4", float)]
i8 = Annotated[int, Scalar("<i1", int)]
u8 = Annotated[int, Scalar("<u1", int)]
i32 = Annotated[int, Scalar("<i4", int)]
u32 = Annotated[int, Scalar("<u4", int)]
i64 = Annotated[int, Scalar("<i8", int)]
u64 = Annotated[int, Scalar("<u8", int)]
boolean = Annotated[bool, Scalar("?", bool)]


def string(length: int) -> Any:
    """A text field of at most ``length`` bytes (LinuxCNC's ``char name[length]``)."""
    return Annotated[str, Text(length)]


def array(item: Any, length: int) -> Any:
    """A fixed-size array field, e.g. ``array(f64, 9)`` or ``array(EMC_JOINT_STAT, 16)``."""
    if isinstance(item, type) and issubclass(item, Struct):
        return Annotated[list, Array(item, length)]
    marker = _marker_of(item)
    if not isinstance(marker, Scalar):
        raise TypeError("array items must be scalars or Struct classes")
    return Annotated[list, Array(marker, length)]


def _marker_of(hint: Any) -> Scalar | Text | Array | Nested | None:
    if get_origin(hint) is Annotated:
        for meta in get_args(hint)[1:]:
            if isinstance(meta, Scalar | Text | Array):
                return meta
    if isinstance(hint, type) and issubclass(hint, Struct):
        return Nested(hint)
    return None


# ----------------------------------------------------------------------------- field access


@dataclass(frozen=True)
class Field:
    name: str
    marker: Scalar | Text | Array | Nested


class _ScalarField:
    __slots__ = ("name",)

    def __init__(self, name: str) -> None:
        self.name = name

    def __get__(self, obj: Struct | None, owner: type) -> Any:
        if obj is None:
            return self
        return obj._arr[self.name].item()

    def __set__(self, obj: Struct, value: Any) -> None:
        obj._arr[self.name] = value


class _TextField(_ScalarField):
    __slots__ = ("length",)

    def __init__(self, name: str, length: int) -> None:
        super().__init__(name)
        self.length = length

    def __get__(self, obj: Struct | None, owner: type) -> Any:
        if obj is None:
            return self
        return obj._arr[self.name].item().decode("utf-8", errors="replace")

    def __set__(self, obj: Struct, value: str | bytes) -> None:
        data = value.encode("utf-8") if isinstance(value, str) else bytes(value)
        if len(data) > self.length:
            raise ValueError(
                f"{type(obj).__name__}.{self.name}: {len(data)} bytes do not fit in "
                f"{self.length} (text would be truncated)"
            )
        obj._arr[self.name] = data


class _ArrayField(_ScalarField):
    """Scalar arrays read as numpy views (writable in place); struct arrays as StructArray."""

    __slots__ = ("struct",)

    def __init__(self, name: str, struct: type[Struct] | None) -> None:
        super().__init__(name)
        self.struct = struct

    def __get__(self, obj: Struct | None, owner: type) -> Any:
        if obj is None:
            return self
        view = obj._arr[self.name]
        return view if self.struct is None else StructArray(self.struct, view)

    def __set__(self, obj: Struct, value: Any) -> None:
        if self.struct is None:
            obj._arr[self.name] = value
            return
        target = obj._arr[self.name]
        for index, item in enumerate(value):
            target[index] = item._arr if isinstance(item, Struct) else item


class _NestedField(_ScalarField):
    __slots__ = ("struct",)

    def __init__(self, name: str, struct: type[Struct]) -> None:
        super().__init__(name)
        self.struct = struct

    def __get__(self, obj: Struct | None, owner: type) -> Any:
        if obj is None:
            return self
        return self.struct._view(obj._arr[self.name])

    def __set__(self, obj: Struct, value: Struct) -> None:
        if not isinstance(value, self.struct):
            raise TypeError(f"{self.name} must be a {self.struct.__name__}")
        target, source = obj._arr[self.name], value._arr
        if target.dtype is source.dtype and target.ndim == 0 and source.ndim == 0:
            # the same layout: one copy of the bytes (numpy copies a nested struct field by
            # field, ~15x slower: task copies motion's whole status every cycle)
            target.reshape(1).view(np.uint8)[:] = source.reshape(1).view(np.uint8)
        else:
            obj._arr[self.name] = source


class StructArray:
    """A fixed-size array of structs; items are live views into the owning message."""

    __slots__ = ("_struct", "_view_arr")

    def __init__(self, struct: type[Struct], view: np.ndarray) -> None:
        self._struct = struct
        self._view_arr = view

    def __len__(self) -> int:
        return len(self._view_arr)

    def __getitem__(self, index: int) -> Any:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        return self._struct._view(self._view_arr[index, ...])

    def __iter__(self):  # type: ignore[no-untyped-def]
        for index in range(len(self._view_arr)):
            yield self._struct._view(self._view_arr[index, ...])

    def __repr__(self) -> str:
        return f"[{', '.join(repr(item) for item in self)}]"


# ----------------------------------------------------------------------------- structs


_ANNOTATION_CODE: dict[str, CodeType] = {}


def _type_hints(cls: type) -> dict[str, Any]:
    """``typing.get_type_hints(cls, include_extras=True)``, at a fraction of the cost: each
    class's own annotations (strings, under ``from __future__ import annotations``) are
    evaluated once and kept on it, where ``get_type_hints`` evaluates every base's again
    for each subclass (a third of a second per process for nml.emc's 180 classes)."""
    hints: dict[str, Any] = {}
    for base in reversed(cls.__mro__[:-1]):  # (object has none)
        hints.update(_own_type_hints(base))
    return hints


def _own_type_hints(cls: type) -> dict[str, Any]:
    own = cls.__dict__.get("_own_hints")
    if own is None:
        own = {}
        module_names = vars(sys.modules[cls.__module__])
        class_names = dict(vars(cls))
        for name, hint in inspect.get_annotations(cls).items():
            if isinstance(hint, str):
                code = _ANNOTATION_CODE.get(hint)
                if code is None:
                    code = _ANNOTATION_CODE[hint] = compile(hint, "<annotation>", "eval")
                hint = eval(code, module_names, class_names)  # the class's own text
            own[name] = hint
        cls._own_hints = own  # type: ignore[attr-defined]
    return own


class Struct:
    """A plain data structure with a fixed layout (``EmcPose``, ``CANON_TOOL_TABLE`` ...)."""

    fields: ClassVar[tuple[Field, ...]] = ()
    defaults: ClassVar[dict[str, Any]] = {}
    dtype: ClassVar[np.dtype] = np.dtype([])
    flat_format: ClassVar[struct.Struct] = struct.Struct("<")
    flat_text_indexes: ClassVar[tuple[int, ...]] = ()
    flat_codes: ClassVar[tuple[str, ...]] = ()  # ``struct`` code of each leaf ("d", "255s")
    layout_crc: ClassVar[int] = 0
    __slots__ = ("_arr",)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._declare_fields()

    @classmethod
    def _declare_fields(cls) -> None:
        hints = _type_hints(cls)
        defaults = dict(cls.defaults)
        fields = []
        for name, hint in hints.items():
            if get_origin(hint) is ClassVar or name.startswith("_"):
                continue
            marker = _marker_of(hint)
            if marker is None:
                raise TypeError(
                    f"{cls.__name__}.{name}: not an NML field type "
                    "(use f64, i32, boolean, string(n), array(item, n) or a Struct)"
                )
            fields.append(Field(name, marker))
            declared = cls.__dict__.get(name)
            if declared is not None and not isinstance(declared, _ScalarField):
                defaults[name] = declared  # `speed: f64 = 1.0` in the class body
            setattr(cls, name, _descriptor(name, marker))
        cls.fields = tuple(fields)
        cls.defaults = defaults
        cls.dtype = np.dtype([f.marker.dtype_entry(f.name) for f in fields])
        cls.flat_codes = codes = tuple(_flat_codes(cls.dtype))
        cls.flat_format = struct.Struct("<" + "".join(codes))
        cls.flat_text_indexes = tuple(i for i, code in enumerate(codes) if code.endswith("s"))
        cls.layout_crc = zlib.crc32(f"{cls.__name__}:{cls.dtype.descr}".encode())

    def __init__(self, **values: Any) -> None:
        self._arr = type(self)._template().copy()
        for name, value in values.items():
            if not isinstance(getattr(type(self), name, None), _ScalarField):
                raise TypeError(f"{type(self).__name__} has no field '{name}'")
            setattr(self, name, value)

    @classmethod
    def _template(cls) -> np.ndarray:
        """A record holding every declared default, nested structs' defaults included."""
        template = cls.__dict__.get("_template_arr")
        if template is None:
            template = np.zeros((), cls.dtype)
            for f in cls.fields:
                marker = f.marker
                if isinstance(marker, Nested):
                    template[f.name] = marker.struct._template()
                elif isinstance(marker, Array) and not isinstance(marker.item, Scalar):
                    template[f.name][...] = marker.item._template()
            view = cls._view(template)
            for name, value in cls.defaults.items():
                setattr(view, name, value)
            cls._template_arr = template
        return template

    @classmethod
    def _view(cls, arr: np.ndarray) -> Struct:
        """An instance that reads and writes ``arr`` (a 0-d array of ``cls.dtype``) in place."""
        obj = cls.__new__(cls)
        obj._arr = arr
        return obj

    # fixed layout --------------------------------------------------------------
    @classmethod
    def fixed_size(cls) -> int:
        return cls.dtype.itemsize

    def to_bytes(self) -> bytes:
        return self._arr.tobytes()

    def byte_view(self) -> memoryview:
        """The message's fixed-layout bytes, writable in place (for copying a status in
        without allocating: ``ShmBuffer.peek_into``)."""
        return memoryview(self._arr.reshape(1).view(np.uint8))

    @classmethod
    def from_bytes(cls, data: bytes | bytearray | memoryview) -> Struct:
        """Decode the fixed layout; a writable copy, so the caller may keep and change it."""
        arr = np.frombuffer(bytearray(data), dtype=cls.dtype, count=1).reshape(())
        return cls._view(arr)

    # flat form (msgpack payload) ------------------------------------------------
    def to_flat(self) -> list[Any]:
        """Every leaf value in declaration order; texts as bytes without their NUL padding."""
        values = list(self.flat_format.unpack(self._arr.tobytes()))
        for index in self.flat_text_indexes:
            values[index] = values[index].rstrip(b"\0")
        return values

    @classmethod
    def from_flat(cls, values: list[Any] | tuple[Any, ...]) -> Struct:
        data = bytearray(cls.flat_format.pack(*values))
        return cls._view(np.frombuffer(data, dtype=cls.dtype, count=1).reshape(()))

    # python form (dump, APIs) ------------------------------------------------------
    def to_python(self) -> dict[str, Any]:
        return _to_python(type(self), self._arr)

    @classmethod
    def from_python(cls, values: dict[str, Any]) -> Struct:
        obj = cls()
        _fill(cls, obj._arr, values)
        return obj

    def copy(self) -> Struct:
        return type(self)._view(self._arr.copy())

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and self.to_bytes() == other.to_bytes()  # type: ignore[attr-defined]

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        parts = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in self.fields)
        return f"{type(self).__name__}({parts})"


_STRUCT_CODES = {
    "f8": "d",
    "f4": "f",
    "i1": "b",
    "u1": "B",
    "i4": "i",
    "u4": "I",
    "i8": "q",
    "u8": "Q",
    "b1": "?",
}


def _flat_codes(dtype: np.dtype) -> list[str]:
    """``struct`` codes of every leaf of a (packed, little-endian) dtype, in layout order."""
    if dtype.fields is not None:
        return [code for name in dtype.names for code in _flat_codes(dtype.fields[name][0])]
    if dtype.subdtype is not None:
        item, shape = dtype.subdtype
        return _flat_codes(item) * int(np.prod(shape))
    if dtype.kind == "S":
        return [f"{dtype.itemsize}s"]
    return [_STRUCT_CODES[f"{dtype.kind}{dtype.itemsize}"]]


def _descriptor(name: str, marker: Scalar | Text | Array | Nested) -> _ScalarField:
    if isinstance(marker, Text):
        return _TextField(name, marker.length)
    if isinstance(marker, Array):
        return _ArrayField(name, None if isinstance(marker.item, Scalar) else marker.item)
    if isinstance(marker, Nested):
        return _NestedField(name, marker.struct)
    return _ScalarField(name)


def _to_python(cls: type[Struct], arr: np.ndarray) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for f in cls.fields:
        value = arr[f.name]
        marker = f.marker
        if isinstance(marker, Text):
            out[f.name] = value.item().decode("utf-8", errors="replace")
        elif isinstance(marker, Nested):
            out[f.name] = _to_python(marker.struct, value)
        elif isinstance(marker, Array) and not isinstance(marker.item, Scalar):
            out[f.name] = [_to_python(marker.item, value[i, ...]) for i in range(marker.length)]
        else:
            out[f.name] = value.tolist()
    return out


def _fill(cls: type[Struct], arr: np.ndarray, values: dict[str, Any]) -> None:
    """Set fields from a dict; unknown keys are ignored, missing ones keep their value."""
    for f in cls.fields:
        if f.name not in values:
            continue
        value = values[f.name]
        marker = f.marker
        if isinstance(marker, Text):
            data = value.encode("utf-8") if isinstance(value, str) else bytes(value)
            if len(data) > marker.length:
                raise ValueError(f"{cls.__name__}.{f.name}: text longer than {marker.length}")
            arr[f.name] = data
        elif isinstance(marker, Nested):
            _fill(marker.struct, arr[f.name], value)
        elif isinstance(marker, Array) and not isinstance(marker.item, Scalar):
            target = arr[f.name]
            for index, item in enumerate(value[: marker.length]):
                _fill(marker.item, target[index, ...], item)
        elif isinstance(marker, Array):
            items = list(value)[: marker.length]
            arr[f.name][: len(items)] = items
        else:
            arr[f.name] = value


# ----------------------------------------------------------------------------- messages


# The header of every encoded message (nml/codec.py): type, payload length, layout crc, encoding
HEADER = struct.Struct("<iIII")


class MessageKind(enum.Enum):
    COMMAND = "command"
    STATUS = "status"
    OPERATOR = "operator"
    OTHER = "other"


class Receiver(enum.Enum):
    """The process that carries a command out (task routes every other one there)."""

    TASK = "task"
    MOTION = "motion"
    IO = "iocontrol"


@dataclass(frozen=True)
class Requires:
    """What a command needs of task before it is carried out: the machine state and the
    task mode (``EMC_TASK_STATE_ENUM`` / ``EMC_TASK_MODE_ENUM`` values; None: any)."""

    state: int | None = None
    mode: int | None = None


class NMLmsg(Struct):
    """Base of every message. ``TYPE`` is the NML type number, ``NAME`` its symbol.

    A command also says, beside its fields (class keywords, inherited by subclasses), what
    routing and preconditions are derived from (``nml/commands.py``):

    - ``receiver``: the process that carries it out (``Receiver``; None: nobody);
    - ``waits_for_motion``: a queue buster: in a program it goes out only once everything
      queued before it is done (``waits_for_motion()`` may decide per message), as
      LinuxCNC's task preconditions have it: the spindle never changes in the middle of a
      cut, a probe or rigid tap never blends with what came before, a tool change starts
      at rest (moves and their settings go straight into motion's queue);
    - ``requires``: the machine state and task mode it needs (``Requires``).
    """

    TYPE: ClassVar[int] = 0
    NAME: ClassVar[str] = "NMLmsg"
    KIND: ClassVar[MessageKind] = MessageKind.OTHER
    RECEIVER: ClassVar[Receiver | None] = None
    IS_QUEUE_BUSTER: ClassVar[bool] = False
    REQUIRES: ClassVar[Requires | None] = None

    def __init_subclass__(
        cls,
        type_id: int | None = None,
        kind: MessageKind | None = None,
        receiver: Receiver | None = None,
        waits_for_motion: bool | None = None,
        requires: Requires | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init_subclass__(**kwargs)
        if kind is not None:
            cls.KIND = kind
        if receiver is not None:
            cls.RECEIVER = receiver
        if waits_for_motion is not None:
            cls.IS_QUEUE_BUSTER = waits_for_motion
        if requires is not None:
            cls.REQUIRES = requires
        if type_id is not None:
            cls.TYPE = type_id
            cls.NAME = cls.__name__
            REGISTRY.register(cls)

    def waits_for_motion(self) -> bool:
        """Whether, in a program, this goes out only once all before it is done."""
        return self.IS_QUEUE_BUSTER

    @property
    def type(self) -> int:
        """The NML type number (a message with its own ``type`` field shadows this, as in C++)."""
        return self.TYPE

    @property
    def size(self) -> int:
        """Bytes of the fixed encoding, header included (LinuxCNC's NMLmsg::size)."""
        return HEADER.size + self.dtype.itemsize


class RCS_STATUS(enum.IntEnum):
    UNINITIALIZED = -1
    DONE = 1
    EXEC = 2
    ERROR = 3


class RCS_CMD_MSG(NMLmsg, kind=MessageKind.COMMAND):
    """A command; ``serial_number`` identifies it on its channel (NML-041)."""

    serial_number: i32


class RCS_STAT_MSG(NMLmsg, kind=MessageKind.STATUS):
    """A status: which command it reports on, and how that command is doing (NML-041)."""

    command_type: i32
    echo_serial_number: i32
    status: i32 = RCS_STATUS.UNINITIALIZED
    state: i32
