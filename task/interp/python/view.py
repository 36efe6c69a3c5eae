"""The interpreter as Python code sees it: ``self`` of every handler (PY-008, PY-009, PY-020).

``InterpView`` gives LinuxCNC's names and types (``current_x``, ``tool_offset.z``,
``params["name"]``, ``blocks[remap_level].x_flag``, ``tool_table[0].toolno`` ...) over our
interpreter's state, so handlers written for LinuxCNC run unchanged. Attributes a handler adds
(``self.sticky_params = {}``) stay on the view from call to call, apart from the
interpreter's own state.
"""

from __future__ import annotations

from nml.pose import AXIS_NAMES, Pose

from ..params import PA_GLOBAL, PA_READONLY
from ..reader import RS274NGC_MAX_PARAMETERS

# view attribute -> interpreter attribute, read and written as they are
_SAME = (
    "a_axis_wrapped",
    "a_indexer_jnum",
    "active_spindle",
    "arc_not_allowed",
    "b_axis_wrapped",
    "b_indexer_jnum",
    "c_axis_wrapped",
    "c_indexer_jnum",
    "call_level",
    "call_state",
    "current_pocket",
    "cutter_comp_firstmove",
    "cutter_comp_orientation",
    "cutter_comp_radius",
    "cutter_comp_side",
    "cycle_cc",
    "cycle_i",
    "cycle_il",
    "cycle_il_flag",
    "cycle_j",
    "cycle_k",
    "cycle_l",
    "cycle_p",
    "cycle_q",
    "cycle_r",
    "debugmask",
    "distance_mode",
    "feed_mode",
    "feed_override",
    "feed_rate",
    "flood",
    "ijk_distance_mode",
    "input_digital",
    "input_flag",
    "input_index",
    "length_units",
    "mdi_interrupt",
    "mist",
    "motion_mode",
    "num_spindles",
    "origin_index",
    "percent_flag",
    "plane",
    "probe_flag",
    "program_x",
    "program_y",
    "program_z",
    "random_toolchanger",
    "remap_level",
    "retract_mode",
    "return_value",
    "rotation_xy",
    "selected_pocket",
    "selected_tool",
    "sequence_number",
    "speed",
    "speed_feed_mode",
    "speed_override",
    "spindle_mode",
    "spindle_turning",
    "tool_change_at_g30",
    "tool_change_quill_up",
    "tool_change_with_spindle_on",
    "toolchange_flag",
    "traverse_rate",
    "value_returned",
)
# other names of the same state: LinuxCNC's documentation and stdglue write
# ``tool_change_flag`` (which forces a synch here, as they mean it to)
_ALIASES = {"tool_change_flag": "toolchange_flag", "loggingLevel": "log_level"}
# view attribute -> (interpreter list attribute, index): positions and offsets by axis
_ITEMS: dict[str, tuple[str, int]] = {}
for _k, _axis in enumerate(AXIS_NAMES):
    if _k < 3:
        _names_of = (f"current_{_axis}", f"axis_offset_{_axis}", f"origin_offset_{_axis}")
    else:
        _prefix = _axis.upper() * 2 if _k < 6 else _axis  # AA_current ... u_current
        _names_of = (f"{_prefix}_current", f"{_prefix}_axis_offset", f"{_prefix}_origin_offset")
    for _attr, _name in zip(("current", "axis_offset", "origin_offset"), _names_of, strict=True):
        _ITEMS[_name] = (_attr, _k)


