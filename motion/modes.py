"""Motion's three modes (EMC_TRAJ_STAT.mode, MOT-016): joints planned one by one (free),
the trajectory planner (coordinated) and world-axis jogs (teleop)."""

from nml import emc

FREE, COORD, TELEOP = (
    emc.EMC_TRAJ_MODE_ENUM.FREE,
    emc.EMC_TRAJ_MODE_ENUM.COORD,
    emc.EMC_TRAJ_MODE_ENUM.TELEOP,
)
