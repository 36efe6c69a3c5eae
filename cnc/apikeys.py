"""Named API keys with scopes for the web server's API (``cnc api-key``, cnc/ui/web/API.md).

A key is shown once, when it is created: ``cnc_<id>_<secret>`` (``id``: 8 hex digits that
find its record; ``secret``: 32 random bytes). The keys file (``api_keys.json`` next to the
INI, written atomically) keeps, per key, its name, scopes, id, salt and the scrypt hash of
the whole key, never the key itself. Checking a key compares hashes in constant time; a
key that checked once is remembered (by its SHA-256) until the file changes, so that each
request does not pay scrypt's deliberate cost.

Scopes: ``read`` (status, subscriptions, files, tools and offsets to read), ``operate``
(commands that move or change the machine's state) and ``configure`` (writes to the tool
table, the offsets table and the program files). ``operate`` and ``configure`` each imply
``read``; neither implies the other.

    cnc api-key create NAME --scope read|operate|configure [--scope ...] [--ini INI]
    cnc api-key list [--ini INI]
    cnc api-key revoke NAME [--ini INI]
"""

from __future__ import annotations

import argparse
import hashlib
import hmac
import json
import os
import re
import secrets
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from cnc.atomicfile import atomic_write_text

READ, OPERATE, CONFIGURE = "read", "operate", "configure"
SCOPES = (READ, OPERATE, CONFIGURE)
ALL_SCOPES = frozenset(SCOPES)
FILE_NAME = "api_keys.json"
FORMAT_VERSION = 1
# scrypt's cost: about 16 MB and tens of milliseconds a check (paid once per key and file)
SCRYPT = {"n": 2**14, "r": 8, "p": 1}
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")
KEY_PATTERN = re.compile(r"cnc_([0-9a-f]{8})_([A-Za-z0-9_-]{20,})")


class ApiKeyError(Exception):
    """A keys file that cannot be read or changed, or a bad name or scope; str() says why."""


@dataclass(frozen=True)
class Identity:
    """Who a request is: a key's name (or "loopback", "token"), and its scopes."""

    name: str
    scopes: frozenset[str]

    def allows(self, scope: str) -> bool:
        if scope == READ:
            return bool(self.scopes)  # every scope reads
        return scope in self.scopes


LOOPBACK = Identity("loopback", ALL_SCOPES)


def keys_file_for(ini: str | os.PathLike[str]) -> Path:
    """The keys file of a machine: ``api_keys.json`` in its INI file's folder."""
    return Path(ini).resolve().parent / FILE_NAME


def _hash(key: str, salt: bytes) -> bytes:
    return hashlib.scrypt(key.encode(), salt=salt, **SCRYPT, dklen=32)


def normal_scopes(scopes: list[str] | tuple[str, ...]) -> list[str]:
    """The scopes, checked and in canonical order; ApiKeyError for an unknown one."""
    unknown = sorted(set(scopes) - ALL_SCOPES)
    if unknown:
        raise ApiKeyError(f"unknown scope {unknown[0]!r} (scopes: {', '.join(SCOPES)})")
    if not scopes:
        raise ApiKeyError(f"give at least one scope ({', '.join(SCOPES)})")
    return [scope for scope in SCOPES if scope in scopes]


