"""The interpreter's API as task uses it (TASK-004..010, INTERP-005..007, INTERP-018/020)."""

from __future__ import annotations

import inspect
import io

import pytest

from iocontrol.tooltable import ToolTable
from task.interp.canon import Canon, PrintingCanon
from task.interp.errors import (
    INTERP_ENDFILE,
    INTERP_EXECUTE_FINISH,
    INTERP_EXIT,
    INTERP_OK,
    InterpError,
)
from task.interp.interp import Interpreter


def make(tmp_path, text: str, tools: str = "T1 P1 Z0.5 D0.25\nT2 P2 Z1\n"):
    (tmp_path / "prog.ngc").write_text(text)
    table = ToolTable()
    table.load_lines(tools.splitlines(keepends=True))
    out = io.StringIO()
    interp = Interpreter(PrintingCanon(out.write, table), parameter_file=str(tmp_path / "p.var"))
    interp.init()
    interp.open(str(tmp_path / "prog.ngc"))
    return interp, out


def run_all(interp: Interpreter) -> list[int]:
    statuses = []
    while True:
        if interp.read() == INTERP_ENDFILE:
            break
        status = interp.execute()
        statuses.append(status)
        if status == INTERP_EXIT:
            break
    return statuses


def calls(out: io.StringIO) -> list[str]:
    return [line[13:] for line in out.getvalue().splitlines()]


def test_printing_canon_implements_every_canon_call() -> None:
    wanted = {
        name
        for name, _ in inspect.getmembers(Canon, inspect.isfunction)
        if not name.startswith("_")
    }
    missing = {name for name in wanted if not callable(getattr(PrintingCanon, name, None))}
    assert not missing


def test_queue_busters_return_execute_finish(tmp_path) -> None:
    interp, _ = make(tmp_path, "G21\nT1 M6\nG38.2 Z-5 F100\nM66 P0 L0\nG0 X1\nM2\n")
    assert run_all(interp) == [
        INTERP_OK,
        INTERP_EXECUTE_FINISH,
        INTERP_EXECUTE_FINISH,
        INTERP_EXECUTE_FINISH,
        INTERP_OK,
        INTERP_EXIT,
    ]


def test_synch_after_tool_change_reloads_tool_parameters(tmp_path) -> None:
    interp, _ = make(tmp_path, "G20\nT2 M6\nG0 X0\nM2\n")
    interp.read()
    interp.execute()
    interp.read()
    assert interp.execute() == INTERP_EXECUTE_FINISH
    interp.read()  # the next read takes the new tool's data from the world model
    assert interp.parameters[5400] == 2
    assert interp.parameters[5403] == 1.0


def test_positions_are_predicted_at_readahead(tmp_path) -> None:
    interp, out = make(
        tmp_path, "N10 G91\nN20 G0 X10 Y-5 Z20\nN30 G1 Y20 Z-5 F100\nN40 G0 Z30\nN50 M2\n"
    )
    run_all(interp)
    moves = [c for c in calls(out) if c.startswith("STRAIGHT")]
    assert moves[0].startswith("STRAIGHT_TRAVERSE(10.0000, -5.0000, 20.0000")
    assert moves[1].startswith("STRAIGHT_FEED(10.0000, 15.0000, 15.0000")
    assert moves[2].startswith("STRAIGHT_TRAVERSE(10.0000, 15.0000, 45.0000")


def test_queue_buster_inside_nested_calls_keeps_the_call_going(tmp_path) -> None:
    text = (
        "o<inner> sub\nT1 M6\nG0 X#1\no<inner> endsub\n"
        "o<outer> sub\no<inner> call [#1 + 1]\no<outer> endsub\n"
        "o<outer> call [4]\nG0 Y1\nM2\n"
    )
    interp, out = make(tmp_path, text)
    statuses = run_all(interp)
    assert INTERP_EXECUTE_FINISH in statuses
    assert interp.call_level == 0
    assert "STRAIGHT_TRAVERSE(5.0000, 0.0000" in out.getvalue()
    assert "STRAIGHT_TRAVERSE(5.0000, 1.0000" in out.getvalue()


def test_m2_inside_a_subroutine_unwinds_cleanly(tmp_path) -> None:
    interp, out = make(tmp_path, "o<s> sub\nG0 X1\nM2\no<s> endsub\no<s> call\nG0 X9\nM2\n")
    assert run_all(interp)[-1] == INTERP_EXIT
    assert interp.call_level == 0
    assert "X9" not in out.getvalue() and "9.0000" not in out.getvalue()