class InterpView:
    """``self`` of Python handlers, O-word procedures and named-parameter functions."""

    def __init__(self, interp) -> None:
        object.__setattr__(self, "_interp", interp)

    def __getattr__(self, name: str):
        interp = self._interp
        if name in _SAME_SET:
            return getattr(interp, name)
        target = _ALIASES.get(name)
        if target is not None:
            return getattr(interp, target)
        item = _ITEMS.get(name)
        if item is not None:
            return getattr(interp, item[0])[item[1]]
        raise AttributeError(f"'interpreter' has no attribute '{name}'")

    def __setattr__(self, name: str, value) -> None:
        interp = self._interp
        if name in _SAME_SET:
            setattr(interp, name, value)
        elif name in _ALIASES:
            setattr(interp, _ALIASES[name], value)
        elif name in _ITEMS:
            attr, index = _ITEMS[name]
            getattr(interp, attr)[index] = float(value)
        elif name in _READ_ONLY:
            raise AttributeError(f"interpreter attribute '{name}' is read-only")
        else:
            object.__setattr__(self, name, value)  # the handler's own attribute

    # --------------------------------------------------------------- read-only
    @property
    def task(self) -> int:
        return self._interp.task

    @property
    def filename(self) -> str:
        return self._interp.filename

    @property
    def linetext(self) -> str:
        return self._interp.linetext

    @property
    def stack_index(self) -> int:
        return len(self._interp.error_stack_names())

    # ----------------------------------------------------------------- objects
    @property
    def params(self) -> Params:
        return Params(self._interp)

    @property
    def parameters(self) -> list[float]:
        return self._interp.parameters

    @property
    def blocks(self) -> Blocks:
        return Blocks(self._interp)

    @property
    def tool_table(self) -> ToolTable:
        return ToolTable(self._interp)

    @property
    def sub_context(self) -> list[ContextView]:
        return [ContextView(self._interp, frame) for frame in self._interp.sub_context]

    @property
    def current_tool(self) -> int:
        return self._interp.tool_table[0].toolno

    @current_tool.setter
    def current_tool(self, value: int) -> None:
        table = self._interp.tool_table
        entry = table[0]
        entry.toolno = int(value)
        table.set(0, entry)

    @property
    def tool_offset(self) -> EmcPose:
        def store(values: list[float]) -> None:
            self._interp.tool_offset = values

        return EmcPose(self._interp.tool_offset, store)

    @tool_offset.setter
    def tool_offset(self, value) -> None:
        self._interp.tool_offset = EmcPose.values_of(value)

    @property
    def active_g_codes(self) -> list[int]:
        return self._interp.active_g_codes()

    @property
    def active_m_codes(self) -> list[int]:
        return self._interp.active_m_codes()

    @property
    def active_settings(self) -> list[float]:
        return self._interp.active_settings()

    # ----------------------------------------------------------------- methods
    def execute(self, command: str, line_number: int | None = None) -> int:
        """Execute NGC code now (PY-018, PY-021, PY-022)."""
        return self._interp.python_execute(command, line_number)

    def read(self, command: str) -> int:
        return self._interp.python_read(command)

    def find_tool_pocket(self, toolno: int) -> tuple[int, int]:
        return self._interp.find_tool_pocket(int(toolno))

    def load_tool_table(self) -> int:
        self._interp.load_tool_table()
        return 0

    def set_tool_parameters(self) -> int:
        self._interp.set_tool_parameters()
        return 0

    def synch(self) -> int:
        return self._interp.synch()

    def set_errormsg(self, text: str) -> None:
        """The message of the INTERP_ERROR a handler returns next (the old convention)."""
        self._interp.saved_error = text or "###"

    def get_errormsg(self) -> str:
        return self._interp.saved_error

    def stack(self) -> list[str]:
        return self._interp.error_stack_names()


_SAME_SET = frozenset(_SAME)
_READ_ONLY = frozenset(("task", "filename", "linetext", "stack_index"))


