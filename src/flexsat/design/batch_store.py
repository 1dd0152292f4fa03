"""The zarr store of a batch run on disk: its layout, its writes, one run at a time, its faults.

Layout and writes (:func:`create_store`, :func:`write_chunk`, :func:`open_store_mask`): the
store is laid out in a sibling folder ``.<name>.partial`` and renamed into place when complete;
a chunk's results are written before its cases are marked done (:mod:`flexsat.design.
batch_runner` says why a killed run loses at most one chunk). zarr writes every chunk file
through a temporary file renamed into place, so a failed write leaves the previous file whole.

One run at a time (:class:`StoreLock`). A run holds an advisory lock (``flock``) on the file
``.<name>.lock`` next to the store from before it reads the store until it ends; the file
names the holder (process id, host, start time, command line). A second run on the same store
is refused at once with :class:`StoreInUse`, naming the first, and changes nothing: a sweep
can run for hours, so waiting for it would look like a hang, while the refused command, given
again when the first has ended, resumes the store. The kernel releases the lock of a process
that dies however it dies (SIGKILL included), so a lock file left by a killed run is stale by
construction and the next run takes it over. Where the file system has no locks (some NFS
set-ups) the file's content decides instead: a holder on this host whose process is gone is
stale and taken over; a live one, or one on another host (whose processes cannot be seen), is
refused, the message naming the lock file to remove if that run is in fact gone.

Faults (:class:`StoreError`). Any error of the operating system while the store is locked, read
or written (a read-only or full disk, a file-size limit, a missing or unwritable folder, a name
too long) becomes a :class:`StoreError`: an :class:`OSError` with the store's path, the original
``errno``, ``strerror`` and ``filename``, and an ``outcome`` sentence saying what the store
keeps. ``flexsat run`` words it as it words a report it cannot write
(:func:`flexsat.report.publish.write_error`) and exits with code 2. The store stays resumable:
the chunks marked done are whole, the rest run again.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import socket
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager, suppress
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from flexsat.file_locks import try_lock
from flexsat.input_checks import FieldError

#: the layout of the store; part of the fingerprint so a store of another layout is refused
STORE_LAYOUT = "flexsat.design.batch_runner/2"


class StoreError(OSError):
    """The batch store ``store`` cannot be locked, read or written.

    ``errno``, ``strerror`` and ``filename`` are the operating system's; ``outcome`` says what
    the store keeps and what to do next. ``flexsat run`` prints it through
    :func:`flexsat.report.publish.write_error`, the words of a report that cannot be written.

    Parameters
    ----------
    store : Path
        The store.
    error : OSError
        What the operating system refused.
    outcome : str
        What the store keeps (a sentence).
    """

    def __init__(self, store: Path, error: OSError, outcome: str) -> None:
        super().__init__(error.errno or errno.EIO, error.strerror or str(error), error.filename)
        self.store, self.outcome = Path(store), outcome

    def __reduce__(self) -> tuple[Any, ...]:
        error = OSError(self.errno, self.strerror, self.filename)
        return type(self), (self.store, error, self.outcome)

    def __str__(self) -> str:
        where = f": '{os.fsdecode(self.filename)}'" if self.filename is not None else ""
        return f"store '{self.store}': {self.strerror}{where}. {self.outcome}"


class StoreInUse(StoreError):
    """Another run holds the store (:class:`StoreLock`); ``holder`` is what its lock file says
    (``pid``, ``host``, ``started``, ``command``; empty if it had not written it yet)."""

    def __init__(
        self, store: Path, holder: Mapping[str, Any], lock_file: Path | None = None
    ) -> None:
        self.holder, self.lock_file = dict(holder), lock_file
        who = describe_holder(holder)
        reason = f"another flexsat run is filling it ({who})"
        then = "run the same command again when it has ended (it resumes the store)"
        if lock_file is not None:  # no kernel locks here: the lock file may outlive its run
            then += f"; if that run is gone, remove '{lock_file}'"
        outcome = f"Nothing was changed: {then}, or give another store."
        super().__init__(store, OSError(errno.EBUSY, reason), outcome)

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.store, self.holder, self.lock_file)


def describe_holder(holder: Mapping[str, Any]) -> str:
    """``pid 1234 on host 'node7', started 2026-12-07 02:30:01 UTC: flexsat run sweep.yaml``
    from a lock file's content (what is known of it)."""
    if "pid" not in holder:
        return "it is starting up"
    text = f"pid {holder['pid']} on host {holder.get('host', '?')!r}"
    if "started" in holder:
        text += f", started {holder['started']}"
    if holder.get("command"):
        text += f": {holder['command']}"
    return text


