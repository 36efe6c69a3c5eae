"""LinuxCNC's error stack, for ``rs274 -s`` (``cnc rs274 -s``).

On an error, LinuxCNC's interpreter remembers the functions the error passed through, the
innermost first, as ``__PRETTY_FUNCTION__`` strings; ``rs274 -s`` prints them after the
error text and the line, at most 79 characters each. Ours are worked out from the Python
traceback: each of our functions stands for the LinuxCNC functions that do the same step
(``_frame_functions``); helpers of ours that LinuxCNC does not have stand for none. Reading
follows LinuxCNC's reader closely, so its stacks are the same; execution stacks name the
convert functions both share. (With ``-s``, lines are always read by the interpreting
reader, never by compiled values or line plans, so that the traceback has the reader's
shape: see ``Interpreter.record_error_stack``.)

The parameter lists are those rs274 2.9 prints (where it cuts them at 79 characters, the
part it prints).
"""

from __future__ import annotations

from types import TracebackType

NAME_LENGTH = 79  # stack_name() fills an 80-character buffer
_PACKAGE = __name__.rpartition(".")[0] + "."  # our frames: those of this package's modules

# LinuxCNC function -> its parameter list as __PRETTY_FUNCTION__ prints it
SIGNATURES = {
    "_execute": "const char*",
    "_read": "const char*",
    "arc_data_ijk": "int, int, double, double, double, double, int, double,",
    "arc_data_r": "int, int, double, double, double, double, double, int, d",
    "check_g_codes": "block_pointer, setup_pointer",
    "check_items": "block_pointer, setup_pointer",
    "check_m_codes": "block_pointer",
    "check_other_codes": "block_pointer",
    "close_and_downcase": "char*",
    "control_save_offset": "block_pointer, setup_pointer",
    "convert_arc": "int, block_pointer, setup_pointer",
    "convert_arc2": "int, block_pointer, setup_pointer, double*, double*, d",
    "convert_control_functions": "block_pointer, setup_pointer",
    "convert_control_mode": "int, double, double, setup_pointer",
    "convert_cutter_compensation": "int, block_pointer, setup_pointer",
    "convert_cutter_compensation_on": "int, block_pointer, setup_pointer",
    "convert_cycle": "int, block_pointer, setup_pointer",
    "convert_cycle_g74_g84": "block_pointer, CANON_PLANE, double, double, d",
    "convert_cycle_g73": "block_pointer, CANON_PLANE, double, double, doubl",
    "convert_cycle_g83": "block_pointer, CANON_PLANE, double, double, doubl",
    "convert_cycle_g86": "block_pointer, CANON_PLANE, double, double, doubl",
    "convert_cycle_g87": "block_pointer, CANON_PLANE, double, double, doubl",
    "convert_cycle_g88": "block_pointer, CANON_PLANE, double, double, doubl",
    "convert_cycle_xy": "int, block_pointer, setup_pointer",
    "convert_cycle_yz": "int, block_pointer, setup_pointer",
    "convert_cycle_zx": "int, block_pointer, setup_pointer",
    "convert_cycle_uv": "int, block_pointer, setup_pointer",
    "convert_cycle_vw": "int, block_pointer, setup_pointer",
    "convert_cycle_wu": "int, block_pointer, setup_pointer",
    "convert_g": "block_pointer, setup_pointer",
    "convert_g7x": "int, block_pointer, setup_pointer",
    "convert_home": "int, block_pointer, setup_pointer",
    "convert_m": "block_pointer, setup_pointer",
    "convert_modal_0": "int, block_pointer, setup_pointer",
    "convert_motion": "int, block_pointer, setup_pointer",
    "convert_nurbs": "int, block_pointer, setup_pointer",
    "convert_probe": "block_pointer, int, setup_pointer",
    "convert_set_plane": "int, setup_pointer",
    "convert_setup": "block_pointer, setup_pointer",
    "convert_setup_tool": "block_pointer, setup_pointer",
    "convert_spline": "int, block_pointer, setup_pointer",
    "convert_straight": "int, block_pointer, setup_pointer",
    "convert_straight_comp1": "int, block_pointer, setup_pointer, double, d",
    "convert_straight_comp2": "int, block_pointer, setup_pointer, double, d",
    "convert_threading_cycle": "block_pointer, setup_pointer, double, doubl",
    "convert_tool_change": "setup_pointer",
    "convert_tool_length_offset": "int, block_pointer, setup_pointer",
    "convert_tool_select": "block_pointer, setup_pointer",
    "enhance_block": "block_pointer, setup_pointer",
    "enter_context": "setup_pointer, block_pointer",
    "execute_binary": "double*, int, double*",
    "execute_binary1": "double*, int, double*",
    "execute_binary2": "double*, int, double*",
    "execute_block": "block_pointer, setup_pointer",
    "execute_unary": "double*, int",
    "find_ends": "block_pointer, setup_pointer, double*, double*, double*, d",
    "find_tool_index": "setup_pointer, int, int*",
    "move_endpoint_and_flush": "setup_pointer, double, double",
    "parse_line": "char*, block_pointer, setup_pointer",
    "read_a": "char*, int*, block_pointer, double*",
    "read_atan": "char*, int*, double*, double*",
    "read_b": "char*, int*, block_pointer, double*",
    "read_bracketed_parameter": "char*, int*, double*, double*, bool",
    "read_c": "char*, int*, block_pointer, double*",
    "read_d": "char*, int*, block_pointer, double*",
    "read_dollar": "char*, int*, block_pointer, double*",
    "read_e": "char*, int*, block_pointer, double*",
    "read_f": "char*, int*, block_pointer, double*",
    "read_g": "char*, int*, block_pointer, double*",
    "read_h": "char*, int*, block_pointer, double*",
    "read_i": "char*, int*, block_pointer, double*",
    "read_integer_unsigned": "char*, int*, int*",
    "read_integer_value": "char*, int*, int*, double*",
    "read_items": "block_pointer, char*, double*",
    "read_j": "char*, int*, block_pointer, double*",
    "read_k": "char*, int*, block_pointer, double*",
    "read_l": "char*, int*, block_pointer, double*",
    "read_m": "char*, int*, block_pointer, double*",
    "read_n_number": "char*, int*, block_pointer",
    "read_name": "char*, int*, char*",
    "read_named_parameter": "char*, int*, double*, double*, bool",
    "read_named_parameter_setting": "char*, int*, char**, double*",
    "read_o": "char*, int*, block_pointer, double*",
    "read_one_item": "char*, int*, block_pointer, double*",
    "read_operation": "char*, int*, int*",
    "read_operation_unary": "char*, int*, int*",
    "read_p": "char*, int*, block_pointer, double*",
    "read_parameter": "char*, int*, double*, double*, bool",
    "read_parameter_setting": "char*, int*, block_pointer, double*",
    "read_q": "char*, int*, block_pointer, double*",
    "read_r": "char*, int*, block_pointer, double*",
    "read_real_expression": "char*, int*, double*, double*",
    "read_real_number": "char*, int*, double*",
    "read_real_value": "char*, int*, double*, double*",
    "read_s": "char*, int*, block_pointer, double*",
    "read_t": "char*, int*, block_pointer, double*",
    "read_text": "const char*, FILE*, char*, char*, int*",
    "read_unary": "char*, int*, double*, double*",
    "read_x": "char*, int*, block_pointer, double*",
    "read_y": "char*, int*, block_pointer, double*",
    "read_z": "char*, int*, block_pointer, double*",
    "restore_parameters": "const char*",
    "store_named_param": "setup_pointer, const char*, double, int",
}

