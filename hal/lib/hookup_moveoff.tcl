# hookup_moveoff.tcl -- put the moveoff component between motion and the joints.
#
# Role (as LinuxCNC's hallib/hookup_moveoff.tcl): [HAL]HALFILE = LIB:hookup_moveoff.tcl,
# after the files that connect joint.N.motor-pos-cmd and joint.N.motor-pos-fb. For every
# [JOINT_N] section (N < 9) with a TYPE:
#   - loadrt moveoff names=mv personality=<highest joint + 1>, with mv.read-inputs just
#     before motion-command-handler and mv.write-outputs just after motion-controller;
#   - joint.N.motor-pos-cmd -> mv.pos-N (signal hu:pos-N); mv.pos-plusoffset-N drives
#     what the command drove before (hu:plus-N);
#   - what drove the feedback -> mv.fb-N (hu:fb-N, also to the feedback's other readers);
#     mv.fb-minusoffset-N -> joint.N.motor-pos-fb (hu:minus-N);
#   - a joint whose command was looped straight back as its feedback (one signal) gets
#     mv.pos-plusoffset-N -> mv.fb-N and the loop's other readers (hu:shortcircuit-N);
#   - mv.offset-vel-N, offset-accel-N, offset-max-N, offset-min-N from [MOVEOFF_N]
#     MAX_VELOCITY, MAX_ACCELERATION, MAX_LIMIT, MIN_LIMIT, else from [JOINT_N];
#   - mv.epsilon, waypoint-sample-secs, waypoint-threshold, backtrack-enable from
#     [MOVEOFF] EPSILON, WAYPOINT_SAMPLE_SECS, WAYPOINT_THRESHOLD, BACKTRACK_ENABLE.
# The component's name is mv, as moveoff_gui expects. In pass 0 of [HAL]TWOPASS it does
# nothing (the HAL it inspects does not exist yet).

source [file join $::env(HALLIB_DIR) hal_procs_lib.tcl]

set ::m mv

proc moveoff_joints {} {
  set joints {}
  for {set j 0} {$j < 9} {incr j} {
    if {[info exists ::JOINT_${j}(TYPE)]} {
      lappend joints $j
    }
  }
  return $joints
}

proc moveoff_install {joints} {
  thread_info threads
  if {![info exists threads(motion-controller,threadname)]} {
    return -code error "motion-controller is in no thread"
  }
  set thread $threads(motion-controller,threadname)
  hal loadrt moveoff personality=[expr {[lindex $joints end] + 1}] names=$::m
  hal addf $::m.write-outputs $thread [expr {$threads($thread,motion-controller) + 1}]
  set handler $threads($thread,motion-command-handler)
  hal addf $::m.read-inputs $thread [expr {$handler > 1 ? $handler - 1 : 1}]
}

# the signal on PIN and the pins linked to it; then PIN is unlinked
proc moveoff_take {pin} {
  if {![connection_info found $pin] || $found(signame) eq ""} {
    return -code error "<$pin> not connected as expected"
  }
  get_netlist inputs output ios $found(signame)
  hal unlinkp $pin
  return [list $found(signame) $inputs $output]
}

# relink each pin of PINS but SKIP to SIGNAL
proc moveoff_relink {signal pins skip} {
  foreach pin $pins {
    if {$pin eq $skip} continue
    hal unlinkp $pin
    hal net $signal $pin
  }
}

proc moveoff_hookup {j} {
  set cmd joint.$j.motor-pos-cmd
  set fb joint.$j.motor-pos-fb
  lassign [moveoff_take $cmd] cmd_signal cmd_inputs
  lassign [moveoff_take $fb] fb_signal fb_inputs fb_output
  set is_loop [expr {$cmd_signal eq $fb_signal}]

  hal delsig $cmd_signal
  hal net hu:pos-$j $cmd $::m.pos-$j
  if {!$is_loop} {
    hal net hu:plus-$j $::m.pos-plusoffset-$j
    moveoff_relink hu:plus-$j $cmd_inputs $fb
  }
  hal net hu:minus-$j $::m.fb-minusoffset-$j $fb
  if {$is_loop} {
    hal net hu:shortcircuit-$j $::m.pos-plusoffset-$j $::m.fb-$j
    moveoff_relink hu:shortcircuit-$j $cmd_inputs $fb
  } else {
    hal delsig $fb_signal
    hal net hu:fb-$j $::m.fb-$j {*}$fb_output
    moveoff_relink hu:fb-$j $fb_inputs $fb
  }
}

proc moveoff_last {section key} {
  # the last value of [section]key, or "" (a key may be repeated)
  if {![info exists ::${section}($key)]} {
    return ""
  }
  return [lindex [set ::${section}($key)] end]
}

proc moveoff_settings {joints} {
  foreach j $joints {
    foreach {pin key} {offset-vel MAX_VELOCITY offset-accel MAX_ACCELERATION
                       offset-max MAX_LIMIT offset-min MIN_LIMIT} {
      set value [moveoff_last MOVEOFF_$j $key]
      if {$value eq ""} {
        set value [moveoff_last JOINT_$j $key]
      }
      if {$value ne ""} {
        hal setp $::m.$pin-$j $value
      }
    }
  }
  foreach {pin key} {epsilon EPSILON waypoint-sample-secs WAYPOINT_SAMPLE_SECS
                     waypoint-threshold WAYPOINT_THRESHOLD backtrack-enable BACKTRACK_ENABLE} {
    set value [moveoff_last MOVEOFF $key]
    if {$value ne ""} {
      hal setp $::m.$pin $value
    }
  }
}

if {[namespace exists ::tp] && [::tp::passnumber] == 0} {
  return
}
set joints [moveoff_joints]
if {![llength $joints]} {
  return -code error "hookup_moveoff.tcl: no \[JOINT_N\] section has a TYPE"
}
moveoff_install $joints
foreach j $joints {
  moveoff_hookup $j
}
moveoff_settings $joints
