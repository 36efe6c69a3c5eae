"""command() against a fake task in another process: the EXEC/DONE/ERROR contract."""

from __future__ import annotations

import cnc


def test_mdi_then_wait_complete_is_done(fake_task) -> None:
    task = fake_task()
    c = cnc.command()
    c.mdi("G0 X1")
    assert c.wait_complete() == cnc.RCS_DONE
    received = task.next_command()
    assert received["type"] == "EMC_TASK_PLAN_EXECUTE"
    assert received["fields"]["command"] == "G0 X1"
    assert received["fields"]["serial_number"] == c.serial


def test_failed_command_reports_error_and_the_operator_sees_why(fake_task) -> None:
    fake_task("--fail", "G1 X1")
    errors = cnc.error_channel()
    c = cnc.command()
    c.mdi("G1 X1")
    assert c.wait_complete() == cnc.RCS_ERROR
    assert errors.poll() == (cnc.OPERATOR_ERROR, "failed: G1 X1")


def test_unfinished_command_times_out(fake_task) -> None:
    fake_task("--hang", "M66 P0 L3 Q100")
    c = cnc.command()
    c.mdi("M66 P0 L3 Q100")
    assert c.wait_complete(0.2) == -1
    s = cnc.stat()
    s.poll()
    assert (s.echo_serial_number, s.state) == (c.serial, cnc.RCS_EXEC)


def test_wait_complete_follows_the_last_command(fake_task) -> None:
    task = fake_task()
    c = cnc.command()
    c.mode(cnc.MODE_MDI)
    c.mdi("G0 X2")
    first, second = c.serial - 1, c.serial
    assert c.wait_complete(timeout=5) == cnc.RCS_DONE
    assert [task.next_command()["fields"]["serial_number"] for _ in range(2)] == [first, second]


def test_command_methods_need_a_running_controller() -> None:
    c = cnc.command()
    try:
        c.mdi("G0 X1")
    except cnc.error as exc:
        assert "not running" in str(exc)
    else:
        raise AssertionError("no cnc.error")


def test_status_after_wait_complete_shows_the_result(fake_task) -> None:
    fake_task()
    c, s = cnc.command(), cnc.stat()
    c.mode(cnc.MODE_MDI)
    s.poll()
    assert s.echo_serial_number == c.serial  # a command returns once task has taken it
    assert c.wait_complete() == cnc.RCS_DONE
    s.poll()
    assert (s.task_mode, s.state) == (cnc.MODE_MDI, cnc.RCS_DONE)


def test_error_msg_reaches_every_error_channel(fake_task) -> None:
    fake_task()
    channels = [cnc.error_channel(), cnc.error_channel()]
    c = cnc.command()
    c.error_msg("probe failed")
    c.text_msg("tool changed")
    assert c.wait_complete() == cnc.RCS_DONE
    for channel in channels:
        assert channel.poll() == (cnc.OPERATOR_ERROR, "probe failed")
        assert channel.poll() == (cnc.OPERATOR_TEXT, "tool changed")
