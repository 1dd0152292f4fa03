"""An in-process, content-addressed cache of the modal models built from ``model:`` sections.

A sweep or Monte Carlo over a scenario with a ``model:`` section runs each case as its own
scenario (:mod:`flexsat.scenarios.batch_cases`), so each case builds its plant from the section.
When the varied parameters are not structural (a law gain, a sensor noise, a slew's duration)
every case holds the same section, and its finite-element modal solve or file read would be
redone per case (measured: 11 ms for the 9-node spacecraft of
``examples/own_spacecraft_slew.yaml``, 96 ms for the same booms in 120 frames with 30 modes,
against 0.7 ms for a hit, the key of the 121-node section included). This cache keys the built
:class:`~flexsat.structures.modal_model.ModalModel` by the section's content — the canonical
JSON of the validated section (SI numbers, keys sorted) and the SHA-256 digest of every file it
reads — so a case whose structure is unchanged reuses the model, and a case whose modulus,
inertia or file content differs gets its own solve.

It lives in one process (each dask worker has its own; nothing is written to disk, and the cache
refuses to be pickled, so it cannot travel to another process by accident) and keeps the
:data:`MAX_ENTRIES` most recently used models. Sharing is safe: a ModalModel is frozen and its
arrays are read-only.
"""

from __future__ import annotations

import hashlib
import json
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

if TYPE_CHECKING:
    from flexsat.structures.modal_model import ModalModel

__all__ = ["MAX_ENTRIES", "CacheInfo", "ModalModelCache", "MODAL_MODELS", "section_key"]

#: models kept per process: a batch varies one structure at a time, so a few suffice, and each
#: model holds its mode shapes (dofs x modes floats), so the bound keeps the memory small
MAX_ENTRIES = 8


@dataclass(frozen=True)
class CacheInfo:
    """Counts of a :class:`ModalModelCache`: ``hits``, ``misses`` (models built) and ``size``."""

    hits: int
    misses: int
    size: int


def section_key(section: dict[str, Any], files: Iterable[Path] = ()) -> str:
    """The cache key of a validated section: the SHA-256 of its canonical JSON (``section``,
    its ``model_dump(mode="json")``, keys sorted, no whitespace) and of each file's bytes, in
    the order given."""
    digest = hashlib.sha256(
        json.dumps(section, sort_keys=True, separators=(",", ":"), allow_nan=False).encode()
    )
    for path in files:
        digest.update(b"\0")
        digest.update(hashlib.sha256(Path(path).read_bytes()).digest())
    return digest.hexdigest()


class ModalModelCache:
    """A bounded least-recently-used map of section keys to modal models (module docstring).

    Thread-safe (an in-process dask scheduler runs chunks on threads); two threads missing the
    same key at once may both build it, and the first stored is kept.
    """

    def __init__(self, max_entries: int = MAX_ENTRIES) -> None:
        self.max_entries = max_entries
        self._models: OrderedDict[str, ModalModel] = OrderedDict()
        self._lock = threading.Lock()
        self._hits = 0
        self._misses = 0

    def get(self, key: str, build: Callable[[], ModalModel]) -> ModalModel:
        """The model stored under ``key``, else ``build()``, stored. An exception of ``build``
        propagates and nothing is stored."""
        with self._lock:
            model = self._models.get(key)
            if model is not None:
                self._models.move_to_end(key)
                self._hits += 1
                return model
        built = build()
        with self._lock:
            self._misses += 1
            model = self._models.setdefault(key, built)
            self._models.move_to_end(key)
            while len(self._models) > self.max_entries:
                self._models.popitem(last=False)
        return model

    def info(self) -> CacheInfo:
        """The hit and miss counts since the last :meth:`clear`, and the models held."""
        with self._lock:
            return CacheInfo(self._hits, self._misses, len(self._models))

    def clear(self) -> None:
        """Drop every model and reset the counts."""
        with self._lock:
            self._models.clear()
            self._hits = self._misses = 0

    def __reduce__(self) -> NoReturn:
        raise TypeError("a ModalModelCache stays in its process; it is never pickled")


#: the process's cache, used by :meth:`flexsat.scenarios.models.ModelSection.modal_model`
MODAL_MODELS = ModalModelCache()
