"""``cnc rs274``: the standalone interpreter, a drop-in for LinuxCNC's ``rs274`` (TASK-004).

    cnc rs274 [-t TOOL_TABLE] [-v VAR_FILE] [-i INI] [-b] [-s] [-g] [-n 0|1|2] [FILE [OUT]]

Options may follow the file names, as GNU getopt lets them (``cnc rs274 -g prog.ngc -t
tool.tbl``). With ``-i``, the INI's remaps and ``[PYTHON]`` plug-in are used; what Python code
prints comes out in order with the canonical calls, as rs274 (unbuffered) prints it.

Output goes to stdout (or OUT) in rs274's format; ``executing``, errors and the failing line go
to stderr (with ``-s``, followed by the error's stack of LinuxCNC function names, see
``stack.py``); the exit status is 0, or 1 after an interpreter error (with ``-n 2``, the
default).
Without ``-g`` rs274's interactive menu is offered; without FILE lines are read from stdin.
"""

from __future__ import annotations

import contextlib
import getopt
import io
import os
import sys

from iocontrol.tooltable import ToolTable

from . import canterp
from .canon import PrintingCanon
from .canterp import Canterp
from .errors import INTERP_ENDFILE, INTERP_EXECUTE_FINISH, INTERP_EXIT, INTERP_OK, InterpError
from .interp import Interpreter

DEFAULT_TOOL_TABLE = "/usr/share/doc/linuxcnc/examples/sample-configs/common/tool.tbl"
DEFAULT_VAR_FILE = "/etc/emc2/sample-configs/sim/sim.var"
PLUGIN_DIR = "/usr/lib/linuxcnc"  # where rs274 -p looks for a plug-in named without a path
USAGE = """Usage: {prog} [-p interp.so] [-t tool.tbl] [-v var-file.var] [-n 0|1|2]
          [-b] [-s] [-g] [input file [output file]]

    -p: Specify the pluggable interpreter to use
    -t: Specify the .tbl (tool table) file to use
    -v: Specify the .var (parameter) file to use
    -n: Specify the continue mode:
           0: continue
           1: enter MDI mode
           2: stop (default)
    -b: Toggle the 'block delete' flag (default: OFF)
    -s: Toggle the 'print stack' flag (default: OFF)
    -g: Toggle the 'go (batch mode)' flag (default: OFF)
    -i: specify the INI file (default: no INI file)
    -T: call task_init()
    -l: specify the log_level (default: -1)
"""


def _write_bytes(stream, text: str) -> None:
    """Programs are read as latin-1, so writing latin-1 gives back their bytes unchanged."""
    binary = getattr(stream, "buffer", None)
    if binary is not None:
        stream.flush()
        binary.write(text.encode("latin-1", errors="replace"))
        binary.flush()
    else:
        stream.write(text)


_stdin_drained = False


class _Out:
    """Buffered writer for the canon; flushed before anything goes to stderr and every
    few thousand lines (rs274 itself writes unbuffered)."""

    def __init__(self, stream) -> None:
        self.stream = stream
        self.parts: list[str] = []
        self.append = self.parts.append

    def flush(self) -> None:
        if self.parts:
            _write_bytes(self.stream, "".join(self.parts))
            self.parts.clear()
        self.stream.flush()


def _err(out: _Out, text: str) -> None:
    out.flush()
    stderr = sys.stderr
    _write_bytes(getattr(stderr, "stream", stderr), text)
    stderr.flush()


class _PythonStdout(io.TextIOBase):
    """sys.stdout during a run: what user Python code prints joins the canonical calls in
    order (as UTF-8 bytes, as Python writes them)."""

    encoding = "utf-8"

    def __init__(self, out: _Out) -> None:
        self.out = out

    def write(self, text: str) -> int:
        self.out.append(text.encode("utf-8", "replace").decode("latin-1"))
        return len(text)

    def writable(self) -> bool:
        return True


class _PythonStderr(io.TextIOBase):
    """sys.stderr during a run: the canonical calls so far go out first."""

    encoding = "utf-8"

    def __init__(self, out: _Out, stream) -> None:
        self.out = out
        self.stream = stream

    def write(self, text: str) -> int:
        self.out.flush()
        self.stream.write(text)
        return len(text)

    def flush(self) -> None:
        self.stream.flush()

    def writable(self) -> bool:
        return True


