# xhc-hb04.tcl -- the XHC-HB04 wireless USB pendant: its driver and connections.
#
# Role (as LinuxCNC's hallib/xhc-hb04.tcl): [HAL]HALFILE = LIB:xhc-hb04.tcl, after the
# files that make the machine, with [HAL]HALUI set and:
#   [XHC_HB04_CONFIG]
#   layout = 1 | 2 | FILE     button layout: LIB:xhc-hb04-layout<N>.cfg, or a .cfg file
#   coords = x y z a          up to four axis letters for the pendant's switch and display
#   coefs = 1 1 1 1           low-pass filter of the wheel per coordinate (0 < coef <= 1)
#   scales = 1 1 1 1          wheel counts scale per coordinate (may be negative)
#   mpg_accels = ...          acceleration while jogging with the wheel, per coordinate
#   threadname = servo-thread
#   sequence = 1..5           the step sizes the step button goes through
#   jogmode = normal|vnormal  vnormal: joint/axis jog-vel-mode
#   require_pendant = yes|no  no: the driver makes its pins without a pendant plugged in
#   inch_or_mm = in|mm        the pendant's inch icon
#   [XHC_HB04_BUTTONS]
#   NAME = PIN                button NAME (xhc-hb04.button-NAME) drives PIN; "" for none;
#                             start-pause = std_start_pause for run/pause/resume via halui
# It starts the driver (loadusr -W xhc-hb04 [-x] [-s N] -I CFG -H); if the driver cannot
# start (not installed, pendant not plugged in) it says so and the machine starts without
# the pendant. Then: pendant_util (xhc_hb04_util) filters and scales the wheel, which jogs
# the selected axis and joint and counts feed and spindle override through halui; the
# pendant shows positions, feed and spindle speed (signals pendant:*).

source [file join $::env(HALLIB_DIR) hal_procs_lib.tcl]
source [file join $::env(HALLIB_DIR) util_lib.tcl]

set ::progname xhc-hb04.tcl
set ::xhc_hb04_quiet [expr {[namespace exists ::tp] && [::tp::passnumber] == 0}]

proc xhc_problem {text} {
  puts stderr "$::progname: $text"
}

proc xhc_fail {text} {
  xhc_problem $text
  exit 1
}

# net, with failures collected and reported at the end rather than stopping the file
proc makenet {args} {
  if {[catch {eval net $args} problem]} {
    lappend ::makenet_problems "signal <[lindex $args 0]>: $problem"
  }
}

# the signal on an output pin if it has one (other files may have named it), else NAME
proc existing_outpin_signame {pin name} {
  set state [is_connected $pin signal]
  switch $state {
    not_connected {return $name}
    is_output {return $signal}
    default {return -code error "existing_outpin_signame: $pin is $state"}
  }
}

# one value of the config section: lower-case keys win over upper-case ones
proc xhc_config {key {default ""}} {
  foreach name [list [string tolower $key] [string toupper $key]] {
    if {[info exists ::XHC_HB04_CONFIG($name)]} {
      return [string trim [lindex $::XHC_HB04_CONFIG($name) end] "{}"]
    }
  }
  return $default
}

proc std_start_pause_button {} {
  makenet pendant:start-or-pause <= xhc-hb04.button-start-pause => pendant_util.start-or-pause
  makenet pendant:program-resume <= pendant_util.resume => halui.program.resume
  makenet pendant:program-pause <= pendant_util.pause => halui.program.pause
  makenet pendant:program-run <= pendant_util.run => halui.program.run halui.mode.auto
  foreach {pin name util} {is-idle is-idle is-idle is-paused is-paused is-paused
                           is-running is-running is-running} {
    makenet [existing_outpin_signame halui.program.$pin pendant:$name] \
        <= halui.program.$pin => pendant_util.$util
  }
}

proc connect_pins {} {
  set done {}
  foreach key [lsort [array names ::XHC_HB04_BUTTONS]] {
    set name [string tolower $key]
    if {$name in $done} continue
    lappend done $name
    set target [lindex $::XHC_HB04_BUTTONS($key) 0]
    if {$target eq "\"\"" || $target eq ""} continue
    if {$name eq "start-pause" && [string tolower $target] eq "std_start_pause"} {
      std_start_pause_button
      continue
    }
    if {[string tolower $target] eq "caution"} {
      xhc_problem "skipping button $name marked <$target>"
      continue
    }
    set button xhc-hb04.button-$name
    if {!$::xhc_hb04_quiet} {
      if {![pin_exists $button]} {
        xhc_problem "<$button> pin does not exist, continuing"
        continue
      }
      if {![pin_exists $target]} {
        xhc_problem "<$target> target pin does not exist, continuing"
        continue
      }
    }
    makenet pendant:$name <= $button => $target
  }
}