def _read_holder(fd: int) -> dict[str, Any]:
    """The lock file's content ({} if empty or not a holder's record)."""
    try:
        holder = json.loads(os.pread(fd, 4096, 0).decode())
    except (OSError, ValueError):
        return {}
    return holder if isinstance(holder, dict) else {}


def _gone(holder: Mapping[str, Any]) -> bool:
    """True if the holder is a process of this host that no longer exists (or no holder is
    named): its lock is stale. A process of another host cannot be seen: never gone."""
    if "pid" not in holder:
        return True
    if holder.get("host") != socket.gethostname():
        return False
    try:
        pid = int(holder["pid"])
    except (TypeError, ValueError):  # not a record this module wrote
        return True
    if pid <= 0:  # kill(0 or -n) would ask about process groups
        return True
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:  # a process of another user: alive
        return False
    return False


class StoreLock:
    """Hold the store ``store`` for one run (module docstring): ``with StoreLock(path): ...``.

    Raises :class:`StoreInUse` naming the holder if another run holds it; an error of the
    operating system (the folder cannot be created or written) propagates as it is.

    Parameters
    ----------
    store : str or Path
        The store; its folder is created if needed.
    """

    def __init__(self, store: str | Path) -> None:
        self.store = Path(store)
        # next to the store itself: one lock however the path to it is spelled (links, ..)
        real = Path(os.path.realpath(self.store))
        self.path = real.with_name(f".{real.name}.lock")
        self._fd: int | None = None

    def __enter__(self) -> StoreLock:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        while self._fd is None:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            try:
                if self._take(fd):
                    self._fd = fd
            finally:
                if self._fd is None:
                    os.close(fd)
        return self

    def _take(self, fd: int) -> bool:
        """Take the lock on ``fd`` and write this run's record into it; False if the file was
        removed by its previous holder as it was opened (open it again)."""
        locked = try_lock(fd)
        if locked is False:
            raise StoreInUse(self.store, _read_holder(fd))
        if locked is None:
            holder = _read_holder(fd)
            if not _gone(holder):
                raise StoreInUse(self.store, holder, self.path)
        try:
            if os.fstat(fd).st_ino != os.stat(self.path).st_ino:
                return False
        except FileNotFoundError:
            return False
        argv0 = Path(sys.argv[0])
        program = f"python -m {argv0.parent.name}" if argv0.name == "__main__.py" else argv0.name
        record = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "started": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
            "command": " ".join([program, *sys.argv[1:]])[:300],
        }
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, json.dumps(record).encode(), 0)
        except OSError:  # a full disk: leave no empty lock file behind (it is this run's)
            with suppress(OSError):
                os.unlink(self.path)
            raise
        return True

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._fd is None:
            return
        with suppress(OSError):  # a lock file left behind is stale: the next run takes it
            os.unlink(self.path)  # while still held, so no other run holds a removed file
        os.close(self._fd)
        self._fd = None


@contextmanager
def store_faults(store: Path, outcome: Callable[[], str]) -> Iterator[None]:
    """Turn an :class:`OSError` raised inside into a :class:`StoreError` of ``store`` whose
    outcome is ``outcome()`` (called then: what the store keeps at that moment)."""
    try:
        yield
    except StoreError:
        raise
    except OSError as exc:
        raise StoreError(store, exc, outcome()) from exc


