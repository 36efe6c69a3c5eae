"""NML configuration parsing (NML-001..035): valid files and every error, with file:line."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from nml import config as nml_config
from nml.channels import DEFAULT_NML_FILE, load_config
from nml.config import MessageRoom, NmlConfigWarning, parse
from nml.errors import NmlConfigError

GOOD = """\
# comment line
B cmd    SHMEM localhost 8192 0 0 1 16 1001 queue   # trailing comment
B stat   SHMEM localhost 20480 1 0 2 16 1002 mutex=os_sem
P task   cmd   LOCAL localhost R  0 1.0  1 0
P task   stat  LOCAL localhost W  0 1.0  1 0
P ui     cmd   LOCAL localhost W  0 10.0 0 10
P ui     stat  LOCAL localhost RW 0 INF  0 10
P slow   stat  LOCAL localhost R  0 -1   0 11
"""

LINUXCNC_NML = Path("/usr/share/linuxcnc/linuxcnc.nml")
# A copy of the B/P layout of LinuxCNC 2.9's configs/common/linuxcnc.nml options, written for
# this test, so CI (without LinuxCNC) still checks those options parse.
LINUXCNC_STYLE = """\
B emcCommand  SHMEM localhost 8192  0 0 1 16 1001 TCP=5005 xdr queue confirm_write serial
B emcError    SHMEM localhost 8192  0 0 3 16 1003 TCP=5005 xdr queue
B emcStatus   SHMEM localhost 20480 0 0 2 16 1002 TCP=5005 xdr
P emcsvr emcCommand LOCAL localhost W  1 1.0 1 2
P emcsvr default    LOCAL localhost RW 1 1.0 1 2
P xemc   emcStatus  LOCAL localhost R  0 10.0 0 10
"""


def errors_of(text: str, **kwargs) -> list[str]:
    with pytest.raises(NmlConfigError) as info:
        parse(text, "test.nml", **kwargs)
    return info.value.errors


def test_valid_file_parses_into_records() -> None:
    cfg = parse(GOOD, "good.nml")
    assert list(cfg.buffers) == ["cmd", "stat"]
    cmd, stat = cfg.buffers["cmd"], cfg.buffers["stat"]
    assert (cmd.size, cmd.is_queue, cmd.is_neutral, cmd.max_procs, cmd.key) == (
        8192,
        True,
        False,
        16,
        1001,
    )
    assert (stat.is_queue, stat.is_neutral, stat.mutex, stat.line) == (False, True, "os_sem", 3)
    ui = cfg.process("ui", "stat")
    assert (ui.ops, ui.can_read, ui.can_write, ui.c_num, ui.is_master) == (
        "RW",
        True,
        True,
        10,
        False,
    )
    assert math.isinf(ui.timeout)  # INF blocks forever (NML-031)
    assert math.isinf(cfg.process("slow", "stat").timeout)  # negative too
    assert cfg.process("task", "cmd").timeout == 1.0


def test_default_p_line_covers_every_buffer() -> None:
    with pytest.warns(NmlConfigWarning):
        cfg = parse(LINUXCNC_STYLE, "lcnc.nml")
    assert cfg.process("emcsvr", "emcStatus").buffer == "default"
    assert cfg.process("emcsvr", "emcCommand").ops == "W"
    assert cfg.buffers["emcCommand"].is_queue


def test_network_and_serial_options_warn_but_parse() -> None:
    with pytest.warns(NmlConfigWarning, match="TCP=5005 ignored"):
        parse(LINUXCNC_STYLE, "lcnc.nml")
    with pytest.warns(NmlConfigWarning, match="serialPortDevName"):
        parse("B a SHMEM localhost 4096 0 0 1 4 1 serialPortDevName=/dev/ttyS0\n")
    with pytest.warns(NmlConfigWarning, match="mutex=no_interrupts"):
        cfg = parse("B a SHMEM localhost 4096 0 0 1 4 1 mutex=no_interrupts\n")
    assert cfg.buffers["a"].mutex == "os_sem"
    cfg = parse("B a SHMEM localhost 4096 0 0 1 4 1 mutex=mao split\n")
    assert cfg.buffers["a"].mutex == "mao_split"


@pytest.mark.skipif(not LINUXCNC_NML.exists(), reason="LinuxCNC is not installed")
def test_linuxcncs_own_nml_file_parses_unchanged() -> None:
    with pytest.warns(NmlConfigWarning):
        cfg = nml_config.load(LINUXCNC_NML)
    assert set(cfg.buffers) == {"emcCommand", "emcError", "emcStatus", "toolCmd", "toolSts"}
    assert cfg.process("xemc", "emcStatus").timeout == 10.0


def test_our_nml_file_is_valid_and_has_the_standard_channels() -> None:
    cfg = load_config(DEFAULT_NML_FILE)
    for name in (
        "emcCommand",
        "emcStatus",
        "emcError",
        "toolCmd",
        "toolSts",
        "motCommand",
        "motStatus",
    ):
        assert name in cfg.buffers
    assert cfg.buffers["emcCommand"].is_queue and cfg.buffers["emcError"].is_queue
    assert not cfg.buffers["emcStatus"].is_queue
    assert all(p.is_master for p in cfg.processes if p.name == "cnc")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("B a SHMEM localhost 4096 0 0 1 4\n", "test.nml:1: B line has 8 fields, missing: key"),
        ("B a SHMEM localhost big 0 0 1 4 1\n", "test.nml:1: buffer a: size 'big' is not a number"),
        ("B a RAMMEM localhost 4096 0 0 1 4 1\n", "unknown buffer type 'RAMMEM'"),
        ("B a LOCMEM localhost 4096 0 0 1 4 1\n", "type LOCMEM is not supported"),
        ("B a SHMEM localhost 4096 2 0 1 4 1\n", "neut must be 0 or 1"),
        ("B a SHMEM localhost 4096 0 0 1 0 1\n", "max_procs must be positive"),
        ("B a SHMEM localhost 4096 0 0 1 4 1 bogus\n", "unknown option 'bogus'"),
        ("B a SHMEM localhost 4096 0 0 1 4 1 mutex=spin\n", "unknown mutex mode 'spin'"),
        ("X a\n", "test.nml:1: line must start with B (buffer) or P (process), got 'X'"),
        (
            "B a SHMEM localhost 4096 0 0 1 4 1\nB a SHMEM localhost 4096 0 0 2 4 2\n",
            "test.nml:2: buffer a: duplicate name 'a' (already used at line 1 by a)",
        ),
        (
            "B a SHMEM localhost 4096 0 0 1 4 7\nB b SHMEM localhost 4096 0 0 2 4 7\n",
            "test.nml:2: buffer b: duplicate key 7",
        ),
        (
            "B a SHMEM localhost 4096 0 0 1 4 7\nB b SHMEM localhost 4096 0 0 1 4 8\n",
            "test.nml:2: buffer b: duplicate buffer# 1",
        ),
        ("P p nowhere LOCAL localhost R 0 1 0 0\n", "buffer 'nowhere' is not defined by a B line"),
        (
            "B a SHMEM localhost 4096 0 0 1 4 1\nP p a LOCAL localhost R 0 1 0 4\n",
            "test.nml:2: process p on a: c_num 4 out of range 0..3 (max_procs 4)",
        ),
        (
            "B a SHMEM localhost 4096 0 0 1 4 1\nP p a LOCAL localhost R 0 1 0 1\n"
            "P q a LOCAL localhost R 0 1 0 1\n",
            "test.nml:3: process q on a: c_num 1 already used by process p at line 2",
        ),
        (
            "B a SHMEM localhost 4096 0 0 1 4 1\nP p a LOCAL localhost X 0 1 0 0\n",
            "ops 'X' must be R, W or RW",
        ),
        (
            "B a SHMEM localhost 4096 0 0 1 4 1\nP p a LOCAL localhost R 0 soon 0 0\n",
            "timeout 'soon' is not a number",
        ),
        (
            "B a SHMEM localhost 4096 0 0 1 4 1\nP p a REMOTE localhost R 0 1 0 0\n",
            "REMOTE on a, but no process is the server",
        ),
        ("B a SHMEM localhost 4096 0 0 1 4 1\nP p a LOCAL\n", "P line has 3 fields, missing"),
    ],
)
def test_each_error_names_file_line_and_cause(text: str, expected: str) -> None:
    assert any(expected in error for error in errors_of(text)), errors_of(text)


def test_every_error_of_a_file_is_reported_at_once() -> None:
    errors = errors_of(
        "B a SHMEM localhost x 0 0 1 4 1\nB b FOO localhost 4096 0 0 2 4 2\n"
        "P p zzz LOCAL localhost R 0 1 0 0\n"
    )
    assert [e.split(":")[1] for e in errors] == ["1", "2", "3"]


def test_buffer_too_small_for_its_messages() -> None:
    text = "B emcStatus SHMEM localhost 2048 0 0 1 16 1\n"
    errors = errors_of(text, message_room=lambda buffer: MessageRoom(5000, 5000))
    assert (
        "test.nml:1: buffer emcStatus: size 2048 is too small for its largest message"
        in (errors[0])
    )
    parse(text.replace("2048", "8192"), message_room=lambda buffer: MessageRoom(5000, 5000))


def test_missing_file_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(NmlConfigError, match="cannot read NML file"):
        nml_config.load(tmp_path / "absent.nml")


def test_unknown_process_connection_is_a_clear_error() -> None:
    cfg = parse(GOOD, "good.nml")
    with pytest.raises(NmlConfigError, match="no P line connects process 'ghost' to buffer 'cmd'"):
        cfg.process("ghost", "cmd")