def _report(out: _Out, interp: Interpreter, error: InterpError) -> None:
    # with -s the error's LinuxCNC function stack follows (empty otherwise)
    stack = "".join(f"{name}\n" for name in error.stack)
    _err(out, f"{error.message}\n{interp.linetext}\n{stack}")


def _read_line(prompt: str) -> str | None:
    """readline(): the prompt only shows on a terminal, as with rs274."""
    if _stdin_drained:
        return None
    if sys.stdin.isatty():
        try:
            return input(prompt)
        except EOFError:
            return None
    line = sys.stdin.readline()
    if not line:
        return None
    return line.rstrip("\n")


def interpret_from_keyboard(interp: Interpreter, out: _Out, block_delete: bool) -> int:
    while True:
        out.flush()
        line = _read_line("READ => ")
        if line is None or line == "quit":
            return 0
        try:
            status = interp.read(line)
            if status == INTERP_ENDFILE:
                continue
            status = interp.execute()
        except InterpError as error:
            _report(out, interp, error)


def interpret_from_file(interp: Interpreter, out: _Out, do_next: int, block_delete: bool) -> int:
    interp.canon.SET_BLOCK_DELETE(block_delete)
    status = 0
    while True:
        try:
            read_status = interp.read()
        except InterpError as error:
            _report(out, interp, error)
            if do_next == 2:
                return 1
            if do_next == 1 and not _mdi_then_continue(interp, out, block_delete):
                return 1
            continue
        if read_status == INTERP_ENDFILE:
            status = 0  # the end of the file: a success, whatever went wrong before (-n 0)
            break
        if read_status != INTERP_OK and read_status != INTERP_EXECUTE_FINISH:
            _err(out, "File not open\n\n")
            if do_next == 2:
                return 1
            continue
        try:
            status = interp.execute()
        except InterpError as error:
            _report(out, interp, error)
            status = 1
            if do_next == 1:
                if not _mdi_then_continue(interp, out, block_delete):
                    break
            elif do_next == 2:
                break
            continue
        if status == INTERP_EXIT:
            return 0
        status = 0
    return 1 if status == 1 else 0


def _mdi_then_continue(interp: Interpreter, out: _Out, block_delete: bool) -> bool:
    _err(out, "starting MDI\n")
    interpret_from_keyboard(interp, out, block_delete)
    _err(out, "continue program? y/n =>")
    answer = sys.stdin.readline()
    return answer.startswith("y")