class Params:
    """``self.params``: numbered (int) and named (str) parameters (PY-020)."""

    def __init__(self, interp) -> None:
        self._interp = interp

    def __getitem__(self, key) -> float:
        if isinstance(key, str):
            exists, value = self._interp.find_named_param(self._interp.param_name(key))
            if not exists:
                raise RuntimeError(f"parameter does not exist: {key}")
            return value
        if isinstance(key, int):
            return self._interp.parameters[key]
        raise RuntimeError("params subscript type must be integer or string")

    def __setitem__(self, key, value: float) -> None:
        interp = self._interp
        if isinstance(key, str):
            name = interp.param_name(key)
            interp.add_named_param(name, PA_GLOBAL if name.startswith("_") else 0)
            try:
                interp.store_named_param(name, float(value))
            except Exception:
                raise RuntimeError(f"can't assign value to parameter: {key}") from None
        elif isinstance(key, int):
            if key < 0 or key > RS274NGC_MAX_PARAMETERS - 1:
                raise RuntimeError(
                    f"params subscript out of range : {key} - must be between 0 and "
                    f"{RS274NGC_MAX_PARAMETERS}"
                )
            interp.parameters[key] = float(value)
        else:
            raise RuntimeError("params subscript type must be integer or string")

    def __len__(self) -> int:
        return RS274NGC_MAX_PARAMETERS

    def __contains__(self, key) -> bool:
        if isinstance(key, str):
            return self._interp.find_named_param(self._interp.param_name(key))[0]
        return isinstance(key, int) and 0 <= key < RS274NGC_MAX_PARAMETERS

    def locals(self) -> list[str]:
        return _names(self._interp.sub_context[self._interp.call_level].named_params)

    def globals(self) -> list[str]:
        return _names(self._interp.sub_context[0].named_params)

    def __call__(self) -> list[str]:
        return self.locals() + self.globals()


def _names(params: dict) -> list[str]:
    """Names in LinuxCNC's order (its map compares them case-insensitively)."""
    return sorted(params, key=str.lower)


class Blocks:
    """``self.blocks``: [0] the block being executed, [n] the block whose remapped code
    runs at remap level n."""

    def __init__(self, interp) -> None:
        self._interp = interp

    def __getitem__(self, level: int):
        if level == 0:
            return self._interp.block
        block = self._interp.remap_blocks[level]
        if block is None:
            from ..block import Block

            return Block()
        return block

    def __len__(self) -> int:
        return len(self._interp.remap_blocks)


class EmcPose(Pose):
    """LinuxCNC's Python view of a pose (``self.tool_offset``, a tool's ``offset``): a
    ``nml.pose.Pose`` that also reads as LinuxCNC's struct (``tran.x``) and hands every
    change to ``store`` (the nine values), so a handler's write reaches the interpreter."""

    __slots__ = ("_store",)

    def __init__(self, values, store=None) -> None:
        object.__setattr__(self, "_store", None)  # (the fields are set first)
        super().__init__(*(float(v) for v in values))
        object.__setattr__(self, "_store", store)

    @staticmethod
    def values_of(value) -> list[float]:
        return [float(v) for v in value]

    def as_list(self) -> list[float]:
        return list(self.as_tuple())

    @property
    def tran(self) -> EmcPose:
        return self

    def __setattr__(self, name: str, value: float) -> None:
        if len(name) != 1 or name not in AXIS_NAMES:
            raise AttributeError(name)
        object.__setattr__(self, name, float(value))
        if self._store is not None:
            self._store(self.as_list())

    def zero(self) -> None:
        for axis in AXIS_NAMES:
            setattr(self, axis, 0.0)

    def __str__(self) -> str:
        text = " ".join(f"{a}={v:.4f}" for a, v in zip(AXIS_NAMES, self, strict=True))
        return f"EmcPose({text})"