proc wheel_setup {jogmode} {
  # per coordinate: filter coefficient, scale, optional wheel acceleration
  set coefs [xhc_config coefs "1 1 1 1"]
  set scales [xhc_config scales "1 1 1 1"]
  set accels [xhc_config mpg_accels]
  # the s32 jog counts are scaled by k so that fractional scales (0.1, 0.01) work
  set k 100.0
  setp pendant_util.k $k
  makenet pendant:jog-prescale <= xhc-hb04.jog.scale => pendant_util.divide-by-k-in
  makenet pendant:jog-scale <= pendant_util.divide-by-k-out
  makenet pendant:wheel-counts <= xhc-hb04.jog.counts
  makenet pendant:wheel-counts-neg <= xhc-hb04.jog.counts-neg

  # the pendant's switch and display know x y z a: a coordinate takes its own letter's
  # place when it has one, the others take the places left
  set labels {x y z a}
  set free {0 1 2 3}
  set coords [xhc_config coords "x y z a"]
  foreach coord $coords {
    set place [lsearch $labels $coord]
    if {$place >= 0} {
      set index($coord) $place
      set free [lsearch -all -inline -not $free $place]
    }
  }
  foreach coord $coords {
    if {![info exists index($coord)]} {
      set index($coord) [lindex $free 0]
      set free [lrange $free 1 end]
    }
  }

  foreach coord $coords {
    set i $index($coord)
    set label [lindex $labels $i]
    set COORD [string toupper $coord]
    set coef [lindex $coefs $i]
    if {$coef eq ""} {set coef 1.0}
    if {$coef < 0} {set coef [expr {-$coef}]}
    if {$coef > 1} {set coef .5}
    set scale [lindex $scales $i]
    if {$scale eq ""} {set scale 1.0}
    setp pendant_util.coef$i $coef
    setp pendant_util.scale$i [expr {$k * $scale}]
    if {$label ne $coord} {
      puts "$::progname: coord $coord uses the pendant's $label switch and display"
    }

    makenet [existing_outpin_signame halui.axis.$coord.pos-feedback pendant:pos-$coord] \
        <= halui.axis.$coord.pos-feedback => xhc-hb04.$label.pos-absolute
    makenet [existing_outpin_signame halui.axis.$coord.pos-relative pendant:pos-rel-$coord] \
        <= halui.axis.$coord.pos-relative => xhc-hb04.$label.pos-relative
    makenet pendant:jog-scale => axis.$coord.jog-scale
    makenet pendant:wheel-counts => pendant_util.in$i
    makenet pendant:wheel-counts-$coord-filtered <= pendant_util.out$i => axis.$coord.jog-counts
    makenet pendant:jog-$coord <= xhc-hb04.jog.enable-$label => axis.$coord.jog-enable
    if {$jogmode eq "vnormal"} {
      setp axis.$coord.jog-vel-mode 1
    }
    set accel [lindex $accels $i]
    set fraction 1.0
    if {$accel ne ""} {
      if {![info exists ::AXIS_${COORD}(MAX_ACCELERATION)]} {
        xhc_fail "missing INI setting: \[AXIS_$COORD\]MAX_ACCELERATION"
      }
      set fraction [expr {abs($accel) / [lindex [set ::AXIS_${COORD}(MAX_ACCELERATION)] 0]}]
    }
    setp axis.$coord.jog-accel-fraction $fraction

    # the joint of the coordinate too, where the kinematics tell it (trivkins)
    if {[catch {joint_number_for_axis $coord} joint]} {
      xhc_problem $joint
      continue
    }
    if {![pin_exists joint.$joint.jog-scale]} {
      xhc_fail "not configured for coords = $coords: no joint.$joint.* pins"
    }
    if {![info exists ::JOINT_${joint}(MAX_ACCELERATION)]} {
      xhc_fail "missing INI setting: \[JOINT_$joint\]MAX_ACCELERATION"
    }
    makenet pendant:jog-scale => joint.$joint.jog-scale
    makenet pendant:wheel-counts-$coord-filtered => joint.$joint.jog-counts
    makenet pendant:jog-$coord => joint.$joint.jog-enable
    set fraction 1.0
    if {$accel ne ""} {
      set fraction [expr {abs($accel) / [lindex [set ::JOINT_${joint}(MAX_ACCELERATION)] 0]}]
    }
    setp joint.$joint.jog-accel-fraction $fraction
    if {$jogmode eq "vnormal"} {
      setp joint.$joint.jog-vel-mode 1
    }
  }

  # the wheel also counts the overrides, while their buttons say so
  setp halui.feed-override.scale 0.01
  makenet pendant:wheel-counts => halui.feed-override.counts
  setp halui.spindle.0.override.scale 0.01
  makenet pendant:wheel-counts => halui.spindle.0.override.counts
  makenet pendant:feed-override-enable => halui.feed-override.count-enable \
      <= xhc-hb04.jog.enable-feed-override
  makenet pendant:spindle-override-enable => halui.spindle.0.override.count-enable \
      <= xhc-hb04.jog.enable-spindle-override

  # what the pendant shows
  makenet [existing_outpin_signame motion.current-vel pendant:feed-value] \
      <= motion.current-vel => xhc-hb04.feed-value
  makenet [existing_outpin_signame spindle.0.speed-out-rps-abs pendant:spindle-rps] \
      <= spindle.0.speed-out-rps-abs => xhc-hb04.spindle-rps
  makenet [existing_outpin_signame halui.max-velocity.value pendant:jog-speed] \
      <= halui.max-velocity.value
  makenet [existing_outpin_signame halui.feed-override.value pendant:feed-override] \
      <= halui.feed-override.value => xhc-hb04.feed-override
  makenet [existing_outpin_signame halui.spindle.0.override.value pendant:spindle-override] \
      <= halui.spindle.0.override.value => xhc-hb04.spindle-override
}

