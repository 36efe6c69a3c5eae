"""The ``cnc`` command: one entry point whose subcommands live in their own packages.

Each subcommand is a ``module:function`` taking the remaining argv and returning an exit
status, imported only when used so that ``cnc rs274`` does not pay for HAL or NML imports.
"""

from __future__ import annotations

import importlib
import sys

from cnc.stdio import keep_lines_whole

# Subcommand -> (entry point, one-line help). Add a line here to add a subcommand.
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("nml.demo:main", "two processes exchanging commands and status over NML"),
    "nml": ("nml.cli:main", "check, list and dump NML buffers (check|ls|dump)"),
    "rs274": ("task.interp.cli:main", "run the RS274NGC interpreter standalone, like rs274"),
    "halcmd": ("hal.halcmd:main", "HAL command interpreter, like halcmd"),
    "halrun": ("hal.halrun:main", "start a realtime host, run a HAL file, tear down"),
    "hal": ("hal.tools:main", "HAL tools (watch|sample|stream)"),
    "run": ("cnc.launcher:main", "start a machine from an INI file, like linuxcnc"),
    "top": ("cnc.ui.top:main", "live status view of the running machine, like linuxcnctop"),
    "sh": ("cnc.ui.sh:main", "local command shell and script runner"),
    "rsh": ("cnc.ui.rsh:main", "LinuxCNC's remote shell, a TCP server (linuxcncrsh, port 5007)"),
    "haltcl": ("hal.haltcl:main", "run a Tcl HAL file, like haltcl (-i INI FILE [ARGS])"),
    "ui": ("cnc.ui.web.server:main", "operator UI in the browser (ui web [INI] [--host --port])"),
    "api-key": ("cnc.apikeys:main", "the web API's keys (create NAME --scope S|list|revoke NAME)"),
    "latency-test": ("cnc.latency:main", "realtime thread jitter idle and loaded, with a verdict"),
    "bridge": ("cnc.bridges:main", "MQTT or OPC UA bridge of a machine (bridge mqtt|opcua INI)"),
    "inivar": ("cnc.ini:inivar", "print one INI value, like inivar (-var KEY -sec SECTION)"),
}


def _usage() -> str:
    lines = ["usage: cnc SUBCOMMAND [ARGS...]", "", "subcommands:"]
    for name, (_, text) in SUBCOMMANDS.items():
        lines.append(f"  {name:<8} {text}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if not args or args[0] in ("-h", "--help", "help"):
        print(_usage())
        return 0 if args else 2
    name, rest = args[0], args[1:]
    if name not in SUBCOMMANDS:
        print(f"cnc: unknown subcommand '{name}'\n\n{_usage()}", file=sys.stderr)
        return 2
    module_name, func_name = SUBCOMMANDS[name][0].split(":")
    keep_lines_whole()
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and module_name.startswith(exc.name):
            print(f"cnc: subcommand '{name}' is not available yet ({exc})", file=sys.stderr)
            return 2
        raise
    return int(getattr(module, func_name)(rest) or 0)


if __name__ == "__main__":
    sys.exit(main())
