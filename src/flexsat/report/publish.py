"""Publish a report folder whole or not at all (POSIX: Linux, macOS).

A report is written into a temporary sibling of the output folder, ``.<out>.tmp-<id>``, and
published by renaming that folder, so ``<out>`` holds the complete previous report or the complete
new one, never a mixture:

- on Linux, on the file systems that support it (ext4, xfs, btrfs, tmpfs, ...), one
  ``renameat2(RENAME_EXCHANGE)`` swaps the new folder and the previous report atomically: there is
  no instant without ``<out>``; the previous report, now at the temporary name, is then removed;
- elsewhere (NFS, older kernels or C libraries, macOS), two renames: the previous report to
  ``.<out>.old-<id>``, then the new folder to ``<out>``; if the second fails the first is undone.
  A crash between the two leaves no ``<out>``: the next write into it first renames the newest
  ``.<out>.old-<id>`` back (the complete previous report).

A symbolic link swapped by a rename would also be atomic, but ``<out>`` would become a link, which
copies, archives and other tools treat differently from the folder users asked for. The previous
report stays until the new one is complete, so both must fit on the disk for a moment.

Before the swap every file is flushed to the disk (``fsync``), so that a power loss cannot publish
a folder of still-empty files. The folder gets a manifest, ``.flexsat-report.json``, listing its
files: a folder is replaced only if everything in it belongs to a report (listed in its manifest,
or among the names the new report writes). A folder holding anything else -- the user's notes, a
project, the current folder -- is refused rather than lost; so is a mount point (it cannot be
renamed).

Concurrent writers never interleave. Each holds an advisory lock (``flock``) on its temporary
folder while it writes; the short steps that create a temporary folder, remove stale ones and swap
hold an exclusive lock on the parent folder itself (no lock file is left behind). A second writer
waits for that lock up to :data:`LOCK_TIMEOUT_S`, with a logged message, then gives up; the last
writer's report is the one published. Temporary folders of killed runs are locked by no live
process: the next write into the same folder removes them. (Where the file system has no locks,
publishing stays atomic but stale temporary folders are kept: a live run's cannot be told from a
dead one's.)

Write errors (disk full, quota exceeded, read-only file system, permission denied, ...) raise
:class:`OutputError`, saying where and why, and leave ``<out>`` unchanged.
"""

from __future__ import annotations

import ctypes
import errno
import json
import logging
import os
import re
import secrets
import shutil
import stat
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING

from flexsat.file_locks import try_lock

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.report.page import ReportedResult

log = logging.getLogger(__name__)

#: name of the manifest listing a published report's files
MANIFEST = ".flexsat-report.json"
#: seconds a writer waits for another writer's publishing step in the same parent folder; the
#: step holds the lock for milliseconds (a rename and removing stale folders), so a wait this long
#: means a hung process
LOCK_TIMEOUT_S = 60.0

_AT_FDCWD = -100  # Linux: paths relative to the working directory
_RENAME_EXCHANGE = 2
#: errors of renameat2 that mean "not supported here" (old kernel, file system, C library)
_NO_EXCHANGE = {errno.ENOSYS, errno.EINVAL, errno.ENOTSUP, errno.EOPNOTSUPP}
_HINTS = {
    errno.ENOSPC: "free some space or choose another folder",
    errno.EDQUOT: "free some space or choose another folder",
    errno.EFBIG: "raise the file-size limit (ulimit -f) or choose a folder on another file system",
    errno.EROFS: "choose a folder you can write to",
    errno.EACCES: "choose a folder you can write to",
    errno.EPERM: "choose a folder you can write to",
}


class OutputError(OSError):
    """The report folder cannot be written; ``str()`` says where and why, ``errno`` is kept."""

    def __str__(self) -> str:
        return self.strerror or super().__str__()  # always given (errno, message) here


def _load_renameat2() -> Callable[[int, bytes, int, bytes, int], int] | None:
    try:
        function = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError, TypeError):  # not glibc >= 2.28 / musl, or not Linux
        return None
    function.argtypes = [
        ctypes.c_int,
        ctypes.c_char_p,
        ctypes.c_int,
        ctypes.c_char_p,
        ctypes.c_uint,
    ]
    function.restype = ctypes.c_int
    return function


