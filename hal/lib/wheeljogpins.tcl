# wheeljogpins.tcl -- enable wheel jogging on every axis and joint.
#
# Role (as LinuxCNC's hallib/wheeljogpins.tcl): [HAL]HALFILE = LIB:wheeljogpins.tcl [SCALE]
# sets axis.L.jog-enable 1 and axis.L.jog-scale SCALE for L in x y z a b c u v w, and the
# same for joint.0 .. joint.8 (SCALE defaults to 1). It stops quietly at the first pin
# that does not exist.

set scale 1
if {[llength $::argv] == 1} {
  set scale [lindex $::argv 0]
}
catch {
  foreach letter {x y z a b c u v w} {
    setp axis.$letter.jog-enable 1
    setp axis.$letter.jog-scale $scale
  }
  for {set joint 0} {$joint < 9} {incr joint} {
    setp joint.$joint.jog-enable 1
    setp joint.$joint.jog-scale $scale
  }
}
