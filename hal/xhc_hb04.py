"""``xhc-hb04``: the HAL side of LinuxCNC's XHC-HB04 pendant driver (``loadusr xhc-hb04``).

    xhc-hb04 [-I BUTTON_CFG] [-H] [-x] [-s 1..5] [-h]

As LinuxCNC's driver, run by its ``xhc-hb04.tcl`` (``loadusr -W xhc-hb04 ...``): with ``-H``
it makes component ``xhc-hb04`` with LinuxCNC's pins (positions, feed and spindle in; one
``button-NAME`` out per ``BUTTON=CODE:button-NAME`` line of the ``[XHC-HB04]`` section of
BUTTON_CFG; the wheel's jog pins out; ``connected``, ``require_pendant``, ``stepsize``), then
waits for the pendant (USB 10CE:EB70). Without ``-x`` the pins are made and ready at once
and the machine starts with ``connected`` false; with ``-x`` (``require_pendant = yes``) they
are made only once a pendant is seen, and after 10 s without one the driver exits with
status 1, so that ``loadusr -W`` fails and the Tcl file goes on without the pendant: what a
LinuxCNC user with no pendant plugged in sees. Without ``-H`` (LinuxCNC's simulation mode)
no HAL component is made.

Talking to a plugged-in pendant (its USB reports: wheel, buttons, display) is not done
here: when one is found the driver says so and its pins stay as they are, ``connected``
false.
"""

from __future__ import annotations

import getopt
import signal
import sys
import time
from pathlib import Path
from typing import Any

NAME = "xhc-hb04"
VENDOR, PRODUCT = "10ce", "eb70"  # the pendant's USB identity
MAX_WAIT_S = 10  # -x: how long the pendant is waited for before the driver gives up
POLL_S = 1.0
USB_DEVICES = Path("/sys/bus/usb/devices")
# -s N: the step sizes (in 0.001 units) the step button goes through
STEP_SEQUENCES = {
    1: (1, 10, 100, 1000),
    2: (1, 5, 10, 20),
    3: (1, 10, 100),
    4: (1, 5, 10, 20, 50, 100),
    5: (1, 10, 50, 100, 1000),
}
AXES = "xyza"
# buttons that also get one pin per axis (NAME-x ... NAME-a)
PER_AXIS_BUTTONS = ("button-zero", "button-goto-zero", "button-half")
USAGE = f"""Usage: {NAME} [-I button-cfg-file] [-h] [-H] [-s n]
 -I button-cfg-file: configuration file defining the MPG keyboard layout
 -h: usage (this)
 -H: run in real-time HAL mode (run in simulation mode by default)
 -x: wait for pendant detection before creating HAL pins
 -s: step sequence (multiplied by 0.001 unit):
     1: 1,10,100,1000 (default)
     2: 1,5,10,20
     3: 1,10,100
     4: 1,5,10,20,50,100
     5: 1,10,50,100,1000
"""


class ConfigError(Exception):
    """A button configuration file that cannot be used (file, line and cause)."""


def read_buttons(path: str) -> list[tuple[int, str]]:
    """(code, pin name) of each ``BUTTON=XN:button-NAME`` line of section ``[XHC-HB04]``."""
    try:
        lines = Path(path).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise ConfigError(f"{path}: {exc.strerror}") from None
    buttons = []
    section = ""
    for number, raw in enumerate(lines, 1):
        line = raw.split("#", 1)[0].split(";", 1)[0].strip()
        if line.startswith("["):
            section = line.strip("[]").strip()
            continue
        key, sep, value = line.partition("=")
        if section != "XHC-HB04" or not sep or key.strip() != "BUTTON":
            continue
        code, colon, pin = value.strip().partition(":")
        try:
            if not colon or not pin.strip():
                raise ValueError
            buttons.append((int(code, 16), pin.split()[0]))
        except ValueError:
            raise ConfigError(
                f"{path}:{number}: BUTTON wants HEXCODE:button-name, not '{value.strip()}'"
            ) from None
    return buttons


def pin_specs(buttons: list[tuple[int, str]]) -> list[tuple[str, str, str]]:
    """(name, type, direction) of every pin the driver makes, in LinuxCNC's order."""
    specs = [(f"{axis}.pos-absolute", "float", "in") for axis in AXES]
    specs += [(f"{axis}.pos-relative", "float", "in") for axis in AXES]
    specs += [
        (name, "float", "in")
        for name in ("feed-value", "feed-override", "spindle-rps", "spindle-override")
    ]
    for _, pin in buttons:
        specs.append((pin, "bit", "out"))
        if pin in PER_AXIS_BUTTONS:
            specs += [(f"{pin}-{axis}", "bit", "out") for axis in AXES]
    specs += [
        ("sleeping", "bit", "out"),
        ("connected", "bit", "out"),
        ("stepsize-up", "bit", "in"),
        ("stepsize-down", "bit", "in"),
        ("stepsize", "s32", "out"),
        ("require_pendant", "bit", "out"),
        ("inch-icon", "bit", "in"),
    ]
    specs += [
        (f"jog.enable-{what}", "bit", "out")
        for what in ("off", *AXES, "feed-override", "spindle-override")
    ]
    specs += [
        ("jog.scale", "float", "out"),
        ("jog.counts", "s32", "out"),
        ("jog.counts-neg", "s32", "out"),
        ("jog.velocity", "float", "out"),
        ("jog.max-velocity", "float", "in"),
        ("jog.increment", "float", "out"),
    ]
    specs += [(f"jog.{sign}-{axis}", "bit", "out") for axis in AXES for sign in ("plus", "minus")]
    return specs


