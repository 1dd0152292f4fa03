"""Stages of a design study and the cache of their results.

A design study (``kind: design_study``, :mod:`flexsat.scenarios.design_study`) is a chain of
stages -- model, modes, placement, law design, runs -- each a function of its own section of the
document and of the results of the stages upstream of it. A stage is named by a
*fingerprint*: the SHA-256 of the canonical JSON (keys sorted, no spaces, floats in their
shortest round-trip form) of

    {"stage": name, "section": the validated section, "upstream": upstream fingerprints,
     "flexsat": flexsat.__version__}

so that a result depends on exactly what went into it: changing a law's weight changes that
law's fingerprint and those of the runs that use it, never the model's or the modes'; changing
the model changes every fingerprint downstream. A new flexsat version invalidates everything
(its numerics may differ).

:class:`StageCache` keeps one folder per fingerprint, ``<stage>-<fingerprint>``, holding what
the stage writes (netCDF and JSON files, never pickles). A folder is written under a temporary
name in the cache folder and renamed into place (``os.rename`` of a directory is atomic on one
file system), so an entry is whole or absent: an interrupted write leaves a temporary folder
that is never read, and two processes computing one stage at once both publish a whole entry,
the first rename winning. An entry that cannot be read back (a file edited or truncated by hand)
is discarded and the stage computed afresh. A process computing a stage holds its lock file
(:func:`flexsat.file_locks.try_lock`), so that the cases of a batch sharing one cache compute
each stage once: the others wait for the entry and read it.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from flexsat import __version__
from flexsat.file_locks import try_lock
from flexsat.input_checks import FieldError

T = TypeVar("T")

#: the default cache folder, under the system's temporary folder
DEFAULT_CACHE = Path(tempfile.gettempdir()) / "flexsat-stage-cache"
#: s between two attempts at a stage's lock another process holds
LOCK_POLL = 0.05


def canonical_json(value: Any) -> str:
    """``value`` as canonical JSON: keys sorted, no spaces, non-ASCII kept, NaN refused.

    Raises
    ------
    ValueError
        For a value JSON cannot hold (NaN, infinity, an object).
    """
    return json.dumps(
        value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False
    )


def fingerprint(stage: str, section: Any, upstream: Sequence[str] = ()) -> str:
    """The fingerprint of a stage (module docstring): 64 hexadecimal digits.

    Parameters
    ----------
    stage : str
        The stage's name (``"model"``, ``"modes"``, ...).
    section : JSON-ready value
        The stage's validated section (``model_dump(mode="json")``), with whatever else its
        result depends on (the hash of a file it reads).
    upstream : sequence of str
        The fingerprints of the stages it builds on, in a fixed order.
    """
    payload = {
        "stage": stage,
        "section": section,
        "upstream": list(upstream),
        "flexsat": __version__,
    }
    return hashlib.sha256(canonical_json(payload).encode()).hexdigest()


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's bytes (a stage reading a file depends on its content, not its name)."""
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


@dataclass(frozen=True)
class Stage:
    """One stage of a study: its name, its fingerprint and the label it is shown under.

    Attributes
    ----------
    name : str
        The kind of stage (``"model"``, ``"law"``, ...): the prefix of its cache folder.
    label : str
        What the report and the progress display call it (``"law 'LQR'"``).
    key : str
        Its fingerprint (:func:`fingerprint`).
    """

    name: str
    label: str
    key: str

    @classmethod
    def of(cls, name: str, label: str, section: Any, upstream: Sequence[Stage] = ()) -> Stage:
        """The stage ``name`` of ``section`` downstream of ``upstream``."""
        return cls(name, label, fingerprint(name, section, [s.key for s in upstream]))


@dataclass(frozen=True)
class StageRecord:
    """What a stage did: computed or read from the cache, in how long, and its key numbers.

    Attributes
    ----------
    stage : Stage
    cached : bool
        Read from the cache (True) or computed (False).
    seconds : float
        Wall time of the computation or of the read, s.
    summary : dict
        JSON-ready key numbers the report shows (frequencies, the placement, gains, poles).
    """

    stage: Stage
    cached: bool
    seconds: float
    summary: dict[str, Any] = field(default_factory=dict)


