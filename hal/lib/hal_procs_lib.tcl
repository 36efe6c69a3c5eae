# hal_procs_lib.tcl -- procedures for Tcl HAL files that look at the HAL made so far.
#
# Role (as LinuxCNC's hallib/hal_procs_lib.tcl):
#   pin_exists NAME                     1 if the pin exists, else 0
#   connection_info ARRAY PIN           1 and ARRAY(owner type direction value separator
#                                       signame) filled in, or 0 if there is no such pin
#   is_connected PIN ?SIGVAR?           is_input, is_output, is_io or not_connected (and
#                                       the signal's name in SIGVAR)
#   thread_info ARRAY                   the threads: ARRAY(threadnames), ($t,period),
#                                       ($t,fp), ($t,$funct) = its 1-based place in $t,
#                                       ($t,index,last), (motion-command-handler,threadname)
#                                       (...,index), (motion-controller,threadname) (...,index);
#                                       returns motion-controller's thread
#   get_netlist INPINS OUTPIN IOPINS SIG    the pins linked to signal SIG, by direction
#   find_file_in_hallib_path FILE ?INI? a HAL file by LinuxCNC's rules (LIB:, absolute,
#                                       the INI file's folder, then $::env(HALLIB_DIR))
# They read the HAL through ::haltcl::pin_info, ::haltcl::signal_info and
# ::haltcl::thread_info (structured data, not the text of show).
package require Hal

proc pin_exists {name} {
  return [expr {[llength [::haltcl::pin_info $name]] > 0}]
}

proc connection_info {result_name pinname} {
  upvar $result_name result
  set found [::haltcl::pin_info $pinname]
  if {![llength $found]} {
    return 0
  }
  lassign $found result(owner) result(type) result(direction) result(value) result(signame)
  set result(separator) ""
  if {$result(signame) ne ""} {
    set result(separator) [dict get {IN <== OUT ==> I/O <=>} $result(direction)]
  }
  return 1
}

proc is_connected {pinname {signame {}}} {
  if {$signame ne ""} {
    upvar $signame linked_to
  }
  set linked_to ""
  if {![connection_info found $pinname] || $found(signame) eq ""} {
    return not_connected
  }
  set linked_to $found(signame)
  return [dict get {IN is_input OUT is_output I/O is_io} $found(direction)]
}

proc thread_info {ay_name} {
  upvar $ay_name ay
  foreach thread [::haltcl::thread_info] {
    lassign $thread name period fp functs
    lappend ay(threadnames) $name
    set ay($name,period) $period
    set ay($name,fp) $fp
    set index 0
    foreach funct $functs {
      incr index
      set ay($name,$funct) $index
      set ay($name,index,last) $index
      if {$funct in {motion-command-handler motion-controller}} {
        set ay($funct,threadname) $name
        set ay($funct,index) $index
      }
    }
  }
  if {![info exists ay(motion-controller,threadname)]} {
    return ""
  }
  if {![info exists ay(motion-command-handler,threadname)]} {
    return -code error "thread_info: motion-command-handler not found"
  }
  if {$ay(motion-controller,threadname) ne $ay(motion-command-handler,threadname)} {
    return -code error "thread_info: mot funcs on separate threads"
  }
  if {$ay(motion-command-handler,index) > $ay(motion-controller,index)} {
    return -code error "thread_info: mot funcs OUT-OF-SEQUENCE"
  }
  return $ay(motion-controller,threadname)
}

proc get_netlist {inpins_name outpin_name iopins_name signame} {
  upvar $inpins_name inpins
  upvar $outpin_name outpin
  upvar $iopins_name iopins
  set found [::haltcl::signal_info $signame]
  if {![llength $found]} {
    return -code error "get_netlist: no signal <$signame>"
  }
  lassign $found type inpins outpin iopins
}

proc find_file_in_hallib_path {filename {inifile .}} {
  set name [lindex $filename end]
  if {[string match LIB:* $name]} {
    set path [file join $::env(HALLIB_DIR) [string range $name 4 end]]
  } elseif {[file pathtype $name] eq "absolute"} {
    set path $name
  } else {
    set path [file join [file dirname $inifile] $name]
    if {![file readable $path]} {
      set path [file join $::env(HALLIB_DIR) $name]
    }
  }
  if {[file readable $path]} {
    return $path
  }
  return -code error "find_file_in_hallib_path: cannot find: <$filename>"
}
