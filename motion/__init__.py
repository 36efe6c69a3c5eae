"""Motion controller core (SPEC MOT, KIN, ARCH-007/008/022).

Plain Python objects with no process, NML or HAL dependency, driven once per servo period
by the realtime motion component:

- ``motion.pose``: ``EmcPose`` (x y z a b c u v w) and axis letters.
- ``motion.kinematics``: kinematics modules loaded by name (trivkins, corexy, bipod).
- ``motion.free``: the per-joint trapezoidal free-mode planner and jog rules.
- ``motion.tp``: the coordinated-mode trajectory planner (replaceable, ARCH-008).
- ``motion.homing``: the per-joint homing state machine (replaceable, ARCH-008).
- ``motion.joint``: backlash, leadscrew compensation, following error, soft limits.
"""
