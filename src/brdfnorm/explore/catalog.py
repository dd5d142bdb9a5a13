"""The explorer's server-side table of models: the only things a request can name.

A request never carries a path: it names a model by an id from this table (``arg0``, ``builtin:ggx``,
``example:ggx.brdf``), fixed when the server starts — the models given on the command line, the built-in lobes
and the ``.brdf`` files of the source tree's ``examples/``. Files given on the command line are *watched*: when
one is saved, :meth:`Catalog.reload` compiles it again; a compile error is kept beside the last good model (the
page shows FILE:LINE:COL and keeps its plots) until the file compiles again.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from pathlib import Path

from .. import load
from ..errors import BrdfFileError, BrdfnormError, ModelNotFoundError
from ..models import REGISTRY, Model

#: The examples shipped beside the sources (a source checkout or an editable install); absent from a wheel.
EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


@dataclass
class Entry:
    """One model the explorer serves; ``source`` is a built-in name or a path fixed at start-up."""

    id: str
    label: str
    group: str  # "given", "built-in" or "example"
    source: str
    watched: bool = False
    model: Model | None = None  # the last model that compiled (loaded on first use)
    error: dict | None = None  # the current file's compile error, while it has one
    version: int = 0  # bumped on every reload, good or bad
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    @property
    def path(self) -> Path | None:
        return None if self.source in REGISTRY else Path(self.source).resolve()

    def describe(self) -> dict:
        return {"id": self.id, "label": self.label, "group": self.group, "watched": self.watched,
                "version": self.version}


def error_record(error: BrdfnormError) -> dict:
    """What the page shows for a failed reload: ``FILE:LINE:COL: message`` and its parts."""
    record = {"text": str(error), "message": error.message, "where": error.where}
    if isinstance(error, BrdfFileError):
        record.update(file=error.path, line=error.line, column=error.column)
    return record


class Catalog:
    """Models by id. Built with :meth:`build`; ``get`` loads lazily; ``reload`` re-reads a watched file."""

    def __init__(self, entries: list[Entry]) -> None:
        self._entries = {entry.id: entry for entry in entries}

    @classmethod
    def build(cls, given: list[str], examples: Path | None = EXAMPLES) -> Catalog:
        """The given models (loaded now, so a bad one fails before the server starts), built-ins, examples."""
        entries: list[Entry] = []
        for i, name in enumerate(given):
            model = load(name)  # ModelNotFoundError / BrdfFileError with FILE:LINE:COL for the command line
            watched = name not in REGISTRY
            label = Path(name).name if watched else name
            entries.append(Entry(f"arg{i}", label, "given", name if not watched else str(Path(name).resolve()),
                                 watched=watched, model=model))
        entries += [Entry(f"builtin:{name}", name, "built-in", name) for name in REGISTRY]
        if examples is not None and examples.is_dir():
            entries += [Entry(f"example:{path.name}", path.name, "example", str(path))
                        for path in sorted(examples.glob("*.brdf"))]
        return cls(entries)

    def entries(self) -> list[Entry]:
        return list(self._entries.values())

    def entry(self, model_id: object) -> Entry:
        if not isinstance(model_id, str) or model_id not in self._entries:
            raise ModelNotFoundError(f"unknown model id {str(model_id)[:80]!r}", where="model")
        return self._entries[model_id]

    def get(self, model_id: object) -> Model:
        """The entry's model (its last good one, for a watched file with a compile error)."""
        entry = self.entry(model_id)
        with entry.lock:
            if entry.model is None:
                entry.model = load(entry.source)
            return entry.model

    def watched(self) -> dict[Path, Entry]:
        return {entry.path: entry for entry in self._entries.values() if entry.watched and entry.path}

    def reload(self, entry: Entry) -> None:
        """Compile the file again: a success replaces the model, a failure is recorded beside the last good one."""
        try:
            model = load(entry.source)
        except BrdfnormError as error:
            record = error_record(error)
        except Exception as error:  # noqa: BLE001 — a compiler bug must not stop the watcher; show it instead
            record = {"text": f"{entry.source}: internal error: {type(error).__name__}: {error}",
                      "message": str(error), "where": entry.source}
        else:
            with entry.lock:
                entry.model, entry.error = model, None
                entry.version += 1
            return
        with entry.lock:
            entry.error = record
            entry.version += 1
