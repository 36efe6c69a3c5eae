"""``mqtt-publisher``: LinuxCNC 2.9's HAL-to-MQTT program, for ``loadusr`` in a HAL file.

    loadusr -W mqtt-publisher [--dryrun] [--mqtt-broker=HOST] [--mqtt-port=N]
        [--mqtt-user=NAME] [--mqtt-password=SECRET] [--mqtt-prefix=TOPIC]
        keys=pin-or-signal[,...] [keys=...]

As LinuxCNC's: options come before the ``keys=`` arguments (several are merged); a HAL
component ``mqtt-publisher`` has the pins ``enable`` (bit in, 1), ``period`` (u32 in,
seconds, 10) and ``lastpublish`` (u32 out, seconds since the epoch of the last message).
While ``enable`` is set, one JSON object is published on the prefix topic at once and then
every ``period`` seconds: each key (a pin, signal or parameter name) with its value (a bit
as true/false), plus ``"mqtt-publisher.period"``; QoS 0, not retained. A key that names
nothing is left out, with one warning. ``--dryrun`` prints the message and connects to no
broker.

Differences: the program runs until ``unload`` (SIGTERM) or until its component is gone,
with or without halui (LinuxCNC's stops when halui is not loaded); a new ``period`` takes
effect at once rather than after the current wait, and a period of 0 publishes every 0.1 s
(LinuxCNC's would publish without pause).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import hal

COMPONENT = "mqtt-publisher"
DEFAULT_PREFIX = "devices/linuxcnc/machine"
WAIT_SLICE_S = 0.1  # how often a wait looks at the pins again (and the shortest period)


def parse_arguments(argv: list[str]) -> tuple[argparse.Namespace, list[str]]:
    """The options and the merged keys; exits with the usage (status 1) without arguments."""
    parser = argparse.ArgumentParser(
        prog="mqtt-publisher",
        usage="mqtt-publisher [options] keys=pin1,pin2,... [keys=...]",
        description="Publish HAL pin, signal and parameter values to an MQTT broker.",
    )
    parser.add_argument("--dryrun", action="store_true", help="print, connect to no broker")
    parser.add_argument("--mqtt-broker", default="localhost", metavar="FQDN")
    parser.add_argument("--mqtt-port", type=int, default=1883, metavar="PORTNUMBER")
    parser.add_argument("--mqtt-user", metavar="USERNAME")
    parser.add_argument("--mqtt-password", metavar="PASSWORD")
    parser.add_argument("--mqtt-prefix", default=DEFAULT_PREFIX, metavar="PREFIX")
    parser.add_argument("args", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    # an INI substitution that is empty ([MQTT]DRYRUN =) gives an empty word: not an argument
    opts = parser.parse_args([word for word in argv if word])
    if not opts.args or (not opts.dryrun and not (opts.mqtt_broker and opts.mqtt_prefix)):
        parser.print_help()
        sys.exit(1)
    keys = []
    for word in opts.args:
        if word.startswith("keys="):
            keys += [key for key in word.removeprefix("keys=").split(",") if key]
    return opts, keys


def connect(opts: argparse.Namespace) -> Any:
    """A paho client connecting (and reconnecting) in its own thread."""
    import paho.mqtt.client as mqtt

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)

    def on_connect(_client: Any, _data: Any, _flags: Any, reason: Any, _props: Any) -> None:
        print(f"info: MQTT connected: {reason}", flush=True)

    def on_disconnect(_client: Any, _data: Any, _flags: Any, reason: Any, _props: Any) -> None:
        print(f"warning: MQTT disconnected: {reason}", flush=True)

    client.on_connect = on_connect
    client.on_connect_fail = lambda *_: print("warning: MQTT connection failed", flush=True)
    client.on_disconnect = on_disconnect
    if opts.mqtt_user is not None:
        client.username_pw_set(opts.mqtt_user, opts.mqtt_password)
    client.connect_async(opts.mqtt_broker, opts.mqtt_port, keepalive=60)
    client.loop_start()
    return client


class Publisher:
    """The component and its loop: read the keys, publish, wait ``period``."""

    def __init__(self, keys: list[str], prefix: str, client: Any | None) -> None:
        self.keys = keys
        self.prefix = prefix
        self.client = client  # None: dry run
        self.missing: set[str] = set()
        self.comp = hal.component(COMPONENT)
        self.comp.newpin("enable", hal.HAL_BIT, hal.HAL_IN)
        self.comp.newpin("period", hal.HAL_U32, hal.HAL_IN)
        self.comp.newpin("lastpublish", hal.HAL_U32, hal.HAL_OUT)
        self.comp["enable"] = True
        self.comp["period"] = 10
        self.comp.ready()

    def message(self) -> dict[str, Any]:
        data: dict[str, Any] = {}
        for key in self.keys:
            try:
                data[key] = hal.get_value(key)
            except RuntimeError:
                if key not in self.missing:
                    self.missing.add(key)
                    print(f"warning: Missing pin {key} not sent to MQTT", flush=True)
        data[f"{COMPONENT}.period"] = self.comp["period"]
        return data

    def publish(self) -> None:
        text = json.dumps(self.message())
        if self.client is None:
            print(f"info: Not publishing MQTT message ({self.prefix}): {text}", flush=True)
        else:
            print(f"info: Publishing MQTT message ({self.prefix}): {text}", flush=True)
            self.client.publish(self.prefix, text)
        self.comp["lastpublish"] = int(time.time())

    def run(self) -> None:
        """Until SIGTERM (``unload``) or until the component is gone (``unload all``)."""
        last = None
        while hal.component_exists(COMPONENT):
            now = time.monotonic()
            if self.comp["enable"] and (last is None or now - last >= self.comp["period"]):
                self.publish()
                last = now
            time.sleep(WAIT_SLICE_S)


def main(argv: list[str] | None = None) -> int:
    opts, keys = parse_arguments(sys.argv[1:] if argv is None else argv)
    print("Preparing LinuxCNC2MQTT", flush=True)
    client = None if opts.dryrun else connect(opts)
    try:
        Publisher(keys, opts.mqtt_prefix, client).run()
    except KeyboardInterrupt:  # SIGTERM from halcmd's unload (hal's default handling)
        pass
    finally:
        if client is not None:
            client.disconnect()
            client.loop_stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
