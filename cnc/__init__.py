"""A CNC machine controller with LinuxCNC's architecture, written in Python.

The public Python API (``cnc.stat``, ``cnc.command``, ``cnc.error_channel``) lives here once
the task/launcher issue lands; the other packages are the processes:
``nml`` (message buffers), ``hal``, ``motion``, ``task`` (with the RS274NGC interpreter),
``iocontrol``.
"""