_READ_ONE_ITEM = "read_one_item"
# our word readers, each one of LinuxCNC's read_<letter> called through read_one_item
_ITEM_READERS = frozenset(
    name
    for name in SIGNATURES
    if name.startswith("read_") and SIGNATURES[name] == "char*, int*, block_pointer, double*"
) - {"read_one_item", "read_o"}
# our functions that are a different LinuxCNC function (or several, innermost first)
ALIASES = {
    "_execute_unary": ("execute_unary",),
    "_read_operation_unary": ("read_operation_unary",),
    "read_o_body": (),  # part of read_o
    "read_expression_cached": (),  # read_real_expression's cache
}
_BINARY1 = frozenset((1, 2, 3, 4))  # DIVIDED_BY, MODULO, POWER, TIMES: execute_binary1
# canned cycles by plane (canon.PLANE_XY, _YZ, _XZ, _UV, _VW, _UW)
_CYCLE_PLANES = {
    1: "convert_cycle_xy",
    2: "convert_cycle_yz",
    3: "convert_cycle_zx",
    4: "convert_cycle_uv",
    5: "convert_cycle_vw",
    6: "convert_cycle_wu",
}
# the interface functions (virtual in LinuxCNC), by the name of ours that does the work
_INTERFACE = {
    "_open": "virtual int Interp::open(const char*)",
    "_init": "virtual int Interp::init()",
}
# the canned cycle of one_cycle (cycles.py) by its G code (x 10)
_CYCLES = {
    730: "convert_cycle_g73",
    740: "convert_cycle_g74_g84",
    830: "convert_cycle_g83",
    840: "convert_cycle_g74_g84",
    860: "convert_cycle_g86",
    870: "convert_cycle_g87",
    880: "convert_cycle_g88",
}
# errors our functions raise that LinuxCNC raises one call deeper
_DEEPER = (
    ("read_items", "Bad character", "read_one_item"),
    ("check_items", "Too many m codes", "check_m_codes"),
    ("read_unary", "Expected", "read_bracketed_parameter"),
    ("read_unary", "Slash missing after first atan", "read_atan"),
    ("read_unary", "Left bracket missing after slash with atan", "read_atan"),
)