def test_error_carries_message_and_line_text(tmp_path) -> None:
    interp, _ = make(tmp_path, "G21\n  G1 X[1/0]\nM2\n")
    with pytest.raises(InterpError) as info:
        run_all(interp)
    assert str(info.value) == "Attempt to divide by zero"
    assert interp.linetext == "  G1 X[1/0]"
    assert interp.call_level == 0


def test_mdi_lines_execute_directly(tmp_path) -> None:
    interp, out = make(tmp_path, "M2\n")
    assert interp.execute("G0 X3 Y4") == INTERP_OK
    assert calls(out)[-1].startswith("STRAIGHT_TRAVERSE(3.0000, 4.0000")


def test_parameter_file_is_saved_atomically_with_backup(tmp_path) -> None:
    var = tmp_path / "p.var"
    var.write_text("3000\t7.000000\n5161\t1.000000\n5221\t2.000000\n")
    interp, _ = make(tmp_path, "#3000 = 8\n#5161 = 9\nM2\n")
    assert interp.parameters[5221] == 2.0 and interp.parameters[3000] == 7.0
    run_all(interp)
    interp.exit()
    saved = dict(line.split("\t") for line in var.read_text().splitlines())
    assert saved["3000"] == "8.000000" and saved["5161"] == "9.000000"
    assert saved["5220"] == "1.000000"  # required parameters are always written
    assert "1" not in saved  # #1..#30 are not persistent unless the file has them
    assert (tmp_path / "p.var.bak").exists()
    assert not list(tmp_path.glob(".p.var.*"))


def test_parameter_file_out_of_order_is_an_error(tmp_path) -> None:
    (tmp_path / "p.var").write_text("5221\t1\n5161\t1\n")
    table = ToolTable()
    interp = Interpreter(
        PrintingCanon(io.StringIO().write, table), parameter_file=str(tmp_path / "p.var")
    )
    with pytest.raises(InterpError, match="Parameter file out of order"):
        interp.init()


def test_hal_parameters_come_from_the_lookup(tmp_path) -> None:
    (tmp_path / "prog.ngc").write_text("(DEBUG, #<_hal[motion.spindle-speed]> #<_hal[nope]>)\nM2\n")
    out = io.StringIO()
    interp = Interpreter(
        PrintingCanon(out.write, ToolTable()),
        parameter_file=str(tmp_path / "p.var"),
        hal={"motion.spindle-speed": 1200.0}.get,
    )
    interp.init()
    interp.open(str(tmp_path / "prog.ngc"))
    run_all(interp)
    assert 'MESSAGE(" 1200.000000 ######")' in out.getvalue()


def test_an_unexecuted_line_does_not_leak_into_the_next_command(tmp_path) -> None:
    interp, out = make(tmp_path, "G0 X5\nM2\n")
    assert interp.read() == INTERP_OK  # read, then abandoned (an abort, say)
    assert interp.execute("G0 Y7") == INTERP_OK
    assert calls(out)[-1].startswith("STRAIGHT_TRAVERSE(0.0000, 7.0000")


LOOP = """o<step> sub
  #<r> = [#2 * 0.5 + 10]
  G1 X[#<r> * COS[#1]] Y[#<r> * SIN[#1]]
  o<step> return [#<r>]
o<step> endsub
G21 F1000
#1 = 0
o100 while [#1 LT 4]
  o<step> call [#1 * 0.72] [#1 MOD 7]
  #1 = [#1 + 1]
o100 endwhile
M2
"""


def test_lines_read_again_get_plans(tmp_path) -> None:
    """A loop body and a subroutine are read the general way twice, then by their plans."""
    from task.interp.compiled import MotionPlan, OWordPlan, ParameterPlan

    interp, out = make(tmp_path, LOOP)
    assert run_all(interp)[-1] == INTERP_EXIT
    kinds = {type(plan).__name__: plan for plan in interp._plans.values()}
    assert {"MotionPlan", "ParameterPlan", "OWordPlan"} <= set(kinds)
    planned = {plan.text.strip() for plan in interp._plans.values() if plan.line}
    assert "G1 X[#<r> * COS[#1]] Y[#<r> * SIN[#1]]" in planned
    assert isinstance(interp._plans["  #1 = [#1 + 1]\n"], ParameterPlan)
    assert isinstance(interp._plans["o100 while [#1 LT 4]\n"], OWordPlan)
    assert isinstance(interp._plans["  G1 X[#<r> * COS[#1]] Y[#<r> * SIN[#1]]\n"], MotionPlan)
    assert len([line for line in calls(out) if line.startswith("STRAIGHT_FEED")]) == 4


