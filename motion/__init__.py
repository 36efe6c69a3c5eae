"""Motion controller core (SPEC MOT, KIN, ARCH-007/008/022).

Plain Python objects with no process, NML or HAL dependency, driven once per servo
period by the realtime motion component, on poses of ``nml.pose.Pose`` (x y z a b c
u v w; messages carry them as ``nml.emc.EmcPose``):

- ``motion.kinematics``: kinematics modules loaded by name, one file each named as
  LinuxCNC's module (trivkins, corexykins, xyzac-trt-kins, genserkins, ... and bipod);
  ``loadrt NAME`` finds them there.
- ``motion.free``: the per-joint trapezoidal free-mode planner and its jog rules.
- ``motion.tp``: the coordinated-mode trajectory planner (replaceable, ARCH-008), and
  ``motion.tp.naivecam`` for G64 Q.
- ``motion.teleop``: the teleop velocity-vector planner, and the joint limiter that slows
  teleop motion (axis jogs plus vector) as a whole to keep every joint within its limits.
- ``motion.homing``: the per-joint homing state machine (replaceable, ARCH-008).
- ``motion.joint``: the joint record: position forms, backlash, leadscrew compensation,
  following error.

One servo period, in order:

1. per joint: ``joint.update_feedback(motor_pos_fb)``, and copy the HAL switch inputs
   into ``joint.is_home_switch_on``, ``is_on_pos_limit``, ``is_on_neg_limit``,
   ``is_index_enabled`` (the encoder clears it), ``is_unlocked``;
2. ``homing.step(dt)`` (it sets targets on the joints' free planners);
3. by mode: free: ``joint.pos_cmd = joint.planner.step(dt)``; coord: set
   ``tp.probe_input``, ``pose = tp.step()``, then inverse kinematics into the joints;
   teleop: ``pose = teleop.step(dt)``, then inverse kinematics;
4. per joint: ``joint.update_command(dt)`` gives ``motor_pos_cmd``; check
   ``joint.is_following_error()``;
5. publish status: ``tp.motion_id``, ``distance_to_go``, ``vel``, ``queue_depth``,
   ``is_paused``, ``probe_tripped``/``probe_pos``, ``tp.take_error()``;
   ``homing.take_error()``, ``joint.is_homed``/``is_homing``.

Commands map onto methods: LINE/CIRCLE/PROBE onto ``tp.add_line``/``add_circle``/
``add_probe`` (as many per period as arrive; ``tp.is_full`` refuses more), PAUSE/RESUME/
STEP/ABORT onto ``tp.pause``/``resume``/``step_once``/``abort``, SCALE onto
``tp.set_feed_scale``/``set_rapid_scale`` (and ``planner.scale`` of free planners), JOG_*
onto ``joint.planner.jog_cont``/``jog_incr``/``jog_abs``/``stop``, HOME/UNHOME onto
``homing.home_joint``/``home_all``/``unhome``.
"""
