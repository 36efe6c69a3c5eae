# sim_lib.tcl -- Tcl procedures that build a simulated machine of any number of joints.
#
# Role (as LinuxCNC's hallib/sim_lib.tcl; basic_sim.tcl calls them):
#   check_ini_items                 the INI keys the procedures need are there
#   get_traj_coordinates            [TRAJ]COORDINATES as a list of lower-case letters
#   setup_kins AXES                 loadrt [KINS]KINEMATICS (with its arguments)
#   core_sim AXES JOINTS SERVO_PERIOD ?BASE_PERIOD? ?EMCMOT?
#                                   motion, and per joint a pass-through pid and a
#                                   sample-and-hold mux2 between command and feedback
#   make_ddts JOINTS                velocity and acceleration of each joint (xy, xyz speeds
#                                   too for trivkins X Y Z)
#   simulated_home JOINTS           a sim_home_switch per joint
#   use_hal_manualtoolchange        tool changes through hal_manualtoolchange
#   sim_spindle                     a simulated spindle with encoder and at-speed
#   save_hal_cmds FILE ?OPTIONS?    write the resulting HAL as a .hal file
#   do_setp PIN VALUE               setp, remembered for save_hal_cmds
#
# The HAL they make, for joint N:
#   J<N>_pid (pid), J<N>_mux (mux2), J<N>_vel J<N>_accel (ddt), J<N>_switch
#   (sim_home_switch); signals J<N>:pos-cmd J<N>:on-pos J<N>:pos-fb J<N>:enable
#   J<N>:vel J<N>:acc J<N>:homesw J<N>:index-enable, sample:enable, estop:loop,
#   tool:prep-loop tool:change-loop (or tool:change tool:changed tool:prep-number),
#   xy:vel xyz:vel (hyp_xy hyp_xyz), and the spindle signals of sim_spindle_encoder.hal.

# [KINS]KINEMATICS' first word and its arguments, e.g. {trivkins coordinates=XZ}
proc ::sim_lib_kins_words {} {
  return [lindex $::KINS(KINEMATICS) end]
}

proc indices_for_trivkins {axes} {
  # trivkins gives joint i to the i-th letter of coordinates= (default all nine)
  if {$axes eq ""} {set axes {x y z a b c u v w}}
  set joint 0
  foreach letter [string tolower $axes] {
    set ::SIM_LIB(jointidx,$letter) $joint
    incr joint
  }
}

proc get_traj_coordinates {} {
  # "X Y Z" or "XYZ" -> {x y z}
  set letters [string map {" " "" "\t" ""} [lindex $::TRAJ(COORDINATES) 0]]
  return [split [string tolower $letters] ""]
}

proc check_ini_items {} {
  foreach {section key} {KINS KINEMATICS KINS JOINTS TRAJ COORDINATES} {
    if {![info exists ::${section}($key)]} {
      return -code error "Missing inifile item: \[$section\]$key"
    }
  }
  set kins [split [sim_lib_kins_words]]
  set module [lindex $kins 0]
  if {[info exists ::DISPLAY(LATHE)] && $module eq "trivkins"
      && [string first "=" $::KINS(KINEMATICS)] < 0} {
    return -code error "trivkins lathe config must specify coordinates=\
      (typically \[KINS\]KINEMATICS = trivkins coordinates=XZ)"
  }
  # trivkins: coordinates= (plus motmod's extra joints) should match [KINS]JOINTS
  set extra_joints 0
  if {[info exists ::EMCMOT(EMCMOT)]} {
    foreach word [split [lindex $::EMCMOT(EMCMOT) 0]] {
      if {[string match num_extrajoints=* $word]} {
        set extra_joints [lindex [split $word =] end]
      }
    }
  }
  if {$module eq "trivkins"} {
    foreach word $kins {
      if {![string match coordinates=* $word]} continue
      set letters [lindex [split $word =] end]
      set expected [expr {[string length $letters] + $extra_joints}]
      if {$expected != [lindex $::KINS(JOINTS) 0]} {
        puts stderr "check_ini_items: WARNING: trivkins coordinates=$letters and\
          $extra_joints extra joints make $expected joints, but \[KINS\]JOINTS is\
          [lindex $::KINS(JOINTS) 0]"
      }
    }
  }
}

proc setup_kins {axes} {
  if {![info exists ::KINS(KINEMATICS)]} {
    puts stderr "setup_kins: no \[KINS\]KINEMATICS, loading trivkins"
    loadrt trivkins
    return
  }
  set words [sim_lib_kins_words]
  if {[catch {eval loadrt $words} problem]} {
    puts stderr "setup_kins: loadrt $words: $problem"
  }
  if {[lindex $words 0] eq "trivkins"} {
    indices_for_trivkins $axes
  }
}

