"""[DISPLAY] user messages shown by HAL pins (GUI-018, GUI-019), as gmoccapy and qtvcp have them.

INI, [DISPLAY] (the k-th value of each key belongs to the k-th message, as in LinuxCNC)::

    MESSAGE_BOLDTEXT = Lube fault          # title; NONE or absent: no title
    MESSAGE_TEXT     = Refill the lube tank
    MESSAGE_DETAILS  = Tank under 10 %     # optional, shown folded
    MESSAGE_TYPE     = okdialog status     # words: status okdialog yesnodialog nonedialog
    MESSAGE_PINNAME  = lube-fault
    MESSAGE_ICON     = WARNING             # optional: INFO WARNING CRITICAL QUESTION

    MULTIMESSAGE_ID = VFD                  # one s32 pin selects one of several messages
    MULTIMESSAGE_VFD_NUMBER = 1
    MULTIMESSAGE_VFD_TYPE   = okdialog status
    MULTIMESSAGE_VFD_TITLE  = VFD error 1
    MULTIMESSAGE_VFD_TEXT   = Overcurrent
    MULTIMESSAGE_VFD_DETAILS / MULTIMESSAGE_VFD_ICON (optional)

Pins of the userspace component ``web`` (gmoccapy's layout, ``gmoccapy.messages.*``):

- ``web.messages.<pinname>`` bit in: a rising edge shows the message. A ``nonedialog`` (no
  button) closes again when the pin falls; the others stay until answered.
- ``web.messages.<id>`` s32 in (MULTIMESSAGE): a change to a configured NUMBER shows that
  message; a change to any other value (e.g. 0) closes the one shown.
- ``<pin>-waiting`` bit out (when a message of the pin has an ok or yes/no dialog): 1 while
  the dialog is open in the pages.
- ``<pin>-response`` bit out (when one has a yes/no dialog): 1 after "Yes", 0 after "No";
  reset to 0 when the dialog shows again.

``status`` posts the text as a notice in every page. A dialog shows in every connected page
(and in pages that connect while it is open); the first answer closes it everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from cnc.ini import IniFile, IniValue

COMPONENT = "web"
PREFIX = "messages"
DIALOG_WORDS = {"okdialog": "ok", "yesnodialog": "yesno", "nonedialog": "none"}
ICONS = ("INFO", "WARNING", "CRITICAL", "QUESTION")


@dataclass(frozen=True)
class UserMessage:
    """One message: ``dialog`` is "ok", "yesno", "none" (no button) or "" (no dialog)."""

    text: str
    title: str = ""
    details: str = ""
    icon: str = "INFO"
    dialog: str = ""
    is_status: bool = False


@dataclass(frozen=True)
class MessagePin:
    """An input pin and the messages its values show: a bit pin shows ``choices[1]``."""

    name: str  # after "web.messages."
    is_multi: bool
    choices: dict[int, UserMessage]

    @property
    def has_waiting(self) -> bool:
        return any(m.dialog in ("ok", "yesno") for m in self.choices.values())

    @property
    def has_response(self) -> bool:
        return any(m.dialog == "yesno" for m in self.choices.values())


def _where(entry: IniValue) -> str:
    return f"{entry.file}:{entry.line}"


def _kind(entry: IniValue, key: str) -> tuple[str, bool]:
    """A TYPE value -> (dialog, is_status); ValueError naming the INI line if unknown."""
    words = entry.value.lower().split()
    unknown = [w for w in words if w != "status" and w not in DIALOG_WORDS]
    dialogs = [DIALOG_WORDS[w] for w in words if w in DIALOG_WORDS]
    if unknown or not words or len(dialogs) > 1:
        raise ValueError(
            f"{_where(entry)}: [DISPLAY]{key} = {entry.value}: expected status and/or one of "
            f"{', '.join(DIALOG_WORDS)}"
        )
    return (dialogs[0] if dialogs else ""), "status" in words


def _column(
    ini: IniFile, key: str, count: int, default: str, problems: list[str]
) -> list[IniValue]:
    """The entries of a repeated key, one per message; ``default`` for all when the key is
    absent, or (with a problem) when it is not given once per message."""
    entries = ini.entries("DISPLAY", key)
    if entries and len(entries) != count:
        problems.append(
            f"{_where(entries[0])}: {len(entries)} [DISPLAY]{key} for {count} messages: "
            f"give one per message; ignored"
        )
        entries = []
    return entries or [IniValue(default, ini.path, 0)] * count


def _icon(entry: IniValue) -> str:
    word = entry.value.strip().upper()
    return word if word in ICONS else "INFO"


def read_message_pins(ini: IniFile) -> tuple[list[MessagePin], list[str]]:
    """The message pins an INI file asks for, and the problems found (each "file:line:
    cause"; a bad message is left out, never fatal)."""
    problems: list[str] = []
    pins: list[MessagePin] = []
    names = ini.findall("DISPLAY", "MESSAGE_PINNAME")
    count = len(names)
    columns = zip(
        names,
        _column(ini, "MESSAGE_TEXT", count, "", problems),
        _column(ini, "MESSAGE_TYPE", count, "status", problems),
        _column(ini, "MESSAGE_BOLDTEXT", count, "NONE", problems),
        _column(ini, "MESSAGE_DETAILS", count, "", problems),
        _column(ini, "MESSAGE_ICON", count, "INFO", problems),
        strict=True,
    )
    for name, text, kind, title, details, icon in columns:
        try:
            dialog, is_status = _kind(kind, "MESSAGE_TYPE")
        except ValueError as exc:
            problems.append(str(exc))
            continue
        shown_title = "" if title.value == "NONE" else title.value
        message = UserMessage(
            text.value, shown_title, details.value, _icon(icon), dialog, is_status
        )
        pins.append(MessagePin(name.strip(), False, {1: message}))
    for ident_entry in ini.entries("DISPLAY", "MULTIMESSAGE_ID"):
        pin = _multimessage(ini, ident_entry, problems)
        if pin is not None:
            pins.append(pin)
    unique: dict[str, MessagePin] = {}
    for pin in pins:
        if pin.name in unique:
            problems.append(
                f"{ini.path}: message pin name {pin.name!r} used twice; the second ignored"
            )
        else:
            unique[pin.name] = pin
    return list(unique.values()), problems


def _multimessage(ini: IniFile, ident: IniValue, problems: list[str]) -> MessagePin | None:
    """The s32 pin of ``MULTIMESSAGE_ID = <ident>`` and its numbered messages."""
    key = f"MULTIMESSAGE_{ident.value.strip()}"
    numbers = ini.entries("DISPLAY", f"{key}_NUMBER")
    count = len(numbers)
    columns = zip(
        numbers,
        _column(ini, f"{key}_TEXT", count, "", problems),
        _column(ini, f"{key}_TYPE", count, "status", problems),
        _column(ini, f"{key}_TITLE", count, "", problems),
        _column(ini, f"{key}_DETAILS", count, "", problems),
        _column(ini, f"{key}_ICON", count, "INFO", problems),
        strict=True,
    )
    choices: dict[int, UserMessage] = {}
    for number, text, kind, title, details, icon in columns:
        try:
            dialog, is_status = _kind(kind, f"{key}_TYPE")
        except ValueError as exc:
            problems.append(str(exc))
            continue
        try:
            value = int(number.value)
        except ValueError:
            problems.append(
                f"{_where(number)}: [DISPLAY]{key}_NUMBER = {number.value}: not a whole number"
            )
            continue
        choices[value] = UserMessage(
            text.value, title.value, details.value, _icon(icon), dialog, is_status
        )
    if not choices:
        problems.append(f"{_where(ident)}: MULTIMESSAGE_ID = {ident.value}: no messages")
        return None
    return MessagePin(ident.value.strip(), True, choices)


@dataclass
class _Watched:
    """A pin's runtime state: the HAL items, the last value seen, the dialog open."""

    pin: MessagePin
    items: dict[str, Any]
    last: int = 0
    shown: UserMessage | None = None  # the message whose dialog is open in the pages


class UserMessages:
    """The HAL component and the dialogs it drives; used from the server's event loop."""

    def __init__(self, pins: list[MessagePin]) -> None:
        self.pins = pins
        self._component: Any = None  # hal.api.component, once open
        self._watched: list[_Watched] = []
        self._own_hal: Any = None  # the Hal opened by open(), closed by close()

    def open(self, hal: Any = None) -> None:
        """Create ``web`` and its pins in ``hal`` (a ``hal.core.Hal``; default: the running
        machine's HAL, never created here). ``HalError`` if that fails."""
        from hal.api import HAL_BIT, HAL_IN, HAL_OUT, HAL_S32, component
        from hal.core import Hal

        try:
            if hal is None:
                hal = self._own_hal = Hal(is_creating=False)
            comp = self._component = component(COMPONENT, hal=hal)
            for pin in self.pins:
                base = f"{PREFIX}.{pin.name}"
                items = {"in": comp.newpin(base, HAL_S32 if pin.is_multi else HAL_BIT, HAL_IN)}
                if pin.has_waiting:
                    items["waiting"] = comp.newpin(f"{base}-waiting", HAL_BIT, HAL_OUT)
                if pin.has_response:
                    items["response"] = comp.newpin(f"{base}-response", HAL_BIT, HAL_OUT)
                self._watched.append(_Watched(pin, items))
            comp.ready()
        except Exception:
            self.close()
            raise

    def close(self) -> None:
        """Remove the component (its pins go with it)."""
        if self._component is not None:
            self._component.exit()
            self._component = None
        self._watched.clear()
        if self._own_hal is not None:
            self._own_hal.close()
            self._own_hal = None

    def poll(self) -> list[dict[str, Any]]:
        """Read the input pins once; the messages for the pages (dialogs, notices)."""
        outgoing: list[dict[str, Any]] = []
        for watched in self._watched:
            value = int(watched.items["in"].get())
            if value == watched.last:
                continue
            watched.last = value
            message = watched.pin.choices.get(value)
            if message is not None:
                outgoing += self._show(watched, message)
            elif watched.shown is not None and (
                watched.pin.is_multi or watched.shown.dialog == "none"
            ):
                outgoing.append(self._close(watched))
        return outgoing

    def _show(self, watched: _Watched, message: UserMessage) -> list[dict[str, Any]]:
        outgoing = []
        if message.is_status:
            words = f"{message.title}: {message.text}" if message.title else message.text
            outgoing.append({"type": "notice", "kind": "display", "text": words})
        if message.dialog:
            watched.shown = message
            if "waiting" in watched.items:
                watched.items["waiting"].set(message.dialog != "none")
            if "response" in watched.items:
                watched.items["response"].set(False)
            outgoing.append(self.dialog_message(watched))
        return outgoing

    def _close(self, watched: _Watched) -> dict[str, Any]:
        watched.shown = None
        if "waiting" in watched.items:
            watched.items["waiting"].set(False)
        return {"type": "dialog_close", "name": watched.pin.name}

    @staticmethod
    def dialog_message(watched: _Watched) -> dict[str, Any]:
        message = watched.shown
        assert message is not None
        return {
            "type": "dialog",
            "name": watched.pin.name,
            "kind": message.dialog,
            "title": message.title,
            "text": message.text,
            "details": message.details,
            "icon": message.icon,
        }

    def open_dialogs(self) -> list[dict[str, Any]]:
        """The dialogs open now (for a page that connects)."""
        return [self.dialog_message(w) for w in self._watched if w.shown is not None]

    def answer(self, name: Any, is_yes: Any) -> dict[str, Any]:
        """The operator answered the dialog of pin ``name``: set -response, clear -waiting;
        the close message for every page. ValueError if no such dialog is open."""
        for watched in self._watched:
            if watched.pin.name == name and watched.shown is not None:
                if watched.shown.dialog == "none":
                    raise ValueError(f"message {name!r} has no button: it closes with its pin")
                if "response" in watched.items and watched.shown.dialog == "yesno":
                    watched.items["response"].set(is_yes is True)
                return self._close(watched)
        raise ValueError(f"no message dialog {name!r} is open")
