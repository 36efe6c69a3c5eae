"""Parameters: the numbered table and its ``.var`` file, named parameters (INTERP-013..015, 020).

Numbered parameters #1..#5601 live in one list. The persistent ones (``REQUIRED``: G28/G30
homes, G92, the nine coordinate systems) are read from and written back to the parameter file
in LinuxCNC's format by ``task.varfile`` (``<number>\\t<value>`` lines, ascending); the file
is replaced atomically and the previous version kept as ``.bak``.

Named parameters are local to a call level unless their name starts with ``_``; the
predefined ``#<_...>`` ones are read-only and computed from the interpreter state.
"""

from __future__ import annotations

import os

from task.varfile import MAX_PARAMETERS, VarFileError, read_var_file, write_var_file

from .common import rotate
from .errors import InterpError

REQUIRED = (
    list(range(5161, 5170))
    + list(range(5181, 5190))
    + list(range(5210, 5221))
    + [n for base in range(5221, 5390, 20) for n in range(base, base + 10)]
)
_REQUIRED_SET = frozenset(REQUIRED)

PA_READONLY = 1
PA_GLOBAL = 2
PA_UNSET = 4
PA_USE_LOOKUP = 8
PA_FROM_INI = 16
PA_PYTHON = 32  # computed by a function of the namedparams module (PY-026)

_PREDEFINED = [
    "_line",
    "_motion_mode",
    "_plane",
    "_ccomp",
    "_metric",
    "_imperial",
    "_absolute",
    "_incremental",
    "_inverse_time",
    "_units_per_minute",
    "_units_per_rev",
    "_coord_system",
    "_tool_offset",
    "_retract_r_plane",
    "_retract_old_z",
    "_spindle_rpm_mode",
    "_spindle_css_mode",
    "_ijk_absolute_mode",
    "_lathe_diameter_mode",
    "_lathe_radius_mode",
    "_spindle_on",
    "_spindle_cw",
    "_mist",
    "_flood",
    "_speed_override",
    "_feed_override",
    "_adaptive_feed",
    "_feed_hold",
    "_feed",
    "_rpm",
    "_current_tool",
    "_current_pocket",
    "_selected_pocket",
    "_selected_tool",
    "_x",
    "_y",
    "_z",
    "_a",
    "_b",
    "_c",
    "_u",
    "_v",
    "_w",
    "_abs_x",
    "_abs_y",
    "_abs_z",
    "_abs_a",
    "_abs_b",
    "_abs_c",
    "_abs_u",
    "_abs_v",
    "_abs_w",
    "_value",
    "_value_returned",
    "_task",
    "_call_level",
    "_remap_level",
]


