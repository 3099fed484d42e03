"""Registries: where each kind of thing a user adds is found by name.

The kinds: robot backends, camera and pose sources, terrains, swing trajectories, map
engines.

A registry maps names to entries. An entry is the object itself, or a ``"module:attribute"``
path imported on first use: built-in hardware backends name their module that way, so
``footfall walk`` never waits for a servo or camera library it does not use. What the CLI
offers, what the benchmarks sweep and what the reports list are read from the registries,
never from lists of their own (see ``docs/extending.md``).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterator
from typing import Generic, TypeVar, overload

from footfall.errors import ConfigError

T = TypeVar("T")


class Registry(Generic[T]):
    """Named entries of one kind, in the order they were registered.

    Args:
        kind: What the entries are, for error messages ("robot backend", "terrain").
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._entries: dict[str, T | str] = {}

    @overload
    def register(self, name: str, entry: None = None) -> Callable[[T], T]: ...

    @overload
    def register(self, name: str, entry: T | str) -> T | str: ...

    def register(self, name: str, entry: T | str | None = None) -> object:
        """Register ``entry`` under ``name``; without an entry, a decorator that does.

        Args:
            name: The name users choose it by (``--backend NAME``, ``--terrain NAME``).
            entry: The object, or ``"module:attribute"`` to import when first asked for.

        Raises:
            ConfigError: On an empty name, or one already registered.
        """
        if entry is None:

            def decorate(item: T) -> T:
                self.register(name, item)
                return item

            return decorate
        if not name or not isinstance(name, str):
            raise ConfigError(f"a {self.kind} needs a non-empty name, got {name!r}")
        if name in self._entries:
            raise ConfigError(f"a {self.kind} named {name!r} is already registered")
        self._entries[name] = entry
        return entry

    def unregister(self, name: str) -> None:
        """Forget ``name`` (a test's or a session's own entry)."""
        self._entries.pop(name, None)

    def check(self, name: str) -> str:
        """``name``, if it is registered (without importing its entry).

        Raises:
            ConfigError: On a name not registered; the message lists the registered ones.
        """
        if name not in self._entries:
            raise ConfigError(f"unknown {self.kind} {name!r}; choose one of {', '.join(self)}")
        return name

    def get(self, name: str) -> T:
        """The entry registered as ``name``, imported if it was registered by path.

        Raises:
            ConfigError: On a name not registered; the message lists the registered ones.
        """
        entry = self._entries[self.check(name)]
        if isinstance(entry, str):
            module, _, attribute = entry.partition(":")
            try:
                loaded = getattr(importlib.import_module(module), attribute)
            except (ImportError, AttributeError) as exc:
                raise ConfigError(f"{self.kind} {name!r} cannot be loaded: {exc}") from exc
            self._entries[name] = loaded
            return loaded
        return entry

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(self._entries))

    def __len__(self) -> int:
        return len(self._entries)