def test_an_error_in_a_planned_line_is_the_general_readers(tmp_path) -> None:
    interp, _ = make(
        tmp_path,
        "#1 = 3\no1 while [#1 GT -1]\n  #2 = [10 / #1]\n  #1 = [#1 - 1]\no1 endwhile\nM2\n",
    )
    with pytest.raises(InterpError) as info:
        run_all(interp)
    assert str(info.value) == "Attempt to divide by zero"
    assert interp.linetext == "  #2 = [10 / #1]"
    assert interp.parameters[2] == 10.0
    assert interp.call_level == 0


def test_error_stack_is_recorded_only_when_asked(tmp_path) -> None:
    program = "o<s> sub\n  G1 X[1 / #1] F10\no<s> endsub\no<s> call [0]\nM2\n"
    interp, _ = make(tmp_path, program)
    with pytest.raises(InterpError) as info:
        run_all(interp)
    assert info.value.stack == []
    interp, _ = make(tmp_path, program)
    interp.record_error_stack()
    with pytest.raises(InterpError) as info:
        run_all(interp)
    assert info.value.stack == [
        "int Interp::execute_binary1(double*, int, double*)",
        "int Interp::execute_binary(double*, int, double*)",
        "int Interp::read_real_expression(char*, int*, double*, double*)",
        "int Interp::read_real_value(char*, int*, double*, double*)",
        "int Interp::read_x(char*, int*, block_pointer, double*)",
        "int Interp::read_one_item(char*, int*, block_pointer, double*)",
        "int Interp::read_items(block_pointer, char*, double*)",
        "int Interp::parse_line(char*, block_pointer, setup_pointer)",
        "int Interp::_read(const char*)",
    ]
    assert not interp._plans  # the stack needs the interpreting reader's calls


def test_error_stack_names_are_cut_at_79_characters(tmp_path) -> None:
    interp, _ = make(tmp_path, "G21 G17\nG0 X0 Y0\nG2 X1 Y1 R0.1 F10\nM2\n")
    interp.record_error_stack()
    with pytest.raises(InterpError) as info:
        run_all(interp)
    assert info.value.stack[0] == (
        "int Interp::arc_data_r(int, int, double, double, double, double, double, int, d"
    )
    assert all(len(name) <= 79 for name in info.value.stack)
    assert info.value.stack[-1] == "int Interp::_execute(const char*)"


def run_to_end(interp: Interpreter, path) -> None:  # type: ignore[no-untyped-def]
    interp.open(str(path))
    while interp.read() != INTERP_ENDFILE:
        if interp.execute() == INTERP_EXIT:
            break
    interp.close()


def test_a_continue_in_a_do_loop_leaves_later_loops_alone(tmp_path) -> None:
    """A deliberate deviation from LinuxCNC 2.9 (tests/interp/linuxcnc/DEVIATIONS.txt):
    its 'continue' flag outlives a do/while loop, and the next repeat loop, in this program
    or the next one task runs, went round twice as often (a pocket cut to twice its depth)."""
    do_loop = tmp_path / "do.ngc"
    do_loop.write_text(
        "#<n> = 0\no600 do\n#<n> = [#<n> + 1]\no610 if [#<n> EQ 2]\no600 continue\n"
        "o610 endif\no600 while [#<n> LT 3]\nM2\n"
    )
    passes = tmp_path / "passes.ngc"
    passes.write_text("G1 X5 F100\no10 repeat [2]\nG1 X0\nG1 X1\no10 endrepeat\nM2\n")
    out = io.StringIO()
    interp = Interpreter(
        PrintingCanon(out.write, ToolTable()), parameter_file=str(tmp_path / "p.var")
    )
    interp.init()
    for program in (do_loop, passes):
        run_to_end(interp, program)
    feeds = [line for line in out.getvalue().splitlines() if "STRAIGHT_FEED" in line]
    assert len(feeds) == 1 + 2 * 2  # the lead-in, then two passes of two moves
