"""The explorer's server-side table of models: the only things a request can name.

A request never carries a path: it names a model by an id from this table (``arg0``, ``builtin:ggx``,
``example:ggx.brdf``), fixed when the server starts — the models given on the command line, the built-in lobes
and the ``.brdf`` files of the source tree's ``examples/``. Files given on the command line are *watched*: when
one is saved, :meth:`Catalog.reload` compiles it again; a compile error is kept beside the last good model (the
page shows FILE:LINE:COL and keeps its plots) until the file compiles again. Each model is listed once: a
model given on the command line replaces its built-in or ``examples/`` entry.

:func:`control_of` says which control the page draws for a declared parameter. η, k, f0 and f90 are numbers per
channel (an index of refraction of 1.5, or a reflectance of 0.0123, is not a colour: a colour picker spans [0, 1]
in 8-bit steps), so they get one numeric input per channel; until parameters carry a per-channel numeric kind of
their own, they are recognised here by name, or by a ``color`` range that reaches beyond 1.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from pathlib import Path

from .. import load
from ..errors import BrdfFileError, BrdfnormError, ModelNotFoundError
from ..models import REGISTRY, Model
from ..parameters import Parameter

#: The examples shipped beside the sources (a source checkout or an editable install); absent from a wheel.
EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


#: Parameters declared as colours that are numbers per channel (indices of refraction, extinction, Fresnel
#: reflectances), compared case-insensitively.
PER_CHANNEL_NAMES = frozenset({"eta", "k", "f0", "f90", "ior", "int_ior", "ext_ior", "kappa"})
#: The controls of the page (see app.js): a slider with a number box, numbers per channel, a colour picker, a
#: labelled switch, a menu.
CONTROLS = ("slider", "channels", "colour", "switch", "menu")


def control_of(p: Parameter) -> str:
    """The page's control for ``p`` (one of :data:`CONTROLS`).

    A kind this table does not know (a per-channel numeric kind, say) with a numeric default is ``channels``
    (three inputs for an R,G,B default, one for a scalar); an integer kind gets a slider with whole steps.
    """
    kind = str(p.kind)
    if kind == "choice" or getattr(p, "choices", ()):
        return "menu"
    if kind == "bool":
        return "switch"
    if kind in ("float", "int", "integer"):
        return "slider"
    if kind == "color":
        numeric = p.name.lower() in PER_CHANNEL_NAMES or (p.maximum is not None and p.maximum > 1.0)
        return "channels" if numeric else "colour"
    return "channels"


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
        listed: set[str] = set()  # sources already listed: a model given twice, or given and built in, is one entry
        for name in given:
            model = load(name)  # ModelNotFoundError / BrdfFileError with FILE:LINE:COL for the command line
            watched = name not in REGISTRY
            source = str(Path(name).resolve()) if watched else name
            if source in listed:
                continue
            listed.add(source)
            label = Path(name).name if watched else name
            entries.append(Entry(f"arg{len(entries)}", label, "given", source, watched=watched, model=model))
        entries += [Entry(f"builtin:{name}", name, "built-in", name) for name in REGISTRY if name not in listed]
        if examples is not None and examples.is_dir():
            entries += [Entry(f"example:{path.name}", path.name, "example", str(path.resolve()))
                        for path in sorted(examples.glob("*.brdf")) if str(path.resolve()) not in listed]
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