_RENAMEAT2 = _load_renameat2()


def _exchange(a: Path, b: Path) -> bool:
    """Swap the folders ``a`` and ``b`` atomically; False where the system cannot."""
    if _RENAMEAT2 is None:
        return False
    if _RENAMEAT2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in _NO_EXCHANGE:
        return False
    raise OSError(code, os.strerror(code), str(a), None, str(b))


def _open_folder(path: Path) -> int:
    return os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)


@contextmanager
def _locked(folder: Path, timeout: float) -> Iterator[None]:
    """Hold the exclusive lock on ``folder`` (waiting up to ``timeout`` seconds)."""
    fd = _open_folder(folder)
    try:
        if try_lock(fd) is False:
            log.warning(
                "waiting up to %.0f s for another flexsat run publishing a report in %s",
                timeout,
                folder,
            )
            deadline = time.monotonic() + timeout
            while try_lock(fd) is False:
                if time.monotonic() > deadline:
                    raise OutputError(
                        errno.EBUSY,
                        (
                            f"another flexsat run has been publishing a report in '{folder}' for "
                            f"{timeout:.0f} s; try again when it has finished"
                        ),
                    )
                time.sleep(0.05)
        yield
    finally:
        os.close(fd)  # releases the lock


def _resolve(out_dir: str | os.PathLike[str]) -> Path:
    out = Path(os.path.realpath(os.fspath(out_dir)))
    if not out.name:
        raise OutputError(
            errno.EINVAL, f"'{out}' is the root folder: a report needs a folder of its own"
        )
    try:
        current = Path.cwd().resolve()
    except OSError:  # the working folder was removed: nothing to protect
        current = None
    if out == current:
        raise OutputError(
            errno.EINVAL,
            (
                f"'{out}' is the current folder; a report folder is replaced as a whole: run from "
                "its parent or choose another folder"
            ),
        )
    return out


def write_error(
    exc: OSError, target: Path, what: str, outcome: str, full_disk_notes: tuple[str, ...] = ()
) -> OutputError:
    """``exc``, raised while writing ``what`` (``"the report"``) to the folder ``target``, as
    one message saying where and why: the reason, the file (named inside ``target`` or inside
    its sibling working folder ``.<target>.*``, else in full), on a full disk the space free
    there and ``full_disk_notes``, what to do for that error, then ``outcome`` (what is left).

    The one place a write fault is put into words: the report's own writes and the batch store
    of a sweep (:class:`flexsat.design.batch_store.StoreError`, ``flexsat run``) both use it.

    Parameters
    ----------
    exc : OSError
        The error (its ``errno``, ``strerror`` and ``filename``).
    target : Path
        The folder being written.
    what : str
        What was being written, as the message names it.
    outcome : str
        The closing sentence: what is left as it was, what to do next.
    full_disk_notes : tuple of str
        Further notes for a full disk or an exceeded quota.
    """
    reason = exc.strerror or str(exc)
    if exc.filename is not None:
        path = Path(os.fsdecode(exc.filename))
        folder = next(
            (
                p
                for p in path.parents
                if p == target
                or (p.parent == target.parent and p.name.startswith(f".{target.name}."))
            ),
            None,
        )
        reason += f" (writing {path.relative_to(folder)})" if folder else f": '{path}'"
    message = f"cannot write {what} to '{target}': {reason}"
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        notes = []
        try:
            fs = os.statvfs(next(p for p in (target, *target.parents) if p.exists()))
            notes.append(f"{fs.f_bavail * fs.f_frsize / 1e6:.1f} MB free there")
        except OSError:
            pass
        notes += full_disk_notes
        if notes:
            message += f" ({'; '.join(notes)})"
    if exc.errno in _HINTS:
        message += f"; {_HINTS[exc.errno]}"
    return OutputError(exc.errno or errno.EIO, f"{message}. {outcome}")


def _error(exc: OSError, out: Path) -> OutputError:
    """``exc`` (raised while writing the report to ``out``) as a message saying where and why."""
    earlier = ("the earlier report stays until the new one is complete, so both must fit",)
    return write_error(
        exc, out, "the report", f"'{out}' is unchanged.", earlier if out.exists() else ()
    )


