"""Manual mode jogs joints until every joint is homed, then world axes (LinuxCNC's
emcTaskSetMode; its tests/motion/jogwheel-axis asks for manual mode again after homing)."""

from __future__ import annotations

import cnc


def test_manual_mode_is_free_until_homed_then_teleop(machine) -> None:
    c, s = machine.command, machine.stat
    for state in (cnc.STATE_ESTOP_RESET, cnc.STATE_ON):
        c.state(state)
        assert c.wait_complete() == cnc.RCS_DONE
    c.mode(cnc.MODE_MANUAL)
    assert c.wait_complete() == cnc.RCS_DONE
    s.poll()
    assert s.motion_mode == cnc.TRAJ_MODE_FREE
    c.home(-1)
    c.wait_complete()
    machine.until(lambda st: all(st.homed[:3]) and st.inpos)
    c.mode(cnc.MODE_MANUAL)  # already manual: asked again, now homed
    assert c.wait_complete() == cnc.RCS_DONE
    s.poll()
    assert s.motion_mode == cnc.TRAJ_MODE_TELEOP
    c.mode(cnc.MODE_MDI)
    assert c.wait_complete() == cnc.RCS_DONE
    c.mdi("G0 X1")
    assert c.wait_complete() == cnc.RCS_DONE
    machine.until(lambda st: st.inpos and st.motion_mode == cnc.TRAJ_MODE_COORD)
    c.mode(cnc.MODE_MANUAL)
    assert c.wait_complete() == cnc.RCS_DONE
    s.poll()
    assert s.motion_mode == cnc.TRAJ_MODE_TELEOP