# begin ----------------------------------------------------------------
if {![info exists ::HAL(HALUI)]} {
  xhc_fail "\[HAL\]HALUI is not set"
}
if {![array exists ::XHC_HB04_CONFIG]} {
  xhc_fail "missing section \[XHC_HB04_CONFIG\]"
}
if {![array exists ::XHC_HB04_BUTTONS]} {
  xhc_fail "missing section \[XHC_HB04_BUTTONS\]"
}

set layout [xhc_config layout 2]
if {$layout in {1 2}} {
  set layout LIB:xhc-hb04-layout$layout.cfg
}
if {[catch {find_file_in_hallib_path $layout $::env(INI_FILE_NAME)} cfg]} {
  xhc_problem "cannot find the layout file <$layout>: continuing without xhc-hb04"
  return
}

set driver [list loadusr -W xhc-hb04]
if {[string tolower [xhc_config require_pendant yes]] ne "no"} {
  lappend driver -x  ;# pins only once a pendant is plugged in
}
if {[xhc_config sequence] ne ""} {
  lappend driver -s [xhc_config sequence]
}
lappend driver -I $cfg -H
if {[catch $driver problem]} {
  xhc_problem "[join $driver]: $problem\n  Is it plugged in? Are permissions correct?\
    Continuing without xhc-hb04"
  return
}

if {[string match in* [xhc_config inch_or_mm mm]]} {
  setp xhc-hb04.inch-icon 1
}
set jogmode [xhc_config jogmode normal]
if {$jogmode ni {normal vnormal}} {
  xhc_problem "unknown jogmode <$jogmode>, using normal"
  set jogmode normal
}
set coords [xhc_config coords "x y z a"]
if {[llength [lsort -unique $coords]] != [llength $coords]} {
  xhc_fail "coords must be unique, not: <$coords>"
}
if {[llength $coords] > 4} {
  xhc_fail "max no. of coords is 4 <$coords>"
}

loadrt xhc_hb04_util names=pendant_util
addf pendant_util [xhc_config threadname servo-thread]

# the connections look at pins, which in pass 0 of [HAL]TWOPASS do not exist yet
if {![namespace exists ::tp] || [::tp::passnumber] != 0} {
  connect_pins
  wheel_setup $jogmode
}
if {[info exists ::makenet_problems]} {
  xhc_problem "failed to make some connections:\n  [join $::makenet_problems "\n  "]"
}