class StageCache:
    """Stage results by fingerprint in a folder (module docstring).

    Parameters
    ----------
    folder : path, optional
        Where the entries live; default :data:`DEFAULT_CACHE`. Created when first written.
    """

    def __init__(self, folder: str | Path | None = None) -> None:
        self.folder = Path(DEFAULT_CACHE if folder is None else folder)

    def entry(self, stage: Stage) -> Path:
        """The folder of ``stage``'s result."""
        return self.folder / f"{stage.name}-{stage.key}"

    def read(self, stage: Stage, read: Callable[[Path], T]) -> T | None:
        """``read(folder)`` of the stage's entry, or None when there is none or it cannot be
        read back (the entry is then removed, to be written afresh)."""
        path = self.entry(stage)
        if not path.is_dir():
            return None
        try:
            return read(path)
        except (OSError, ValueError, KeyError, TypeError):
            shutil.rmtree(path, ignore_errors=True)
            return None

    def write(self, stage: Stage, write: Callable[[Path], None]) -> None:
        """Publish the stage's entry: ``write(folder)`` fills a temporary folder, renamed into
        place whole; an entry already there (another process's) is kept."""
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise FieldError(
                "cache", f"cannot create the cache folder {self.folder}: {exc}"
            ) from None
        temporary = Path(tempfile.mkdtemp(prefix=f".{stage.name}-", dir=self.folder))
        try:
            write(temporary)
            os.rename(temporary, self.entry(stage))
        except OSError:
            if not self.entry(stage).is_dir():
                raise
        finally:
            shutil.rmtree(temporary, ignore_errors=True)

    def get(
        self,
        stage: Stage,
        compute: Callable[[], T],
        write: Callable[[T, Path], None],
        read: Callable[[Path], T],
        summary: Callable[[T], dict[str, Any]],
    ) -> tuple[T, StageRecord]:
        """The stage's result, read from the cache or computed (and then stored), with its
        record.

        Parameters
        ----------
        stage : Stage
        compute : callable
            Computes the result (only on a miss).
        write, read : callable
            ``write(result, folder)`` stores it, ``read(folder)`` loads it.
        summary : callable
            ``summary(result)``: the key numbers of the record.
        """
        start = time.perf_counter()
        found = self.read(stage, read)
        if found is not None:
            return found, StageRecord(stage, True, time.perf_counter() - start, summary(found))
        with self._computing(stage):
            # another process may have published the entry while this one waited for it
            found = self.read(stage, read)
            if found is not None:
                record = StageRecord(stage, True, time.perf_counter() - start, summary(found))
                return found, record
            result = compute()
            facts = summary(result)
            self.write(stage, lambda folder: _write_with_summary(write, result, facts, folder))
        return result, StageRecord(stage, False, time.perf_counter() - start, facts)

    def recorded(self, stage: Stage) -> StageRecord | None:
        """The record of a stage in the cache, its result left unread (a stage whose
        downstream stages are all cached need not be loaded), or None when it is not there."""
        start = time.perf_counter()
        facts = self.read(stage, lambda folder: json.loads((folder / SUMMARY).read_text()))
        if facts is None:
            return None
        return StageRecord(stage, True, time.perf_counter() - start, facts)

    @contextlib.contextmanager
    def _computing(self, stage: Stage) -> Iterator[None]:
        """Hold the stage's lock file while computing it, so that processes sharing the cache
        (the cases of a batch) compute a stage once: one computes, the others wait for its
        entry. Where the file system has no locks every process computes (the entry is still
        published whole, the first rename winning)."""
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise FieldError("cache", f"cannot create the folder {self.folder}: {exc}") from None
        with open(self.folder / f".{stage.name}-{stage.key}.lock", "a+b") as handle:
            # the kernel releases the lock of a process that dies: the wait is bounded by the
            # computation of a live one
            while try_lock(handle.fileno()) is False:
                time.sleep(LOCK_POLL)
            yield


# -- arrays and JSON -------------------------------------------------------------------------------
ARRAYS = "arrays.nc"
INFO = "info.json"
#: the key numbers of an entry's record, beside its result
SUMMARY = "summary.json"


def _write_with_summary(
    write: Callable[[T, Path], None], result: T, facts: Mapping[str, Any], folder: Path
) -> None:
    write(result, folder)
    (folder / SUMMARY).write_text(canonical_json(dict(facts)), encoding="utf-8")


def write_arrays(folder: Path, arrays: Mapping[str, Any], info: Mapping[str, Any]) -> None:
    """Write named arrays (netCDF, ``arrays.nc``; complex arrays as ``<name>.real`` and
    ``<name>.imag``) and a JSON-ready mapping (``info.json``) into ``folder``."""
    import xarray as xr

    from flexsat.netcdf import write_netcdf

    variables: dict[str, Any] = {}
    for name, value in arrays.items():
        array = np.asarray(value)
        parts = (
            {f"{name}.real": array.real, f"{name}.imag": array.imag}
            if np.iscomplexobj(array)
            else {name: array.astype(float)}
        )
        for part, data in parts.items():
            variables[part] = ([f"{part}_{i}" for i in range(data.ndim)], data)
    write_netcdf(xr.Dataset(variables), folder / ARRAYS)
    (folder / INFO).write_text(canonical_json(dict(info)), encoding="utf-8")


def read_arrays(folder: Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The arrays and the mapping :func:`write_arrays` wrote."""
    import xarray as xr

    with xr.open_dataset(folder / ARRAYS, engine="h5netcdf") as ds:
        raw = {str(name): np.asarray(var.values) for name, var in ds.load().data_vars.items()}
    arrays: dict[str, np.ndarray] = {}
    for name, value in raw.items():
        if name.endswith(".imag"):
            continue
        if name.endswith(".real"):
            base = name[: -len(".real")]
            arrays[base] = value + 1j * raw[f"{base}.imag"]
        else:
            arrays[name] = value
    info = json.loads((folder / INFO).read_text(encoding="utf-8"))
    return arrays, info


__all__ = [
    "DEFAULT_CACHE",
    "Stage",
    "StageCache",
    "StageRecord",
    "canonical_json",
    "file_digest",
    "fingerprint",
    "read_arrays",
    "write_arrays",
]
