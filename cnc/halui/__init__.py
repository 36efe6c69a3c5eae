"""halui: LinuxCNC's HAL user interface, a userspace HAL component driving the machine
(ARCH-028: hosted as an ordinary process through ``loadusr``).

Buttons, switches, knobs and lamps of an operator panel are wired in HAL to ``halui.*`` pins
(``man 1 halui``): e-stop, machine on/off, modes, coolant and lube, program run / pause /
resume / step / stop, homing, jogging (held, incremental, analog; per joint or axis, or on
the selected one), feed / rapid / spindle overrides and max velocity (buttons or encoder
counts), spindle control, and one ``halui.mdi-command-NN`` per [HALUI]MDI_COMMAND line.
halui sends the matching command to task on a button's rising edge, and mirrors the
controller's status on the ``is-*`` and value pins every cycle.

Started by ``cnc run`` when the INI file has ``[HAL]HALUI = halui`` (before the HAL files, as
LinuxCNC's launcher does, so that they can ``net`` its pins), or by ``loadusr halui`` in a
HAL file; the program is ``python -m cnc.halui -ini FILE``.

| module | holds |
|---|---|
| ``config.py`` | what is read from the INI file |
| ``pins.py`` | the pins, LinuxCNC 2.9's names, types and directions |
| ``core.py`` | ``Halui``: edges -> commands, status -> pins, one cycle at a time |
| ``process.py`` | the process: HAL component, NML attachment, main loop |

Differences from LinuxCNC 2.9's halui: the cycle time can be set ([HALUI]CYCLE_TIME, 20 ms
by default, LinuxCNC's fixed value); a bad INI number is an error instead of being ignored;
after an MDI line halui goes back to the previous mode when that line has finished, done or
failed (LinuxCNC waits for the next successful command after a failure).
"""