def main(argv: list[str]) -> int:
    prog = "rs274"
    try:
        opts, args = getopt.gnu_getopt(argv, "p:t:v:bsn:gi:l:T")
    except getopt.GetoptError:
        sys.stderr.write(USAGE.format(prog=prog))
        return 1
    if len(args) > 2:
        sys.stderr.write(USAGE.format(prog=prog))
        return 1
    tool_files: list[str] = []
    var_file = DEFAULT_VAR_FILE
    block_delete = False
    print_stack = False
    do_next = 2
    go = False
    ini_path = None
    task = 0
    plugin = None
    for opt, value in opts:
        if opt == "-p":
            plugin = value
        elif opt == "-t":
            tool_files.append(value)
        elif opt == "-v":
            var_file = value
        elif opt == "-b":
            block_delete = not block_delete
        elif opt == "-s":
            print_stack = not print_stack
        elif opt == "-n":
            try:
                do_next = int(value)
            except ValueError:
                do_next = 0
        elif opt == "-g":
            go = not go
        elif opt == "-i":
            ini_path = value
        elif opt == "-T":
            task = 1
    stdout = sys.stdout
    out_file = None
    if len(args) == 2:
        try:
            out_file = open(args[1], "w", encoding="utf-8")  # noqa: SIM115
        except OSError:
            sys.stderr.write("executing\n")
            sys.stderr.write(f"could not open output file {args[1]}\n")
            return 1
        stdout = out_file
    out = _Out(stdout)
    saved = sys.stdout, sys.stderr, os.environ.get("INI_FILE_NAME")
    if out_file is None:
        sys.stdout = _PythonStdout(out)
    sys.stderr = _PythonStderr(out, sys.stderr)
    if ini_path is not None:  # (user Python code may read it, as under rs274)
        os.environ["INI_FILE_NAME"] = ini_path
    else:
        os.environ.pop("INI_FILE_NAME", None)
    try:
        status = _run(
            args,
            out,
            tool_files,
            var_file,
            block_delete,
            do_next,
            go,
            ini_path,
            task,
            print_stack,
            plugin,
        )
        out.flush()
        return status
    except BrokenPipeError:
        # the reader went away (rs274 dies of SIGPIPE): stop quietly
        out.parts.clear()
        with contextlib.suppress(OSError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        return 1
    finally:
        sys.stdout, sys.stderr = saved[0], saved[1]
        if saved[2] is None:
            os.environ.pop("INI_FILE_NAME", None)
        else:
            os.environ["INI_FILE_NAME"] = saved[2]
        if out_file is not None:
            out_file.close()


def _run(
    args, out, tool_files, var_file, block_delete, do_next, go, ini_path, task, print_stack, plugin
) -> int:
    tools = ToolTable()
    canon = PrintingCanon(out.append, tools, out.flush)
    custom = _plugin(plugin, canon, out)
    loaded = False
    for name in tool_files:
        loaded = bool(_load_tools(tools, name, out))
    if not go:
        block_delete = _menu(out, block_delete, tool_files, tools)
    _err(out, "executing\n")
    if not tool_files and not _load_tools(tools, DEFAULT_TOOL_TABLE, out):
        return 1
    del loaded
    ini = None
    if ini_path is not None:
        from cnc.ini import IniError, IniFile

        try:
            ini = IniFile.load(ini_path)
        except IniError as error:
            _err(out, f"Unable to open inifile:{ini_path}:\n{error}\n")
    interp = custom or Interpreter(canon, parameter_file=var_file, task=task)
    if print_stack:
        interp.record_error_stack()
    # rs274 builds its interpreter before it names the INI file, so the predefined
    # #<_metric_machine> never sees it (-1); the INI counts from init() on.
    interp.ini = ini
    interp.report = lambda text: _err(out, text)
    try:
        interp.init()
    except InterpError as error:
        _report(out, interp, error)
        interp.release_python()
        return 1
    if not args:
        status = interpret_from_keyboard(interp, out, block_delete)
    else:
        try:
            interp.open(args[0])
        except InterpError as error:
            _report(out, interp, error)
            interp.release_python()
            return 1
        status = interpret_from_file(interp, out, do_next, block_delete)
        interp.close()
    interp.exit()
    return status


def _plugin(name: str | None, canon: PrintingCanon, out: _Out) -> Canterp | None:
    """-p: the interpreter plug-in named, found as rs274 finds it (a relative name in
    LinuxCNC's library folder). The one plug-in LinuxCNC ships, canterp, is ours in Python;
    for any other the message is rs274's and the built-in interpreter runs."""
    if name is None:
        return None
    path = os.path.join(PLUGIN_DIR, name)
    if os.path.basename(name) == f"{canterp.NAME}.so":
        _err(out, f"emcTaskInit: using custom interpreter '{path}'\n")
        return canterp.Canterp(canon)
    _err(
        out,
        f"emcTaskInit: could not open interpreter '{path}': {path}: "
        "cannot open shared object file: No such file or directory\n",
    )
    return None


def _load_tools(tools: ToolTable, name: str, out: _Out) -> bool:
    try:
        skipped = tools.load(name, strict=False)
    except OSError:
        return False
    for line in skipped:
        out.append(f"File: {name} Unrecognized line skipped:\n    {line}")
    return True


def _menu(out: _Out, block_delete: bool, tool_files: list[str], tools: ToolTable) -> bool:
    """rs274's start-up menu (without -g): start, read a tool file, toggle block delete.

    Returns the block delete switch. Choosing a parameter file and the error-handling
    submenu are offered by rs274 too but not here (use -v and -n).
    """
    while True:
        _err(
            out,
            "enter a number:\n1 = start interpreting\n2 = choose parameter file ...\n"
            "3 = read tool file ...\n"
            f"4 = turn block delete switch {'OFF' if block_delete else 'ON'}\n"
            "5 = adjust error handling...\nenter choice => ",
        )
        line = sys.stdin.readline()
        if not sys.stdin.isatty():
            # rs274's menu reads with stdio, which buffers the whole pipe: readline() then
            # finds nothing left for the interactive mode
            global _stdin_drained
            _stdin_drained = True
        if not line:
            return block_delete
        try:
            choice = int(line.split()[0])
        except (ValueError, IndexError):
            continue
        if choice == 1:
            return block_delete
        if choice == 3:
            _err(out, "name of tool file => ")
            name = sys.stdin.readline().rstrip("\n")
            if not _load_tools(tools, name, out):
                raise SystemExit(1)
            tool_files.append(name)
        elif choice == 4:
            block_delete = not block_delete


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