proc core_sim {axes number_of_joints servo_period {base_period 0} {emcmot motmod}} {
  setup_kins $axes

  # motion: [EMCMOT]EMCMOT may carry arguments of its own (num_extrajoints=, ...)
  set words [split [lindex $emcmot 0]]
  set module [lindex $words 0]
  set options [lrange $words 1 end]
  if {[catch {eval loadrt $module $options base_period_nsec=$base_period \
                servo_period_nsec=$servo_period num_joints=$number_of_joints} problem]} {
    puts stderr "core_sim: loadrt $emcmot: $problem"
    exit 1
  }
  addf motion-command-handler servo-thread
  addf motion-controller      servo-thread

  set pids {}
  set muxes {}
  for {set j 0} {$j < $number_of_joints} {incr j} {
    lappend pids J${j}_pid
    lappend muxes J${j}_mux
  }
  loadrt pid  names=[join $pids ,]
  loadrt mux2 names=[join $muxes ,]

  # each pid passes its command straight through (FF0 = 1, every other gain 0): the
  # machine is wired like a servo machine without being one
  foreach pid $pids {
    addf $pid.do-pid-calcs servo-thread
    do_setp $pid.FF0 1.0
    foreach gain {Pgain Dgain Igain FF1 FF2} {
      do_setp $pid.$gain 0
    }
  }
  # each mux2 holds the last position while motion is disabled, as encoders do
  foreach mux $muxes {
    addf $mux servo-thread
  }

  net estop:loop <= iocontrol.0.user-enable-out
  net estop:loop => iocontrol.0.emc-enable-in
  net tool:prep-loop <= iocontrol.0.tool-prepare
  net tool:prep-loop => iocontrol.0.tool-prepared
  net tool:change-loop <= iocontrol.0.tool-change
  net tool:change-loop => iocontrol.0.tool-changed
  net sample:enable <= motion.motion-enabled

  for {set j 0} {$j < $number_of_joints} {incr j} {
    net sample:enable => J${j}_mux.sel
    net J${j}:enable <= joint.$j.amp-enable-out
    net J${j}:enable => J${j}_pid.enable
    net J${j}:pos-cmd <= joint.$j.motor-pos-cmd
    net J${j}:pos-cmd => J${j}_pid.command
    net J${j}:on-pos <= J${j}_pid.output
    net J${j}:on-pos => J${j}_mux.in1
    net J${j}:pos-fb <= J${j}_mux.out
    net J${j}:pos-fb => J${j}_mux.in0
    net J${j}:pos-fb => joint.$j.motor-pos-fb
  }
}

proc make_ddts {number_of_joints} {
  set ddts {}
  for {set j 0} {$j < $number_of_joints} {incr j} {
    lappend ddts J${j}_vel J${j}_accel
  }
  loadrt ddt names=[join $ddts ,]
  foreach ddt $ddts {
    addf $ddt servo-thread
  }
  for {set j 0} {$j < $number_of_joints} {incr j} {
    net J${j}:pos-fb => J${j}_vel.in
    net J${j}:vel <= J${j}_vel.out
    net J${j}:vel => J${j}_accel.in
    net J${j}:acc <= J${j}_accel.out
  }
  # path speeds when the joints of X, Y and Z are known (trivkins)
  foreach letter {x y z} {
    if {![info exists ::SIM_LIB(jointidx,$letter)]} return
    set joint($letter) $::SIM_LIB(jointidx,$letter)
  }
  loadrt hypot names=hyp_xy,hyp_xyz
  addf hyp_xy  servo-thread
  addf hyp_xyz servo-thread
  net J$joint(x):vel => hyp_xy.in0
  net J$joint(x):vel => hyp_xyz.in0
  net J$joint(y):vel => hyp_xy.in1
  net J$joint(y):vel => hyp_xyz.in1
  net J$joint(z):vel => hyp_xyz.in2
  net xy:vel  <= hyp_xy.out
  net xyz:vel <= hyp_xyz.out
}

proc use_hal_manualtoolchange {} {
  loadusr -W hal_manualtoolchange
  # replace core_sim's loop-back
  unlinkp iocontrol.0.tool-change
  unlinkp iocontrol.0.tool-changed
  delsig tool:change-loop
  net tool:change <= iocontrol.0.tool-change
  net tool:change => hal_manualtoolchange.change
  net tool:changed <= hal_manualtoolchange.changed
  net tool:changed => iocontrol.0.tool-changed
  net tool:prep-number <= iocontrol.0.tool-prep-number
  net tool:prep-number => hal_manualtoolchange.number
}

proc simulated_home {number_of_joints} {
  set switches {}
  for {set j 0} {$j < $number_of_joints} {incr j} {
    lappend switches J${j}_switch
  }
  loadrt sim_home_switch names=[join $switches ,]
  foreach switch $switches {
    addf $switch servo-thread
  }
  for {set j 0} {$j < $number_of_joints} {incr j} {
    net J${j}:pos-fb => J${j}_switch.cur-pos
    net J${j}:homesw <= J${j}_switch.home-sw
    net J${j}:homesw => joint.$j.home-sw-in
    # linear joints of an inch machine: the switch 0.1 in away with 0.05 in of
    # hysteresis (the component's defaults suit mm and degrees); searching towards
    # negative means the switch is on the negative side
    set section ::JOINT_$j
    if {[info exists ${section}(TYPE)] && [lindex [set ${section}(TYPE)] 0] ne "ANGULAR"} {
      if {[info exists ::TRAJ(LINEAR_UNITS)]
          && [lindex $::TRAJ(LINEAR_UNITS) 0] in {in inch imperial}} {
        do_setp J${j}_switch.hysteresis 0.05
        do_setp J${j}_switch.home-pos   0.10
      }
      if {[info exists ${section}(HOME_SEARCH_VEL)]
          && [lindex [set ${section}(HOME_SEARCH_VEL)] 0] < 0} {
        do_setp J${j}_switch.home-pos -[getp J${j}_switch.home-pos]
      }
    }
    if {[info exists ${section}(HOME_USE_INDEX)]
        && [lindex [set ${section}(HOME_USE_INDEX)] 0]} {
      net J${j}:index-enable <= joint.$j.index-enable
      net J${j}:index-enable => J${j}_switch.index-enable
    }
  }
}

