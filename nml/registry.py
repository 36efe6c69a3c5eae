"""The message registry: type numbers <-> classes and names (NML-050, NML-051, NML-072)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from nml.errors import NmlRegistryError

if TYPE_CHECKING:
    from nml.message import MessageKind, NMLmsg


class Registry:
    def __init__(self) -> None:
        self._by_type: dict[int, type[NMLmsg]] = {}
        self._by_name: dict[str, type[NMLmsg]] = {}

    def register(self, cls: type[NMLmsg]) -> None:
        existing = self._by_type.get(cls.TYPE)
        if existing is not None and existing.__qualname__ != cls.__qualname__:
            raise NmlRegistryError(
                f"message type {cls.TYPE} of {cls.__name__} is already used by {existing.__name__}"
            )
        named = self._by_name.get(cls.NAME)
        if named is not None and named.TYPE != cls.TYPE:
            raise NmlRegistryError(
                f"message name {cls.NAME} is already registered with type {named.TYPE}"
            )
        # Re-declaring the same class (module reloaded) replaces it.
        self._by_type[cls.TYPE] = cls
        self._by_name[cls.NAME] = cls

    def unregister(self, cls: type[NMLmsg]) -> None:
        """Remove a class (tests that declare throwaway messages)."""
        if self._by_type.get(cls.TYPE) is cls:
            del self._by_type[cls.TYPE]
        if self._by_name.get(cls.NAME) is cls:
            del self._by_name[cls.NAME]

    def by_type(self, type_id: int) -> type[NMLmsg] | None:
        return self._by_type.get(type_id)

    def by_name(self, name: str) -> type[NMLmsg] | None:
        return self._by_name.get(name)

    def symbol(self, type_id: int) -> str:
        """The name of a type number, like LinuxCNC's emc_symbol_lookup()."""
        cls = self._by_type.get(type_id)
        return cls.NAME if cls is not None else f"UNKNOWN_TYPE_{type_id}"

    def of_kind(self, kind: MessageKind) -> list[type[NMLmsg]]:
        return [cls for cls in self._by_type.values() if cls.KIND is kind]

    def all(self) -> list[type[NMLmsg]]:
        return sorted(self._by_type.values(), key=lambda cls: cls.TYPE)


REGISTRY = Registry()