def is_pendant_plugged_in(devices: Path | None = None) -> bool:
    """Whether a USB device with the pendant's vendor and product ids is present (in
    ``devices``, by default the system's USB device folder)."""
    try:
        entries = list((devices or USB_DEVICES).iterdir())
    except OSError:
        return False
    for entry in entries:
        try:
            vendor = (entry / "idVendor").read_text().strip().lower()
            product = (entry / "idProduct").read_text().strip().lower()
        except OSError:
            continue
        if (vendor, product) == (VENDOR, PRODUCT):
            return True
    return False


class Driver:
    """The component and the wait for a pendant."""

    def __init__(self, buttons: list[tuple[int, str]], step_sequence: tuple[int, ...]) -> None:
        self.buttons = buttons
        self.step_sequence = step_sequence
        self.comp: Any = None
        self.pins: dict[str, Any] = {}
        self.is_stopping = False

    def make_pins(self, is_pendant_required: bool) -> None:
        from hal.api import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_OUT, HAL_S32, component

        types = {"bit": HAL_BIT, "float": HAL_FLOAT, "s32": HAL_S32}
        directions = {"in": HAL_IN, "out": HAL_OUT}
        self.comp = component(NAME)
        for name, kind, direction in pin_specs(self.buttons):
            self.pins[name] = self.comp.newpin(name, types[kind], directions[direction])
        self.pins["require_pendant"].set(is_pendant_required)
        self.pins["stepsize"].set(self.step_sequence[0])
        self.comp.ready()

    def wait_for_pendant(self, give_up_s: float | None) -> bool:
        """Until a pendant is plugged in (True), the driver is stopped or ``give_up_s``
        has passed (False)."""
        print(f"{NAME}: waiting for XHC-HB04 device", flush=True)
        waited = 0.0
        while not self.is_stopping:
            if is_pendant_plugged_in():
                print(f"{NAME}: found XHC-HB04 device", flush=True)
                return True
            if give_up_s is not None:
                waited += POLL_S
                if waited >= give_up_s / 2:
                    print(f"{NAME}: waiting for XHC-HB04 device ({waited:.0f})", flush=True)
                if waited > give_up_s:
                    print(f"{NAME}: MAX_WAIT_SECS exceeded, exiting", flush=True)
                    return False
            time.sleep(POLL_S)
        return False

    def idle(self) -> None:
        while not self.is_stopping:
            time.sleep(POLL_S)

    def close(self) -> None:
        if self.comp is not None:
            self.comp.exit()


def main(argv: list[str] | None = None) -> int:
    try:
        opts, _ = getopt.getopt(sys.argv[1:] if argv is None else argv, "I:hHxs:")
    except getopt.GetoptError as exc:
        print(f"{NAME}: {exc}\n{USAGE}", file=sys.stderr)
        return 1
    options = dict(opts)
    if "-h" in options:
        print(USAGE, file=sys.stderr)
        return 1
    try:
        sequence = STEP_SEQUENCES[int(options.get("-s", "1"))]
    except (ValueError, KeyError):
        print(f"{NAME}: -s wants 1..5, not '{options['-s']}'\n{USAGE}", file=sys.stderr)
        return 1
    try:
        buttons = read_buttons(options["-I"]) if "-I" in options else []
    except ConfigError as exc:
        print(f"{NAME}: {exc}", file=sys.stderr)
        return 1
    is_hal = "-H" in options
    is_pendant_required = "-x" in options
    driver = Driver(buttons, sequence)

    def stop(*_: object) -> None:
        driver.is_stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    try:
        if is_hal and not is_pendant_required:
            driver.make_pins(is_pendant_required)
        if not driver.wait_for_pendant(MAX_WAIT_S if is_pendant_required else None):
            return 1 if is_pendant_required and not driver.is_stopping else 0
        if is_hal and driver.comp is None:
            driver.make_pins(is_pendant_required)
        print(
            f"{NAME}: talking to the pendant is not supported here: its pins stay "
            "as they are (connected false)",
            file=sys.stderr,
            flush=True,
        )
        driver.idle()
        return 0
    finally:
        driver.close()


if __name__ == "__main__":
    sys.exit(main())