proc sim_spindle {} {
  loadrt sim_spindle names=sim_spindle
  loadrt limit2  names=limit_speed
  loadrt lowpass names=spindle_mass
  loadrt near    names=near_speed
  loadrt scale   names=rpm_rps

  do_setp sim_spindle.scale 0.01666667   ;# rpm -> rev/s
  do_setp limit_speed.maxv 5000.0        ;# rpm per second
  do_setp spindle_mass.gain .07          ;# inertia of the speed feedback
  do_setp rpm_rps.gain .0167
  do_setp near_speed.scale 1.1           ;# at speed within 10 % ...
  do_setp near_speed.difference 10       ;# ... or within 10 rpm

  net spindle-index-enable <=> spindle.0.index-enable
  net spindle-index-enable <=> sim_spindle.index-enable
  net spindle-pos <= sim_spindle.position-fb
  net spindle-pos => spindle.0.revs

  net spindle-speed-cmd <= spindle.0.speed-out
  net spindle-speed-cmd => limit_speed.in
  net spindle-speed-cmd => near_speed.in1
  net spindle-speed-limited <= limit_speed.out
  net spindle-speed-limited => sim_spindle.velocity-cmd
  net spindle-speed-limited => spindle_mass.in

  net spindle-rpm-filtered <= spindle_mass.out
  net spindle-rpm-filtered => rpm_rps.in
  net spindle-rpm-filtered => near_speed.in2
  net spindle-rps-filtered <= rpm_rps.out
  net spindle-rps-filtered => spindle.0.speed-in
  net spindle-at-speed <= near_speed.out
  net spindle-at-speed => spindle.0.at-speed

  # M19: the spindle is oriented as soon as it is asked to be
  net spindle-orient <= spindle.0.orient
  net spindle-orient => spindle.0.is-oriented

  addf limit_speed  servo-thread
  addf spindle_mass servo-thread
  addf rpm_rps      servo-thread
  addf near_speed   servo-thread
  addf sim_spindle  servo-thread
}

proc save_hal_cmds {savefilename {options ""}} {
  # the HAL made so far, as a .hal file that can replace basic_sim.tcl
  set halfiles [expr {[info exists ::HAL(HALFILE)] ? $::HAL(HALFILE) : ""}]
  set what [expr {[llength $halfiles] > 1 ? "allu" : "all"}]
  set text "# [clock format [clock seconds]]\n#\n"
  append text "# This file:    $savefilename\n"
  append text "# Created by:   [info script]\n"
  append text "# With options: $::argv\n"
  append text "# From inifile: $::env(INI_FILE_NAME)\n"
  append text "# Halfiles:     $halfiles\n#\n"
  append text "# The HAL commands made by [file tail [info script]] (and the HAL files run\n"
  append text "# before it). To use it instead, replace in the INI file\n"
  append text "#     HALFILE = LIB:basic_sim.tcl ...\n# by\n#     HALFILE = $savefilename\n"
  append text "# Input pins on signals without a writer need their setp added by hand.\n#\n"
  if {"use_hal_manualtoolchange" in $options} {
    append text "# user space components\nloadusr -W hal_manualtoolchange\n\n"
  }
  if {[catch {hal save $what} saved]} {
    puts stderr "save_hal_cmds: $savefilename not written: $saved"
    return
  }
  foreach line [split $saved \n] {
    if {[regexp {^loadrt\s+(tpmod|homemod)\M} $line]} {
      append text "#preloaded module: $line\n"
    } else {
      append text "$line\n"
    }
  }
  if {$what eq "all" && [info exists ::SIM_LIB(setp_list)]} {
    append text "# setp commands for unconnected input pins\n"
    foreach {pin value} $::SIM_LIB(setp_list) {
      append text [format "%-3s %-30s %s\n" setp $pin $value]
    }
  }
  # written whole or not at all; a folder we may not write to is no reason to stop
  set partial $savefilename.tmp[pid]
  if {[catch {
    set channel [open $partial w]
    puts -nonewline $channel $text
    close $channel
    file rename -force $partial $savefilename
  } problem]} {
    catch {file delete $partial}
    puts stderr "save_hal_cmds: $savefilename not written: $problem"
  }
}

proc do_setp {pin value} {
  setp $pin $value
  lappend ::SIM_LIB(setp_list) $pin $value
}
