"""The safety board: requests no lock can block, heartbeats, lost processes, leases."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Iterator

import pytest

from nml.safety import NUM_SLOTS, SafetyBoard, SafetyLink, now_ns
from tests.conftest import REPO


@pytest.fixture
def board() -> Iterator[SafetyBoard]:
    made = SafetyBoard.create()
    yield made
    made.unlink()


def test_without_a_machine_there_is_no_board() -> None:
    assert SafetyBoard.attach() is None
    assert SafetyLink.open("task", 1.0) is None


def test_each_watcher_sees_each_new_request_once(board: SafetyBoard) -> None:
    board.request_estop("before the watchers")
    motion, task = board.watcher(), board.watcher()
    assert motion.take_estop() is None  # made before it: not its business
    stamp = SafetyBoard.attach().request_estop("from a UI", is_braking=True)
    for watcher in (motion, task):
        request = watcher.take_estop()
        assert (request.stamp, request.reason, request.is_braking) == (stamp, "from a UI", True)
        assert request.pid == os.getpid()
        assert watcher.take_estop() is None
    assert motion.take_abort() is None
    board.request_abort("stop")
    assert motion.take_abort().reason == "stop"


def test_a_supervised_process_that_stops_beating_is_lost_once(board: SafetyBoard) -> None:
    beat = board.register("iocontrol", 0.05, is_supervised=True)
    assert board.find_lost(now_ns()) == []
    lost = board.find_lost(now_ns() + 100_000_000)
    assert [(p.name, p.pid) for p in lost] == [("iocontrol", os.getpid())]
    assert "iocontrol (pid" in lost[0].reason and "stopped answering" in lost[0].reason
    assert board.find_lost(now_ns() + 200_000_000) == []  # found once, by whoever looks first
    assert board.lost_names() == [f"iocontrol (pid {os.getpid()})"]
    beat.beat()  # too late: lost stays lost until the process registers again
    assert board.lost_names()
    board.register("iocontrol", 0.05, is_supervised=True)
    assert board.lost_names() == []


def test_unsupervised_slots_are_never_lost(board: SafetyBoard) -> None:
    board.register("ui", 0.05, is_supervised=False)
    assert board.find_lost(now_ns() + 10**9) == []


def test_a_clean_exit_while_running_is_lost_at_shutdown_it_is_not(board: SafetyBoard) -> None:
    board.register("halui", 10.0, is_supervised=True).leave()
    assert "has exited" in board.find_lost()[0].reason
    board.register("halui", 10.0, is_supervised=True).leave()
    board.begin_shutdown()
    assert board.find_lost() == []


def test_the_launcher_marks_a_dead_child_lost_at_once(board: SafetyBoard) -> None:
    _register_and_exit()
    assert board.lost_names() == []  # (gone, but nobody has looked yet)
    pid = _slot_pids(board)[0]
    lost = board.mark_lost(pid, f"iocontrol (pid {pid}) was killed by SIGKILL")
    assert lost is not None and lost.name == "iocontrol"
    assert board.mark_lost(pid, "again") is None  # marked already
    assert board.mark_lost(12345678, "no such process") is None


def _register_and_exit() -> None:
    """Another process registers as supervised 'iocontrol' and exits without a word."""
    code = "from nml.safety import SafetyBoard\n"
    code += "SafetyBoard.attach().register('iocontrol', 10.0, is_supervised=True)\n"
    subprocess.run([sys.executable, "-c", code], cwd=REPO, check=True)


def _slot_pids(board: SafetyBoard) -> list[int]:
    import struct

    from nml.safety import SLOT_SIZE, SLOTS_AT

    return [
        pid
        for index in range(NUM_SLOTS)
        if (pid := struct.unpack_from("<i", board._mm, SLOTS_AT + index * SLOT_SIZE)[0])
    ]


def test_a_dead_supervised_slot_is_not_reused_before_it_is_found(board: SafetyBoard) -> None:
    _register_and_exit()
    for index in range(NUM_SLOTS - 1):
        board.register(f"ui{index}", 1.0, is_supervised=False)
    with pytest.raises(RuntimeError, match="slots are taken"):
        board.register("one more", 1.0, is_supervised=False)
    assert [p.name for p in board.find_lost(now_ns() + 11 * 10**9)] == ["iocontrol"]


def test_a_lease_is_alive_while_its_owner_beats(board: SafetyBoard) -> None:
    lease = board.register("ui", 0.05, is_supervised=False)
    assert board.slot_is_alive(lease.slot, lease.pid)
    assert not board.slot_is_alive(lease.slot, lease.pid + 1)  # another process's slot
    assert not board.slot_is_alive(lease.slot, lease.pid, now_ns() + 10**8)
    assert not board.slot_is_alive(NUM_SLOTS, lease.pid)


def test_a_link_finds_lost_processes_and_asks_for_a_braking_estop(board: SafetyBoard) -> None:
    board.register("halui", 0.001, is_supervised=True)
    link = SafetyLink.open("task", 1.0)
    time.sleep(0.01)
    tick = link.tick()
    assert [p.name for p in tick.lost] == ["halui"]
    assert tick.estop is not None and tick.estop.is_braking and "halui" in tick.estop.reason
    assert link.tick().estop is None
    link.close()


def test_a_loss_found_by_a_process_that_cannot_tell_is_told_by_one_that_can(
    board: SafetyBoard,
) -> None:
    board.register("task", 0.001, is_supervised=True)
    time.sleep(0.01)
    halui = SafetyLink.open("halui", 1.0, is_reporter=False)
    tick = halui.tick()
    assert tick.lost == [] and "task" in tick.estop.reason  # found: E-stop asked for
    motion = SafetyLink.open("motion", 1.0)
    assert [p.name for p in motion.tick().lost] == ["task"]  # told here, once
    launcher_view = SafetyBoard.attach()
    assert launcher_view.take_unreported() == []
    launcher_view.close()
    halui.close()
    motion.close()