# the few that do not return int
FULL_NAMES = {
    "check_g74_g84_spindle": "InterpReturn Interp::check_g74_g84_spindle(GCodes, CANON_DIRECTION)",
}


def pretty(function: str) -> str:
    """A LinuxCNC function's name as the error stack holds it."""
    name = FULL_NAMES.get(function) or f"int Interp::{function}({SIGNATURES[function]})"
    return name[:NAME_LENGTH]


def _frame_functions(
    code_name: str, local: dict, message: str, is_innermost: bool
) -> tuple[str, ...]:
    """The LinuxCNC functions one of our frames stands for, innermost first
    (``is_innermost``: the error was raised in this frame)."""
    if code_name == "_read_one_item":  # the word readers it calls count read_one_item
        return ("read_one_item",) if is_innermost else ()
    if code_name == "reader":  # a word reader made by ReaderMixin._word_reader
        return (f"read_{local['flag'][0]}", _READ_ONE_ITEM)
    if code_name == "read_parameter" and _is_named(local):
        return ("read_named_parameter", "read_parameter")
    if code_name == "read_parameter_setting" and "name" not in local and _is_named(local):
        # LinuxCNC reads the name of a #<name> = setting in a function of its own
        return ("read_named_parameter_setting", code_name, _READ_ONE_ITEM)
    if code_name in _ITEM_READERS:
        return (code_name, _READ_ONE_ITEM)
    if code_name == "_execute_binary":
        first = "execute_binary1" if local.get("operation") in _BINARY1 else "execute_binary2"
        return (first, "execute_binary")
    if code_name == "one_cycle":
        return (_CYCLES.get(local.get("motion"), ""),)
    if code_name == "_cycle_tap" and "Spindle" in message:
        return ("check_g74_g84_spindle",)
    if code_name == "convert_straight" and local.get("move") == 760 and not is_innermost:
        return ()  # LinuxCNC goes from convert_motion to convert_threading_cycle
    if code_name == "_convert_cycle_plane":
        return (_CYCLE_PLANES.get(local.get("plane"), ""),)
    for ours, start, deeper in _DEEPER:
        if is_innermost and code_name == ours and message.startswith(start):
            return (deeper, *_frame_functions(code_name, {}, "", False))
    if code_name in ALIASES:
        return ALIASES[code_name]
    if code_name in SIGNATURES:
        return (code_name,)
    return ()


def _is_named(local: dict) -> bool:
    """Whether a parameter reader's frame reads ``#<name>`` (LinuxCNC has a function for it)."""
    if "name" in local:
        return True
    line, counter = local.get("line", ""), local.get("counter", 0)
    return counter < len(line) and line[counter] == "<"


def error_stack(traceback: TracebackType | None, message: str) -> list[str]:
    """The LinuxCNC error stack for an InterpError raised through ``traceback``."""
    frames = []
    while traceback is not None:
        frame = traceback.tb_frame
        if frame.f_globals.get("__name__", "").startswith(_PACKAGE):
            frames.append(frame)
        traceback = traceback.tb_next
    stack = []
    for depth, frame in enumerate(reversed(frames)):  # innermost first
        code_name = frame.f_code.co_name
        if code_name in _INTERFACE:
            stack.append(_INTERFACE[code_name])
            continue
        for function in _frame_functions(code_name, frame.f_locals, message, depth == 0):
            if function in SIGNATURES or function in FULL_NAMES:
                stack.append(pretty(function))
    return stack