class KeyStore:
    """The keys file of one machine: read when it changes, checked per request."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._records: list[dict[str, object]] = []
        self._stamp: tuple[int, int] | None = None  # (mtime_ns, size) of what was read
        self._checked: dict[bytes, Identity] = {}  # sha256(key) -> identity, this file

    # ---------------------------------------------------------------- the file
    def records(self) -> list[dict[str, object]]:
        """The file's records (re-read when it changed); ApiKeyError for a bad file."""
        with self._lock:
            self._refresh()
            return list(self._records)

    def _refresh(self) -> None:
        try:
            info = self.path.stat()
        except FileNotFoundError:
            self._records, self._stamp, self._checked = [], None, {}
            return
        stamp = (info.st_mtime_ns, info.st_size)
        if stamp == self._stamp:
            return
        self._records = _parse(self.path)
        self._stamp, self._checked = stamp, {}

    def _write(self, records: list[dict[str, object]]) -> None:
        text = json.dumps({"version": FORMAT_VERSION, "keys": records}, indent=2) + "\n"
        atomic_write_text(self.path, text)
        os.chmod(self.path, 0o600)  # hashes only, but nobody else's business
        self._stamp = None

    def has_keys(self) -> bool:
        return bool(self.records())

    # ---------------------------------------------------------------- changes
    def create(self, name: str, scopes: list[str]) -> str:
        """A new key named ``name`` with ``scopes``; the key (shown only now)."""
        if not NAME_PATTERN.fullmatch(name):
            raise ApiKeyError(f"{name!r}: a key's name is letters, digits, '_', '.', '-'")
        ordered = normal_scopes(scopes)
        with self._lock:
            self._refresh()
            if any(record["name"] == name for record in self._records):
                raise ApiKeyError(f"a key named {name!r} exists already (revoke it first)")
            key_id = secrets.token_hex(4)
            key = f"cnc_{key_id}_{secrets.token_urlsafe(32)}"
            salt = secrets.token_bytes(16)
            record = {"name": name, "scopes": ordered, "id": key_id, "salt": salt.hex(),
                      "scrypt": _hash(key, salt).hex(), "created": _now()}  # fmt: skip
            self._write([*self._records, record])
        return key

    def revoke(self, name: str) -> None:
        with self._lock:
            self._refresh()
            kept = [record for record in self._records if record["name"] != name]
            if len(kept) == len(self._records):
                raise ApiKeyError(f"no key named {name!r} in {self.path}")
            self._write(kept)

    # ---------------------------------------------------------------- checking
    def checked(self, key: str) -> Identity | None:
        """The identity of a key that checked already against this file (fast: no scrypt),
        or None (unknown yet, or not a key: ``identify`` tells)."""
        with self._lock:
            try:
                self._refresh()
            except ApiKeyError:
                return None
            return self._checked.get(hashlib.sha256(key.encode()).digest())

    def identify(self, key: str) -> Identity | None:
        """The identity of a key, or None (unknown, revoked, malformed)."""
        found = KEY_PATTERN.fullmatch(key)
        if found is None:
            return None
        digest = hashlib.sha256(key.encode()).digest()
        with self._lock:
            try:
                self._refresh()
            except ApiKeyError:
                return None  # a damaged file admits nobody (cnc api-key list says why)
            known = self._checked.get(digest)
            if known is not None:
                return known
            records = [r for r in self._records if r["id"] == found.group(1)]
        for record in records:
            salt = bytes.fromhex(str(record["salt"]))
            if hmac.compare_digest(_hash(key, salt), bytes.fromhex(str(record["scrypt"]))):
                identity = Identity(str(record["name"]), frozenset(record["scopes"]))  # type: ignore[arg-type]
                with self._lock:
                    self._checked[digest] = identity
                return identity
        return None


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


def _parse(path: Path) -> list[dict[str, object]]:
    """The records of a keys file, each checked; ApiKeyError naming the file and cause."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ApiKeyError(f"{path}: cannot read: {exc.strerror}") from None
    except ValueError as exc:
        raise ApiKeyError(f"{path}: not JSON: {exc}") from None
    if not isinstance(data, dict) or data.get("version") != FORMAT_VERSION:
        raise ApiKeyError(f"{path}: not a keys file of version {FORMAT_VERSION}")
    records = data.get("keys")
    if not isinstance(records, list):
        raise ApiKeyError(f"{path}: 'keys' must be a list")
    for number, record in enumerate(records, 1):
        fields = ("name", "scopes", "id", "salt", "scrypt")
        if not isinstance(record, dict) or any(key not in record for key in fields):
            raise ApiKeyError(f"{path}: key {number}: needs {', '.join(fields)}")
        try:
            normal_scopes(record["scopes"])
            bytes.fromhex(record["salt"]), bytes.fromhex(record["scrypt"])
        except (ApiKeyError, TypeError, ValueError) as exc:
            raise ApiKeyError(f"{path}: key {number} ({record['name']}): {exc}") from None
    return records


# ------------------------------------------------------------------ cnc api-key
def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cnc api-key", description="Create, list and revoke the web API's keys."
    )
    parser.add_argument("--ini", help="the machine's INI file (default: the running one's)")
    verbs = parser.add_subparsers(dest="verb", required=True)
    create = verbs.add_parser("create", help="create a key and print it (shown only once)")
    create.add_argument("name")
    create.add_argument(
        "--scope", action="append", required=True, choices=SCOPES,
        help="read, operate or configure (repeat for several)",
    )  # fmt: skip
    verbs.add_parser("list", help="the keys: name, scopes, created")
    revoke = verbs.add_parser("revoke", help="remove a key: it stops working at once")
    revoke.add_argument("name")
    for sub in verbs.choices.values():  # --ini after the verb too
        sub.add_argument("--ini", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    return parser


def main(argv: list[str]) -> int:
    """``cnc api-key create|list|revoke``."""
    args = _parser().parse_args(argv)
    ini = args.ini
    if ini is None:
        from cnc.ui.controller import running_ini  # (the CLI only: it loads the API)

        ini = running_ini()
        if ini is None:
            print("cnc api-key: no machine runs: give --ini INI", file=sys.stderr)
            return 2
    store = KeyStore(keys_file_for(ini))
    try:
        if args.verb == "create":
            print(store.create(args.name, args.scope))
            print(f"(shown only now; kept hashed in {store.path})", file=sys.stderr)
        elif args.verb == "revoke":
            store.revoke(args.name)
            print(f"revoked {args.name}")
        else:
            for record in store.records():
                scopes = ",".join(record["scopes"])  # type: ignore[arg-type]
                print(f"{record['name']:<24} {scopes:<24} {record.get('created', '')}")
    except ApiKeyError as exc:
        print(f"cnc api-key: {exc}", file=sys.stderr)
        return 1
    return 0