def _listed(out: Path) -> set[str] | None:
    """The files listed in the manifest of the report in ``out``, None if it has none."""
    try:
        files = json.loads((out / MANIFEST).read_text(encoding="utf-8"))["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return {str(name) for name in files} if isinstance(files, list) else None


def _refuse_foreign(out: Path, written: set[str] | None) -> None:
    """Raise :class:`OutputError` if ``out`` is not a folder, is a mount point or holds anything
    that is not part of a report: neither in its manifest nor in ``written`` (the new report's
    files; None: not known yet, then a folder without a manifest is not judged)."""
    if not out.is_dir():
        raise OutputError(errno.ENOTDIR, f"'{out}' is a file, not a folder")
    if os.path.ismount(out):
        raise OutputError(
            errno.EBUSY,
            (
                f"'{out}' is a mount point, which cannot be replaced as a whole; choose a folder "
                f"inside it, e.g. '{out / 'report'}'"
            ),
        )
    listed = _listed(out)
    if listed is None and written is None:
        return
    foreign = sorted(set(os.listdir(out)) - (listed or set()) - (written or set()) - {MANIFEST})
    if foreign:
        shown = ", ".join(foreign[:5]) + (
            f" and {len(foreign) - 5} more" if len(foreign) > 5 else ""
        )
        raise OutputError(
            errno.EEXIST,
            (
                f"'{out}' holds {shown}, not files of a flexsat report; a report folder is "
                "replaced as "
                "a whole: move those away or choose another folder"
            ),
        )


def _probe(folder: Path, name: str) -> None:
    """Create, write, flush and remove a small file in ``folder``: raises what writing would."""
    path = folder / f".{name}.probe-{secrets.token_hex(6)}"
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        exc.filename = str(folder)  # the folder that refuses, not the probe's name
        raise
    try:
        os.write(fd, bytes(4096))  # one block: fails on a full disk
        os.fsync(fd)
    finally:
        os.close(fd)
        os.unlink(path)


def check_output_folder(out_dir: str | os.PathLike[str]) -> Path:
    """Check, before any work, that a report can be published as ``out_dir``.

    ``out_dir`` must be a folder or not exist yet; the closest existing parent must let a file
    be created, written and flushed (a probe file, removed again); an existing report folder must
    hold nothing flexsat did not write (when its manifest says so). Nothing is created.

    Parameters
    ----------
    out_dir : str or Path

    Returns
    -------
    Path
        ``out_dir`` resolved (absolute, symbolic links followed).

    Raises
    ------
    OutputError
        Saying where and why (read-only file system, disk full, a file where a folder is
        expected, permission denied, ...).
    """
    out = _resolve(out_dir)
    try:
        if out.exists():
            _refuse_foreign(out, None)
        base = out.parent
        while not base.exists():
            base = base.parent
        if not base.is_dir():
            raise OutputError(
                errno.ENOTDIR, f"'{base}' is a file, not a folder: cannot create '{out}'"
            )
        _probe(base, out.name)
    except OutputError:
        raise
    except OSError as exc:
        raise _error(exc, out) from exc
    return out


def _temporary(out: Path, kind: str) -> Path:
    # time first, so that names sort by age (the newest ``old`` is restored after a crash)
    return out.parent / f".{out.name}.{kind}-{time.time_ns():016x}{secrets.token_hex(4)}"


def _recover(out: Path) -> None:
    """Restore the previous report if a crash left it renamed away, then remove the temporary
    folders of earlier runs that no live process locks. Call under the parent folder's lock."""
    pattern = re.compile(rf"\.{re.escape(out.name)}\.(tmp|old)-[0-9a-f]+")
    stale = []
    for entry in sorted(os.scandir(out.parent), key=lambda e: e.name):
        if not (pattern.fullmatch(entry.name) and entry.is_dir(follow_symlinks=False)):
            continue
        try:
            fd = _open_folder(Path(entry.path))
        except FileNotFoundError:
            # its writer removed it after publishing, which it does outside the parent's lock
            continue
        try:
            if try_lock(fd):
                stale.append(Path(entry.path))
        finally:
            os.close(fd)
    old = [p for p in stale if ".old-" in p.name]
    if old and not os.path.lexists(out):
        os.rename(old[-1], out)
        stale.remove(old[-1])
        log.warning("restored the report %s that an interrupted run had moved away", out)
    for path in stale:
        shutil.rmtree(path, ignore_errors=True)


def _fsync(path: str | os.PathLike[str]) -> None:
    """Flush the file or folder ``path`` to the disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_tree(folder: Path) -> None:
    for root, _, files in os.walk(folder):
        for name in [*files, "."]:
            _fsync(os.path.join(root, name))


def _swap(new: Path, out: Path) -> Path:
    """Publish the folder ``new`` as ``out``; return what to remove (the previous report)."""
    if not os.path.lexists(out):
        os.rename(new, out)
        return new
    _refuse_foreign(out, set(os.listdir(new)))
    os.chmod(new, stat.S_IMODE(out.stat().st_mode))  # keep the folder's permissions
    if _exchange(new, out):
        return new
    old = _temporary(out, "old")
    os.rename(out, old)
    try:
        os.rename(new, out)
    except BaseException:
        os.rename(old, out)
        raise
    return old


def write_metrics_and_results(result: ReportedResult, folder: Path, ds: xr.Dataset) -> None:
    """The two data files most scenario reports start with: ``metrics.json`` (one record per
    run, the result's ``metrics_records()``) and ``results.nc`` (its dataset ``ds``, netCDF4
    without pickle)."""
    from flexsat.netcdf import write_netcdf
    from flexsat.report.json_data import dumps

    records = result.metrics_records()
    (folder / "metrics.json").write_text(dumps(records), encoding="utf-8")
    write_netcdf(ds, folder / "results.nc")


def write_atomically(
    out_dir: str | os.PathLike[str],
    write: Callable[[Path], None],
    *,
    timeout: float = LOCK_TIMEOUT_S,
) -> Path:
    """Run ``write(folder)`` on a new temporary folder and publish it as ``out_dir`` whole (see
    the module docstring): ``out_dir`` holds the complete previous report or the complete new one
    whatever fails or is killed.

    Parameters
    ----------
    out_dir : str or Path
        The report folder: created (with its parents) if needed, else replaced as a whole; it
        must hold nothing but an earlier report.
    write : callable
        Writes the report's files into the folder it is given.
    timeout : float
        Seconds to wait for another writer's publishing step in the same parent folder.

    Returns
    -------
    Path
        ``out_dir`` resolved (absolute, symbolic links followed).

    Raises
    ------
    OutputError
        For every error of the file system (with ``errno``: ENOSPC for a full disk, EROFS, ...)
        and when ``out_dir`` holds other files; exceptions of ``write`` that are not ``OSError``
        propagate unchanged. Either way ``out_dir`` is unchanged.
    """
    out = _resolve(out_dir)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        with _locked(out.parent, timeout):
            _recover(out)
            folder = _temporary(out, "tmp")
            folder.mkdir()
            fd = _open_folder(folder)
            try_lock(fd)  # marks the folder as live until fd is closed
        try:
            write(folder)
            files = sorted(os.listdir(folder))
            (folder / MANIFEST).write_text(
                json.dumps({"files": files}, indent=1) + "\n", encoding="utf-8"
            )
            _fsync_tree(folder)
            with _locked(out.parent, timeout):
                previous = _swap(folder, out)
            with suppress(OSError):  # published already; this only hastens its way to the disk
                _fsync(out.parent)
        finally:
            os.close(fd)
            # a partial report after a failure; the previous report after an exchange
            shutil.rmtree(folder, ignore_errors=True)
        shutil.rmtree(previous, ignore_errors=True)
    except OutputError:
        raise
    except OSError as exc:
        raise _error(exc, out) from exc
    return out


__all__ = [
    "LOCK_TIMEOUT_S",
    "MANIFEST",
    "OutputError",
    "check_output_folder",
    "write_atomically",
    "write_error",
    "write_metrics_and_results",
]