class ToolView:
    """A tool table entry with LinuxCNC's names; ``offset`` is an EmcPose."""

    _FIELDS = ("toolno", "pocketno", "diameter", "frontangle", "backangle", "orientation")

    def __init__(self, entry, store=None) -> None:
        object.__setattr__(self, "_entry", entry)
        object.__setattr__(self, "_store", store)

    def __getattr__(self, name: str):
        if name == "offset":

            def store(values: list[float]) -> None:
                self._entry.offset = values
                if self._store is not None:
                    self._store(self._entry)

            return EmcPose(self._entry.offset, store)
        if name in self._FIELDS or name == "comment":
            return getattr(self._entry, name)
        raise AttributeError(name)

    def __setattr__(self, name: str, value) -> None:
        if name == "offset":
            self._entry.offset = EmcPose.values_of(value)
        elif name in self._FIELDS:
            setattr(self._entry, name, type(getattr(self._entry, name))(value))
        else:
            raise AttributeError(name)
        if self._store is not None:
            self._store(self._entry)

    def zero(self) -> None:
        self._entry.toolno = -1
        self._entry.offset = [0.0] * 9
        for name in ("diameter", "frontangle", "backangle"):
            setattr(self._entry, name, 0.0)
        self._entry.orientation = 0
        if self._store is not None:
            self._store(self._entry)

    def __str__(self) -> str:
        e = self._entry
        offset = " ".join(f"{a}={v:.4f}" for a, v in zip(AXIS_NAMES, e.offset, strict=True))
        return (
            f"Tool(T{e.toolno} D{e.diameter:.4f} I{e.frontangle:.4f} J{e.backangle:.4f} "
            f"Q{e.orientation} offset: {offset})"
        )


class ToolTable:
    """``self.tool_table``: the interpreter's copy of the tool table; entries write back."""

    def __init__(self, interp) -> None:
        self._table = interp.tool_table

    def __getitem__(self, index: int) -> ToolView:
        table = self._table
        return ToolView(table[index], lambda entry: table.set(index, entry))

    def __setitem__(self, index: int, value: ToolView) -> None:
        self._table.set(index, value._entry.copy())


class ParameterValue:
    """A named parameter's entry: ``value`` and ``attr`` (LinuxCNC's PA_* bits)."""

    def __init__(self, entry: list) -> None:
        self._entry = entry

    @property
    def value(self) -> float:
        return self._entry[0]

    @value.setter
    def value(self, value: float) -> None:
        self._entry[0] = float(value)

    @property
    def attr(self) -> int:
        return self._entry[1]

    @attr.setter
    def attr(self, value: int) -> None:
        self._entry[1] = int(value)


class _MapItem:
    """An item of a ``named_params`` map, as LinuxCNC's map iterates: key() and data()."""

    def __init__(self, name: str, entry: list) -> None:
        self._name = name
        self._entry = entry

    def key(self) -> str:
        return self._name

    def data(self) -> ParameterValue:
        return ParameterValue(self._entry)


class NamedParams:
    """A call frame's named parameters: ``[name]`` gives a ParameterValue."""

    def __init__(self, params: dict) -> None:
        self._params = params

    def __getitem__(self, name: str) -> ParameterValue:
        entry = self._params.get(name.lower())
        if entry is None:
            raise KeyError(name)
        return ParameterValue(entry)

    def __contains__(self, name: str) -> bool:
        return name.lower() in self._params

    def __len__(self) -> int:
        return len(self._params)

    def __iter__(self):
        for name in _names(self._params):
            yield _MapItem(name, self._params[name])


class ContextView:
    """A call frame (``self.sub_context[n]``)."""

    def __init__(self, interp, frame) -> None:
        self._interp = interp
        self._frame = frame

    @property
    def position(self) -> int:
        return self._frame.position

    @property
    def sequence_number(self) -> int:
        return self._frame.sequence_number

    @property
    def filename(self) -> str:
        return self._frame.filename

    @property
    def subname(self) -> str | None:
        return self._frame.subName

    @property
    def call_type(self) -> int:
        return self._frame.call_type

    @property
    def context_status(self) -> int:
        return self._frame.context_status

    @property
    def saved_params(self) -> list[float]:
        return list(self._frame.saved_params)

    @property
    def saved_g_codes(self) -> list[int]:
        return list(self._frame.saved_g_codes)

    @property
    def saved_m_codes(self) -> list[int]:
        return list(self._frame.saved_m_codes)

    @property
    def saved_settings(self) -> list[float]:
        return list(self._frame.saved_settings)

    @property
    def named_params(self) -> NamedParams:
        return NamedParams(self._frame.named_params)


__all__ = ["PA_READONLY", "EmcPose", "InterpView", "Params", "ToolView"]
