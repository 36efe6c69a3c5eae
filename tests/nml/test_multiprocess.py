"""NML between real OS processes over real shared memory (NML-019, -020, -031, -032, -045)."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import time
from collections import defaultdict
from pathlib import Path

import pytest

from nml.config import load
from nml.errors import NmlAccessError
from nml.shmem import ShmBuffer
from tests.nml.sample_messages import TEST_CMD, TEST_STAT

WORKER = str(Path(__file__).with_name("nml_worker.py"))
NML = """\
B q SHMEM localhost 8192  0 0 1 16 21 queue
B s SHMEM localhost 40000 0 0 2 16 22
P master q LOCAL localhost RW 0 5 1 0
P master s LOCAL localhost RW 0 5 1 0
P w1 q LOCAL localhost W 0 10 0 1
P w2 q LOCAL localhost W 0 10 0 2
P w3 q LOCAL localhost W 0 10 0 3
P r1 q LOCAL localhost R 0 10 0 4
P r2 q LOCAL localhost R 0 10 0 5
P sw s LOCAL localhost W 0 10 0 6
P sr s LOCAL localhost R 0 10 0 7
P late q LOCAL localhost R 0 5 0 8
"""


@pytest.fixture
def nml_file(tmp_path: Path) -> str:
    path = tmp_path / "test.nml"
    path.write_text(NML)
    return str(path)


def result_of(proc: subprocess.Popen[str], timeout: float = 60) -> dict:
    out, err = proc.communicate(timeout=timeout)
    assert proc.returncode == 0, err
    return json.loads(out.strip().splitlines()[-1])


def wait_for_line(proc: subprocess.Popen[str]) -> dict:
    line = proc.stdout.readline()
    assert line, proc.stderr.read()
    return json.loads(line)


def test_queue_stress_several_writers_and_readers(procs, nml_file: str) -> None:
    """No loss, no duplicates, FIFO per writer, unique serial numbers."""
    cfg = load(nml_file)
    per_writer = 600
    with ShmBuffer(cfg.buffers["q"], cfg.process("master", "q")):
        readers = [
            procs.python(WORKER, "queue-reader", nml_file, r, "0", "1.5") for r in ("r1", "r2")
        ]
        writers = [
            procs.python(WORKER, "queue-writer", nml_file, f"w{n}", str(n), str(per_writer))
            for n in (1, 2, 3)
        ]
        written = [result_of(w) for w in writers]
        got = [row for r in readers for row in result_of(r)["got"]]
    all_serials = [s for w in written for s in w["serials"]]
    assert len(set(all_serials)) == 3 * per_writer  # NML-041: unique per channel
    assert len(got) == 3 * per_writer
    assert len({(w, i) for w, i, _ in got}) == 3 * per_writer  # nothing duplicated
    assert sorted(s for _, _, s in got) == sorted(all_serials)  # nothing lost
    by_writer: dict[int, list[tuple[int, int]]] = defaultdict(list)
    for w, i, serial in got:
        by_writer[w].append((serial, i))
    for rows in by_writer.values():  # FIFO per writer: serial order is index order
        assert [i for _, i in sorted(rows)] == list(range(per_writer))


def test_latest_value_is_never_torn_while_a_writer_hammers_it(procs, nml_file: str) -> None:
    cfg = load(nml_file)
    count = 20000
    with ShmBuffer(cfg.buffers["s"], cfg.process("master", "s")):
        readers = [
            procs.python(WORKER, "latest-reader", nml_file, "sr", str(count)) for _ in range(2)
        ]
        for reader in readers:
            wait_for_line(reader)
        writer = procs.python(WORKER, "latest-writer", nml_file, "sw", str(count))
        assert result_of(writer) == {"written": count}
        seen = [result_of(r) for r in readers]
    for result in seen:
        assert result["last"] == count
        assert result["reads"] > 100  # the readers really raced the writer
        assert result["torn"] == 0
        assert result["backwards"] == 0


def test_blocked_reader_wakes_on_a_write_from_another_process(procs, nml_file: str) -> None:
    cfg = load(nml_file)
    with ShmBuffer(cfg.buffers["q"], cfg.process("master", "q")) as master:
        reader = procs.python(WORKER, "blocking-reader", nml_file, "r1", "20")
        wait_for_line(reader)
        time.sleep(0.2)
        master.write(TEST_CMD(index=42))
        result = result_of(reader)
    assert result["index"] == 42
    assert result["waited"] < 20  # woke on the write, not at the timeout


def test_process_killed_holding_the_lock_does_not_hang_others(procs, nml_file: str, caplog) -> None:
    cfg = load(nml_file)
    with ShmBuffer(cfg.buffers["q"], cfg.process("master", "q")) as master:
        victim = procs.python(WORKER, "hold-lock-and-die", nml_file, "w1", "q", "0")
        assert wait_for_line(victim) == {"locked": True}
        victim.wait(10)
        with caplog.at_level("ERROR", logger="nml"):
            master.write(TEST_CMD(index=1))  # takes the lock after repairing it
        assert f"pid {victim.pid} died holding the lock; recovered" in caplog.text
        assert master.read().index == 1


def test_status_writer_killed_mid_write_is_discarded_not_torn(procs, nml_file: str, caplog) -> None:
    cfg = load(nml_file)
    with ShmBuffer(cfg.buffers["s"], cfg.process("master", "s")) as master:
        master.write(TEST_STAT(counter=1))
        victim = procs.python(WORKER, "hold-lock-and-die", nml_file, "sw", "s", "1")
        assert wait_for_line(victim) == {"locked": True}
        victim.wait(10)
        with caplog.at_level("ERROR", logger="nml"):
            assert master.peek() is None  # the half-written status is not served
        assert "unfinished status write was discarded" in caplog.text
        master.write(TEST_STAT(counter=2))
        assert master.peek().counter == 2


def test_non_master_waits_for_the_master_to_create_the_buffer(procs, nml_file: str) -> None:
    cfg = load(nml_file)
    late = procs.python(WORKER, "attach-only", nml_file, "late", "q", stdin=subprocess.PIPE)
    time.sleep(0.3)
    with ShmBuffer(cfg.buffers["q"], cfg.process("master", "q")) as master:
        assert wait_for_line(late) == {"attached": True}
        assert any(pid == late.pid for pid, _ in master.connections())
        late.stdin.close()
        late.stdin = None
        assert result_of(late) == {"closed": True}
        assert all(pid != late.pid for pid, _ in master.connections())


def test_dead_attached_process_frees_its_slot(procs, nml_file: str) -> None:
    cfg = load(nml_file)
    with ShmBuffer(cfg.buffers["q"], cfg.process("master", "q")) as master:
        other = procs.python(WORKER, "attach-only", nml_file, "r1", "q", stdin=subprocess.PIPE)
        assert wait_for_line(other) == {"attached": True}
        other.kill()
        other.wait(10)
        # A new connection reclaims the dead process's slot.
        with ShmBuffer(cfg.buffers["q"], cfg.process("r2", "q")):
            assert all(pid != other.pid for pid, _ in master.connections())


def test_second_master_is_refused_while_the_first_lives(procs, nml_file: str) -> None:
    cfg = load(nml_file)
    with ShmBuffer(cfg.buffers["q"], cfg.process("master", "q")):
        code = (
            "import sys; from nml.config import load; from nml.shmem import ShmBuffer\n"
            f"cfg = load({nml_file!r})\n"
            "ShmBuffer(cfg.buffers['q'], cfg.process('master', 'q'))\n"
        )
        proc = procs.python("-c", code)
        _, err = proc.communicate(timeout=30)
    assert proc.returncode != 0
    assert "buffer q already exists and its master" in err


def test_stale_segment_of_a_dead_master_is_replaced(procs, nml_file: str) -> None:
    code = (
        "import os; from nml.config import load; from nml.shmem import ShmBuffer\n"
        f"cfg = load({nml_file!r})\n"
        "b = ShmBuffer(cfg.buffers['q'], cfg.process('master', 'q'))\n"
        "os._exit(0)\n"  # dies without cleaning up
    )
    assert procs.python("-c", code).wait(30) == 0
    cfg = load(nml_file)
    with ShmBuffer(cfg.buffers["q"], cfg.process("master", "q")) as master:
        master.write(TEST_CMD(index=3))
        assert master.read().index == 3


def test_attach_error_names_the_buffer(nml_file: str) -> None:
    cfg = load(nml_file)
    impatient = dataclasses.replace(cfg.process("late", "q"), timeout=0.2)
    with pytest.raises(NmlAccessError, match="buffer q: shared memory segment does not exist"):
        ShmBuffer(cfg.buffers["q"], impatient)