class ParamsMixin:
    """Parameter storage; mixed into the Interpreter."""

    def abs_position(self) -> list[float]:
        """The controlled point in machine coordinates (no G5x, G92/G52, rotation or tool
        offset), in program units: #5021-#5029 and #<_abs_x>..#<_abs_w> (LinuxCNC 2.9.10)."""
        cur, axis, origin, tool = (
            self.current,
            self.axis_offset,
            self.origin_offset,
            self.tool_offset,
        )
        # (read on every line: one pass over the axes; X and Y again only under rotation)
        position = [c + a + o + t for c, a, o, t in zip(cur, axis, origin, tool, strict=True)]
        if self.rotation_xy:
            x, y = rotate(cur[0] + axis[0], cur[1] + axis[1], self.rotation_xy)
            position[0] = x + origin[0] + tool[0]
            position[1] = y + origin[1] + tool[1]
        return position

    # ------------------------------------------------------------- var files
    def restore_parameters(self, filename: str) -> None:
        """Read the ``.var`` file as LinuxCNC does (``task.varfile``, lenient: the
        controller checks the file strictly before task starts); a missing file is none."""
        if not os.path.exists(filename):
            return
        try:
            found = read_var_file(filename, strict=False)
        except VarFileError as error:
            if error.line == 0:
                raise InterpError(f"Unable to open parameter file: '{filename}'") from None
            raise InterpError(error.cause) from None
        pars = self.parameters
        pars[:] = [0.0] * MAX_PARAMETERS
        for number, value in found.items():
            pars[number] = value

    def save_parameters(self, filename: str) -> None:
        """Write the parameters the file lists, and the persistent ones (``REQUIRED``), in
        LinuxCNC's format, atomically, keeping the previous file as ``.bak``. Never raises,
        as LinuxCNC's: ``save_error`` says why nothing was saved (rs274 says nothing, task
        tells the operator) when the file on disk cannot be read (it is then left as it
        is), a value is not finite (nan is never written), or the file cannot be written."""
        self.save_error: Exception | None = None
        try:
            listed = read_var_file(filename, strict=False) if os.path.exists(filename) else {}
        except VarFileError as error:
            self.save_error = error
            return
        pars = self.parameters
        numbers = sorted(_REQUIRED_SET.union(listed))
        existed = os.path.exists(filename)
        try:
            write_var_file(filename, {number: pars[number] for number in numbers})
        except (VarFileError, OSError) as error:
            self.save_error = error
            return
        if not existed:
            # LinuxCNC links the old file to .bak before the rename and reports the failure
            self.report("link (updating variable file): No such file or directory\n")

    # -------------------------------------------------------- named params
    def init_named_parameters(self) -> None:
        globals_ = self.sub_context[0].named_params
        globals_["_vmajor"] = [2.9, PA_READONLY | PA_GLOBAL]
        globals_["_vminor"] = [0.0, PA_READONLY | PA_GLOBAL]
        globals_["_metric_machine"] = [self._inicheck(), PA_READONLY | PA_GLOBAL]
        for name in _PREDEFINED:
            globals_[name] = [0.0, PA_READONLY | PA_GLOBAL | PA_USE_LOOKUP]

    def _inicheck(self) -> float:
        if self.ini is None:
            return -1.0
        units = self.ini.find("TRAJ", "LINEAR_UNITS")
        if units is None:
            return -1.0
        return 0.0 if units == "inch" else 1.0

    def find_named_param(self, name: str) -> tuple[bool, float]:
        level = 0 if name.startswith("_") else self.call_level
        params = self.sub_context[level].named_params
        entry = params.get(name)
        if entry is None:
            lower = name.lower()
            if self.ini is not None and self.feature_ini_vars and lower.startswith("_ini["):
                value = self._fetch_ini_param(name)
                if value is not None:
                    self.sub_context[0].named_params[name] = [
                        value,
                        PA_GLOBAL | PA_READONLY | PA_FROM_INI,
                    ]
                    return True, value
            # #<_hal[pin, signal or parameter]>: a failed lookup leaves the parameter
            # undefined (LinuxCNC drops the lookup's error); rs274 has no HAL at all
            if self.hal is not None and self.feature_hal_pin_vars and lower.startswith("_hal["):
                close = name.find("]", 5)
                if len(name) > 6 and close >= 0 and close + 1 == len(name):
                    value = self.hal(name[5:close])
                    if value is not None:
                        return True, float(value)
            return False, 0.0
        if entry[1] & (PA_USE_LOOKUP | PA_PYTHON):
            if entry[1] & PA_USE_LOOKUP:
                return True, self.lookup_named_param(name)
            return True, self.python_named_param(name)
        return True, entry[0]

    def param_name(self, name: str) -> str:
        """A parameter name given by Python code, as the reader spells it."""
        return name if self.feature_no_downcase_oword else name.lower()

    def _fetch_ini_param(self, name: str) -> float | None:
        close = name.find("]", 6)
        if len(name) <= 7 or close < 0:
            return None
        cap = name.upper()
        section = cap[5:close]
        key = cap[close + 1 :]
        value = self.ini.find(section, key)
        # a missing or non-numeric entry makes the parameter undefined: LinuxCNC's lookup
        # reports an error that its caller drops
        if value is None:
            return None
        try:
            return float(value.split()[0])
        except (ValueError, IndexError):
            return None

    def add_named_param(self, name: str, attr: int = 0) -> None:
        exists, _ = self.find_named_param(name)
        if exists:
            return
        attr |= PA_UNSET
        if name.startswith("_"):
            level = 0
            attr |= PA_GLOBAL
        else:
            level = self.call_level
        self.sub_context[level].named_params[name] = [0.0, attr]

    def store_named_param(self, name: str, value: float, override_readonly: bool = False) -> None:
        level = 0 if name.startswith("_") else self.call_level
        entry = self.sub_context[level].named_params.get(name)
        if entry is None:
            raise InterpError(f"Internal error: Could not assign #<{name}>")
        if entry[1] & PA_READONLY and not override_readonly:
            raise InterpError(f"Cannot assign to read-only parameter #<{name}>")
        entry[0] = value
        entry[1] &= ~PA_UNSET

    def lookup_named_param(self, name: str) -> float:
        s = self
        cur = s.current
        if name == "_line":
            return float(s.sequence_number)
        if name == "_motion_mode":
            return float(s.motion_mode)
        if name == "_plane":
            return {1: 170.0, 3: 180.0, 2: 190.0, 4: 171.0, 6: 181.0, 5: 191.0}.get(s.plane, 0.0)
        if name == "_ccomp":
            return 420.0 if s.cutter_comp_side == 1 else 410.0 if s.cutter_comp_side == 2 else 400.0
        if name == "_metric":
            return float(s.length_units == 2)
        if name == "_imperial":
            return float(s.length_units == 1)
        if name == "_absolute":
            return float(s.distance_mode == 0)
        if name == "_incremental":
            return float(s.distance_mode == 1)
        if name == "_inverse_time":
            return float(s.feed_mode == 1)
        if name == "_units_per_minute":
            return float(s.feed_mode == 0)
        if name == "_units_per_rev":
            return float(s.feed_mode == 2)
        if name == "_coord_system":
            o = s.origin_index
            return float(530 + 10 * o if o < 7 else 584 + o)
        if name == "_tool_offset":
            return float(any(s.tool_offset))
        if name == "_retract_r_plane":
            return float(s.retract_mode == 0)
        if name == "_retract_old_z":
            return float(s.retract_mode == 1)
        if name == "_spindle_rpm_mode":
            return float(s.spindle_mode[0] == 0)
        if name == "_spindle_css_mode":
            return float(s.spindle_mode[0] == 1)
        if name == "_ijk_absolute_mode":
            return float(s.ijk_distance_mode == 0)
        if name == "_lathe_diameter_mode":
            return float(bool(s.lathe_diameter_mode))
        if name == "_lathe_radius_mode":
            return float(not s.lathe_diameter_mode)
        if name == "_spindle_on":
            return float(s.spindle_turning[0] != 1)
        if name == "_spindle_cw":
            return float(s.spindle_turning[0] == 2)
        if name == "_mist":
            return float(s.mist)
        if name == "_flood":
            return float(s.flood)
        if name == "_speed_override":
            return float(s.speed_override[0])
        if name == "_feed_override":
            return float(s.feed_override)
        if name == "_adaptive_feed":
            return float(s.adaptive_feed)
        if name == "_feed_hold":
            return float(s.feed_hold)
        if name == "_feed":
            return float(s.feed_rate)
        if name == "_rpm":
            return float(abs(int(s.speed[0])))
        if name == "_current_tool":
            return s.parameters[5400]
        if name == "_selected_pocket":
            if s.random_toolchanger:
                return float(s.selected_pocket)
            pocket = s.tool_table[s.selected_pocket].pocketno
            return -1.0 if pocket == 0 else float(pocket)
        if name == "_current_pocket":
            if s.current_pocket == -1:
                return -1.0
            if s.random_toolchanger:
                return float(s.current_pocket)
            return float(s.tool_table[s.current_pocket].pocketno)
        if name == "_selected_tool":
            return float(s.selected_tool)
        axes = {"_x": 0, "_y": 1, "_z": 2, "_a": 3, "_b": 4, "_c": 5, "_u": 6, "_v": 7, "_w": 8}
        if name in axes:
            return cur[axes[name]]
        abs_axes = {
            "_abs_x": 0, "_abs_y": 1, "_abs_z": 2, "_abs_a": 3, "_abs_b": 4,
            "_abs_c": 5, "_abs_u": 6, "_abs_v": 7, "_abs_w": 8,
        }  # fmt: skip
        if name in abs_axes:
            return self.abs_position()[abs_axes[name]]
        if name == "_value":
            return s.return_value
        if name == "_value_returned":
            return float(s.value_returned)
        if name == "_call_level":
            return float(s.call_level)
        if name == "_remap_level":
            return float(s.remap_level)
        if name == "_task":
            return float(s.task)
        raise InterpError(f"BUG: lookup_named_param({name}): unhandled index")
