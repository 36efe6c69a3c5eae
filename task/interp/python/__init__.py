"""Embedded Python: LinuxCNC's ``[PYTHON]`` plug-in of the interpreter (PY-001..PY-030).

========== =================================================================
plugin     the plug-in: ``[PYTHON]`` settings, the TOPLEVEL namespace, calls
           into user code (errors, generators), ``;py,`` statements
view       the interpreter as Python code sees it (``self`` in handlers,
           ``interpreter.this``): LinuxCNC's attribute names and types
interpreter, emccanon, emctask, gcode
           the modules user code imports by those names (registered in
           ``sys.modules`` by the plug-in; ``emctask`` only in task,
           ``gcode`` is LinuxCNC's preview interpreter for UIs)
glue       ``stdglue.py``, the standard prolog and epilog functions
           (REMAP-047..052), on the module path after the user's folders
========== =================================================================

User code runs in the interpreter's process and thread, between two steps of a block; it
cannot stop E-stop or abort, which never wait for the interpreter (task answers them
itself).
"""
