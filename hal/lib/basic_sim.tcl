# basic_sim.tcl -- the HAL of a simulated machine, for any joints and axes.
#
# Role (as LinuxCNC's hallib/basic_sim.tcl): [HAL]HALFILE = LIB:basic_sim.tcl [options]
# builds, from [KINS]KINEMATICS, [KINS]JOINTS, [TRAJ]COORDINATES and [EMCMOT]:
#   motion with a pass-through servo loop per joint          (core_sim in sim_lib.tcl)
#   velocity and acceleration signals per joint              (make_ddts; -no_make_ddts)
#   a simulated home switch per joint                        (simulated_home; -no_simulated_home)
#   tool changes through hal_manualtoolchange                (-no_use_hal_manualtoolchange)
#   a simulated spindle with encoder                         (sim_spindle; -no_sim_spindle)
# then writes the equivalent HAL commands to ./<inifile>_cmds.hal.

source [file join $::env(HALLIB_DIR) sim_lib.tcl]

proc basic_sim_wants {part} {
  # a part is made unless the HALFILE entry says -no_<part> (any case)
  return [expr {[lsearch -nocase $::argv -no_$part] < 0}]
}

if {[catch check_ini_items problem]} {
  puts stderr "basic_sim.tcl: $problem"
  exit 1
}
set joints [lindex $::KINS(JOINTS) 0]
set base_period 0
if {[info exists ::EMCMOT(BASE_PERIOD)]} {
  set base_period [lindex $::EMCMOT(BASE_PERIOD) 0]
}
core_sim [get_traj_coordinates] $joints [lindex $::EMCMOT(SERVO_PERIOD) 0] \
    $base_period $::EMCMOT(EMCMOT)

set save_options {}
if {[basic_sim_wants make_ddts]} {
  make_ddts $joints
}
if {[basic_sim_wants simulated_home]} {
  simulated_home $joints
}
if {[basic_sim_wants use_hal_manualtoolchange]} {
  use_hal_manualtoolchange
  lappend save_options use_hal_manualtoolchange
}
if {[basic_sim_wants sim_spindle]} {
  sim_spindle
}

save_hal_cmds ./[file rootname [file tail $::env(INI_FILE_NAME)]]_cmds.hal $save_options