# -- layout and writes -------------------------------------------------------------------------
def open_store_mask(path: Path, fp: str, n_cases: int) -> np.ndarray | None:
    """The completion mask of the store at ``path`` (None if there is none); ValueError if it
    belongs to another setup."""
    import xarray as xr

    if not path.exists():
        return None
    try:
        ds = xr.open_zarr(path, consolidated=False)
    except Exception as exc:  # noqa: BLE001 - any unreadable directory is refused the same way
        raise FieldError(
            "store",
            f"{str(path)!r} exists and is not a batch store "
            f"({type(exc).__name__}: {exc}); give a new path",
        ) from None
    theirs = ds.attrs.get("fingerprint")
    if theirs != fp or ds.sizes.get("case") != n_cases:
        raise FieldError(
            "store",
            f"{str(path)!r} holds the results of a different setup "
            f"(fingerprint {theirs!s:.12} ≠ {fp:.12}: another scenario, parameter "
            f"table, base seed or history selection); refusing to resume into it, "
            f"give a new path",
        )
    return np.asarray(ds["done"].values, bool)


def create_store(
    path: Path,
    fp: str,
    setup_text: str,
    table: Mapping[str, np.ndarray],
    first: Mapping[str, np.ndarray],
    zchunk: int,
    n_cases: int,
) -> None:
    """Lay out the store (metadata and the parameter table; the results are left to fill).

    Parameters
    ----------
    path : Path
        The store.
    fp : str
        The setup's fingerprint.
    setup_text : str
        The scenario as given.
    table : mapping of str to ndarray
        The parameter table, (n_cases,) columns.
    first : mapping of str to ndarray
        A chunk's results (their names, dtypes and time axis).
    zchunk : int
        The zarr chunk along ``case``.
    n_cases : int
    """
    import dask.array as da
    import xarray as xr

    case = np.arange(n_cases)
    data: dict[str, tuple[str | tuple[str, ...], Any]] = {
        f"param_{k}": ("case", v) for k, v in table.items()
    }
    data["done"] = ("case", np.zeros(n_cases, bool))
    encoding = {}
    for name, values in first.items():
        if name == "time":
            continue
        shape = (n_cases,) + values.shape[1:]
        dims = ("case", "time") if values.ndim == 2 else ("case",)
        fill = -1 if values.dtype.kind == "i" else np.nan
        data[name] = (
            dims,
            da.full(shape, fill, dtype=values.dtype, chunks=(zchunk,) + values.shape[1:]),
        )
        encoding[name] = {"chunks": (zchunk,) + values.shape[1:]}
    ds = xr.Dataset(
        data,
        coords={"case": case, "time": first["time"]},
        attrs={"fingerprint": fp, "setup_text": setup_text, "layout": STORE_LAYOUT},
    )
    for name in ("done",) + tuple(f"param_{k}" for k in table):
        encoding[name] = {"chunks": (zchunk,)}
    partial = path.with_name(f".{path.name}.partial")
    shutil.rmtree(partial, ignore_errors=True)  # a run killed while laying out its store
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        ds.to_zarr(partial, mode="w", compute=False, encoding=encoding, consolidated=False)
        # the parameter table, the mask and the coordinates are small: written now in full
        ds[[n for n in map(str, ds.data_vars) if n == "done" or n.startswith("param_")]].to_zarr(
            partial, mode="r+", consolidated=False
        )
        partial.rename(path)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise


def write_chunk(store: Any, start: int, out: Mapping[str, np.ndarray]) -> None:
    """Write one chunk's results into the zarr group ``store`` (the layout :func:`create_store`
    made), then (only then) mark its cases done. Plain zarr slice assignments: an xarray region
    write re-reads the store's metadata for every chunk (twice the time, ~1 % of a 5,000-case
    chunk's compute).

    Parameters
    ----------
    store : zarr.Group
        The store, open for writing.
    start : int
        The chunk's first case.
    out : mapping of str to ndarray
        The chunk's results (:func:`flexsat.design.batch_runner.run_chunk`).
    """
    stop = start + len(out["seed"])
    for name, values in out.items():
        if name != "time":
            store[name][start:stop] = values
    store["done"][start:stop] = True


__all__ = [
    "STORE_LAYOUT",
    "StoreError",
    "StoreInUse",
    "StoreLock",
    "create_store",
    "describe_holder",
    "open_store_mask",
    "store_faults",
    "write_chunk",
]
