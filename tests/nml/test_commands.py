"""nml/commands.py: handlers declared with @handler, refusals, and the one place where an
unexpected exception becomes an internal-error refusal."""

from __future__ import annotations

import pytest

from nml import emc
from nml.commands import (
    QUEUE,
    RUNNING,
    Handlers,
    InternalError,
    Refused,
    carry_out,
    handled_by,
    handler,
    unmet,
)
from nml.message import RCS_STATUS, Requires


class Receiver:
    def __init__(self) -> None:
        self.done: list[str] = []

    @handler(emc.EMC_TASK_PLAN_PAUSE)
    def _pause(self, cmd: emc.NMLmsg) -> None:
        self.done.append("command")

    @handler(emc.EMC_TASK_PLAN_PAUSE, emc.EMC_TASK_PLAN_END, table=QUEUE)
    def _queued(self, cmd: emc.NMLmsg) -> None:
        self.done.append(f"queued {cmd.NAME}")

    @handler(emc.EMC_TASK_PLAN_RESUME)
    def _refuse(self, cmd: emc.NMLmsg) -> None:
        raise Refused("nothing is paused")

    @handler(emc.EMC_TASK_PLAN_STEP)
    def _quietly(self, cmd: emc.NMLmsg) -> None:
        raise Refused("said already", is_quiet=True)

    @handler(emc.EMC_TASK_PLAN_RUN)
    def _run(self, cmd: emc.NMLmsg) -> str:
        return RUNNING

    @handler(emc.EMC_TASK_PLAN_INIT)
    def _bug(self, cmd: emc.NMLmsg) -> None:
        raise KeyError("oops")


def test_each_table_holds_its_own_handlers() -> None:
    receiver = Receiver()
    commands, queue = Handlers(receiver), Handlers(receiver, table=QUEUE)
    commands[emc.EMC_TASK_PLAN_PAUSE](emc.EMC_TASK_PLAN_PAUSE())
    queue[emc.EMC_TASK_PLAN_PAUSE](emc.EMC_TASK_PLAN_PAUSE())
    assert receiver.done == ["command", "queued EMC_TASK_PLAN_PAUSE"]
    assert set(queue) == {emc.EMC_TASK_PLAN_PAUSE, emc.EMC_TASK_PLAN_END}
    assert emc.EMC_TASK_PLAN_END not in commands
    assert set(handled_by(Receiver)) == set(commands)


def test_a_key_with_two_handlers_is_refused() -> None:
    class Twice:
        @handler("stop")
        def one(self) -> None: ...

        @handler("stop")
        def two(self) -> None: ...

    with pytest.raises(TypeError, match="stop has two handlers"):
        Handlers(Twice())


def test_carry_out_answers_done_refused_quiet_and_running() -> None:
    table = Handlers(Receiver())

    def answer(cls: type) -> object:
        return carry_out("task", table[cls], cls())

    assert answer(emc.EMC_TASK_PLAN_PAUSE).status == RCS_STATUS.DONE
    refused = answer(emc.EMC_TASK_PLAN_RESUME)
    assert (refused.status, refused.reason) == (RCS_STATUS.ERROR, "nothing is paused")
    quiet = answer(emc.EMC_TASK_PLAN_STEP)
    assert (quiet.status, quiet.reason) == (RCS_STATUS.ERROR, None)
    assert answer(emc.EMC_TASK_PLAN_RUN).status == RCS_STATUS.EXEC


def test_an_unexpected_exception_is_an_internal_error_refusal() -> None:
    table = Handlers(Receiver())
    answer = carry_out("task", table[emc.EMC_TASK_PLAN_INIT], emc.EMC_TASK_PLAN_INIT())
    assert answer.status == RCS_STATUS.ERROR
    assert isinstance(answer.refusal, InternalError)
    assert answer.reason == "task: internal error in EMC_TASK_PLAN_INIT: KeyError: 'oops'"


def test_requires_names_what_is_missing() -> None:
    state, mode = emc.EMC_TASK_STATE_ENUM, emc.EMC_TASK_MODE_ENUM
    needs_on = Requires(state=state.ON)
    assert unmet(needs_on, state.OFF, mode.MANUAL) == "machine must be on, it is off"
    assert unmet(needs_on, state.ON, mode.MANUAL) is None
    needs_mdi = Requires(mode=mode.MDI)
    assert unmet(needs_mdi, state.ON, mode.AUTO) == "must be in MDI mode, not AUTO"
    assert unmet(None, state.ESTOP, mode.AUTO) is None
    assert emc.EMC_JOG_CONT.REQUIRES == emc.ON_IN_MANUAL
    assert unmet(emc.EMC_JOG_STOP.REQUIRES, state.ESTOP, mode.AUTO) is None  # never refused
