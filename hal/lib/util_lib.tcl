# util_lib.tcl -- small helpers for Tcl HAL files.
#
# Role (as LinuxCNC's hallib/util_lib.tcl):
#   show_context             print the file's arguments and INI file
#   show_ini                 print every INI section array (::SECTION(KEY))
#   show_env                 print the environment
#   joint_number_for_axis L  the joint of axis letter L (trivkins: its place in
#                            [TRAJ]COORDINATES); an error for other kinematics
# show_context and show_ini print nothing in pass 0 of [HAL]TWOPASS.

set ::util_lib_quiet [expr {[namespace exists ::tp] && [::tp::passnumber] == 0}]

proc show_context {} {
  if {$::util_lib_quiet} return
  puts "show_context: argv0=$::argv0"
  puts "show_context:  argv=$::argv"
  foreach arg $::argv {
    puts "show_context:   arg=$arg"
  }
  puts "show_context: INI_FILE_NAME=$::env(INI_FILE_NAME)"
}

proc show_ini {} {
  if {$::util_lib_quiet} return
  foreach name [lsort [uplevel #0 {info vars}]] {
    if {$name in {TP auto_index tcl_platform env}} continue
    if {[array exists ::$name]} {
      parray ::$name
    }
  }
}

proc show_env {} {
  parray ::env
}

proc joint_number_for_axis {axis_letter} {
  set kinematics [lindex $::env(KINS_KINEMATICS) 0]
  set coordinates [string toupper $::env(TRAJ_COORDINATES)]
  if {[string first " " $coordinates] < 0} {
    set coordinates [split $coordinates ""]
  }
  set letter [string toupper $axis_letter]
  if {$kinematics ne "trivkins"} {
    return -code error "joint_number_for_axis: <$letter> unavailable for kinematics:\
      <$::env(KINS_KINEMATICS)>"
  }
  set joint [lsearch $coordinates $letter]
  if {$joint < 0} {
    return -code error "joint_number_for_axis <$letter> not in $::env(TRAJ_COORDINATES)"
  }
  return $joint
}
