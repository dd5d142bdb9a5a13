"""One pattern for every pluggable set of the product: a :class:`Registry` of names to objects.

As colour-science pairs each ``*_METHODS`` mapping with ``validate_method``, a registry is a read-only mapping
(models, albedo methods, fit forms, emitted languages, verified claims, output formats) plus one validation
helper, :meth:`Registry.validate`, that turns an unknown or mistyped name into an
:class:`~brdfnorm.errors.ArgumentError` naming the API argument and the known names. Every entry is declared where
the registry is built; one whose module lies above the registry's in the import graph (the ``openpbr`` model of
:mod:`brdfnorm.materials` in the models' registry, its albedo method in the engine's) is declared as a
:class:`Reference` — ``"package.module:name"`` — and imported when first looked up, so that a registry never
imports its members' modules at import time and no module fills another package's registry as a side effect of
being imported. :meth:`Registry.register` adds an entry from outside (a user's own model or method).
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from .errors import ArgumentError, ArgumentTypeError

T = TypeVar("T")


@dataclass(frozen=True)
class Reference:
    """An object named by where it lives, ``"package.module:name"``, imported when first resolved."""

    target: str

    def resolve(self) -> Any:
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)

    def call(self) -> Callable[..., Any]:
        """A function that resolves the target on its first call and calls it (a registry entry's callable that
        lives above the registry, such as an albedo method's ``run``)."""
        def call(*args: Any, **kwargs: Any) -> Any:
            return self.resolve()(*args, **kwargs)
        return call


class Registry(Mapping[str, T], Generic[T]):
    """Names → objects of one kind; ``argument`` is the API argument that selects among them."""

    def __init__(self, kind: str, argument: str, entries: Mapping[str, T | Reference] | None = None) -> None:
        self.kind = kind
        self.argument = argument
        self._entries: dict[str, T | Reference] = dict(entries or {})

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
        entry = self._entries[name]
        if isinstance(entry, Reference):  # declared by where it lives: imported on first use
            entry = self._entries[name] = entry.resolve()
        return entry

    def __contains__(self, name: object) -> bool:  # without resolving a Reference
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._entries)})"


def lazy_exports(package: str, names: Mapping[str, str], *, subpackages: bool = False,
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A package's PEP 562 ``__getattr__`` and ``__dir__`` for its public ``names`` (name -> the module that defines
    it, relative to ``package``; a name that is that module itself is the submodule), each imported when first
    asked for and then bound in the package (so asked once): ``import brdfnorm`` and the command line's start pay
    for what a command uses, not for the engine, the models, scipy and the materials (docs/performance.md, eighth
    round). With ``subpackages``, any other public name that is a module of the package is imported as asked."""

    def __getattr__(name: str) -> Any:
        if name in names:
            module = importlib.import_module(f"{package}.{names[name]}")
            value = module if module.__name__ == f"{package}.{name}" else getattr(module, name)
            setattr(importlib.import_module(package), name, value)
            return value
        if subpackages and not name.startswith("_") and importlib.util.find_spec(f"{package}.{name}") is not None:
            return importlib.import_module(f"{package}.{name}")  # (the import binds it as an attribute, too)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted({*vars(importlib.import_module(package)), *names})

    return __getattr__, __dir__
