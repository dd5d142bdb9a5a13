"""One pattern for every pluggable set of the product: a :class:`Registry` of names to objects.

As colour-science pairs each ``*_METHODS`` mapping with ``validate_method``, a registry is a read-only mapping
(models, albedo methods, fit forms, emitted languages, verified claims, output formats) plus one validation
helper, :meth:`Registry.validate`, that turns an unknown or mistyped name into an
:class:`~brdfnorm.errors.ArgumentError` naming the API argument and the known names. Entries are added with
:meth:`Registry.register` by the module that defines them (a registry never imports its members' modules,
so registration cannot create an import cycle).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Generic, TypeVar

from .errors import ArgumentError, ArgumentTypeError

T = TypeVar("T")


class Registry(Mapping[str, T], Generic[T]):
    """Names → objects of one kind; ``argument`` is the API argument that selects among them."""

    def __init__(self, kind: str, argument: str, entries: Mapping[str, T] | None = None) -> None:
        self.kind = kind
        self.argument = argument
        self._entries: dict[str, T] = dict(entries or {})

    def register(self, name: str, entry: T) -> T:
        """Add ``entry`` under ``name`` (a name is registered once); returns the entry."""
        if name in self._entries:
            raise ValueError(f"{self.kind} {name!r} is registered already")
        self._entries[name] = entry
        return entry

    def validate(self, name: object, *, extra: tuple[str, ...] = ()) -> str:
        """``name`` if it is registered (or one of ``extra``, e.g. ``"auto"``), else an ArgumentError."""
        known = ", ".join([*extra, *self._entries])
        if not isinstance(name, str):
            raise ArgumentTypeError(f"expected a {self.kind} name ({known}), got {type(name).__name__}",
                                    where=self.argument)
        if name not in self._entries and name not in extra:
            raise ArgumentError(f"unknown {self.kind} {name[:40]!r} (known: {known})", where=self.argument)
        return name

    def __getitem__(self, name: str) -> T:
        return self._entries[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._entries)})"
