"""Publishing a report folder whole or not at all (flexsat.report.publish).

The claim under test: whatever fails or is killed while a report is written, the output folder
holds the complete previous report or the complete new one, and nothing of a failed attempt stays
behind. Each test writes reports of a few small files whose contents name the report they belong
to, so a mixture is visible.
"""

from __future__ import annotations

import errno
import fcntl
import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import flexsat.report.publish as publish
from flexsat.report.publish import (
    MANIFEST,
    OutputError,
    check_output_folder,
    write_atomically,
)

NAMES = ("metrics.json", "results.nc", "plot.png", "index.html")
SRC = str(Path(publish.__file__).resolve().parents[2])


def writer(tag: str):
    """A report of the files NAMES, each holding ``tag``."""

    def write(folder: Path) -> None:
        for name in NAMES:
            (folder / name).write_text(f"{tag}:{name}")

    return write


def contents(out: Path) -> dict[str, str]:
    return {p.name: p.read_text() for p in out.iterdir()}


def complete(tag: str) -> dict[str, str]:
    """The files of the complete report ``tag``, manifest included."""
    files = {name: f"{tag}:{name}" for name in NAMES}
    files[MANIFEST] = json.dumps({"files": sorted(NAMES)}, indent=1) + "\n"
    return files


def leftovers(parent: Path, out: Path) -> list[str]:
    return sorted(p.name for p in parent.iterdir() if p != out)


@pytest.fixture
def old_report(tmp_path):
    """``tmp_path/report`` holding the complete report "old"."""
    out = write_atomically(tmp_path / "report", writer("old"))
    assert contents(out) == complete("old")
    return out


@pytest.mark.parametrize("name", [*NAMES, MANIFEST])
def test_failure_at_each_file_keeps_the_old_report(old_report, fail_opening, name):
    fail_opening(name)
    with pytest.raises(OutputError) as info:
        write_atomically(old_report, writer("new"))
    assert info.value.errno == errno.ENOSPC
    assert contents(old_report) == complete("old")
    assert leftovers(old_report.parent, old_report) == []


def test_failure_at_flushing_keeps_the_old_report(old_report, monkeypatch):
    """Network file systems report a full disk at fsync: nothing is published before it."""

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OutputError):
        write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("old")
    assert leftovers(old_report.parent, old_report) == []


def test_exception_of_the_writer_propagates_and_keeps_the_old_report(old_report):
    def broken(folder):
        (folder / "metrics.json").write_text("partial")
        raise RuntimeError("plot failed")

    with pytest.raises(RuntimeError, match="plot failed"):
        write_atomically(old_report, broken)
    assert contents(old_report) == complete("old")
    assert leftovers(old_report.parent, old_report) == []


def test_failed_exchange_keeps_the_old_report(old_report, monkeypatch):
    def broken(a, b):
        raise OSError(errno.EIO, os.strerror(errno.EIO))

    monkeypatch.setattr(publish, "_exchange", broken)
    with pytest.raises(OutputError, match="Input/output error"):
        write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("old")
    assert leftovers(old_report.parent, old_report) == []


@pytest.mark.parametrize("failing", [1, 2])
def test_two_rename_fallback_keeps_the_old_report_when_either_rename_fails(
    old_report, monkeypatch, failing
):
    """Without renameat2: rename 1 moves the old report away, rename 2 publishes the new one;
    a failure of rename 2 puts the old report back."""
    monkeypatch.setattr(publish, "_RENAMEAT2", None)
    real, calls = os.rename, []

    def rename(a, b):
        calls.append(b)
        if len(calls) == failing:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real(a, b)

    monkeypatch.setattr(os, "rename", rename)
    with pytest.raises(OutputError):
        write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("old")
    assert leftovers(old_report.parent, old_report) == []


@pytest.mark.parametrize("exchange", [True, False], ids=["renameat2", "two renames"])
def test_rewrite_publishes_the_complete_new_report(old_report, monkeypatch, exchange):
    if not exchange:
        monkeypatch.setattr(publish, "_RENAMEAT2", None)
    old_report.chmod(0o750)
    write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("new")
    assert old_report.stat().st_mode & 0o777 == 0o750  # the folder's permissions are kept
    assert leftovers(old_report.parent, old_report) == []


def test_stale_temporaries_of_killed_runs_are_removed(old_report):
    """Simulated SIGKILL: a temporary folder with a truncated file, from before and after this
    version (``uuid`` and time-ordered names)."""
    parent = old_report.parent
    for name in (".report.tmp-0123456789ab", ".report.tmp-0187d3a1b2c3d4e5f0a1b2c3"):
        (parent / name).mkdir()
        (parent / name / "results.nc").write_bytes(b"\x89HDF\r\n")
    (parent / ".other.tmp-0123456789ab").mkdir()  # another output folder's: left alone
    write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("new")
    assert leftovers(parent, old_report) == [".other.tmp-0123456789ab"]


def test_a_crash_between_the_two_renames_is_recovered(old_report):
    """The old report was renamed away and the process died before publishing the new one: the
    next write restores the old report first, so even its own failure leaves a complete one."""
    parent = old_report.parent
    old_report.rename(parent / ".report.old-0187d3a1b2c3d4e5f0a1b2c3")
    (parent / ".report.tmp-0187d3a1b2c3d4e6f0a1b2c3").mkdir()

    def broken(folder):
        raise RuntimeError("plot failed")

    with pytest.raises(RuntimeError):
        write_atomically(old_report, broken)
    assert contents(old_report) == complete("old")
    assert leftovers(parent, old_report) == []


def test_temporary_folder_of_a_live_run_is_kept(old_report):
    live = old_report.parent / ".report.tmp-0187d3a1b2c3d4e5f0a1b2c3"
    live.mkdir()
    fd = os.open(live, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        write_atomically(old_report, writer("new"))
        assert live.is_dir()
    finally:
        os.close(fd)
    assert contents(old_report) == complete("new")


def test_without_locks_publishing_stays_whole_and_stale_folders_are_kept(old_report, monkeypatch):
    """NFS refuses flock on a folder (EBADF): a killed run's folder cannot be told from a live
    one's, so it stays; the report is still swapped in whole."""

    def no_locks(fd, operation):
        raise OSError(errno.EBADF, os.strerror(errno.EBADF))

    stale = old_report.parent / ".report.tmp-0187d3a1b2c3d4e5f0a1b2c3"
    stale.mkdir()
    monkeypatch.setattr(fcntl, "flock", no_locks)
    write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("new")
    assert leftovers(old_report.parent, old_report) == [stale.name]


KILLED_WRITER = """
import os, sys, time
from pathlib import Path
from flexsat.report.publish import write_atomically

def write(folder):
    (folder / "results.nc").write_bytes(b"truncated")
    Path(sys.argv[2]).write_text("ready")
    time.sleep(60)

write_atomically(sys.argv[1], write)
"""


def test_sigkill_while_writing_keeps_the_old_report_and_the_next_run_cleans_up(
    old_report, tmp_path
):
    ready = tmp_path / "ready"
    process = subprocess.Popen(
        [sys.executable, "-c", KILLED_WRITER, str(old_report), str(ready)],
        env={**os.environ, "PYTHONPATH": SRC},
    )
    try:
        deadline = time.monotonic() + 30
        while not ready.exists():
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
        os.kill(process.pid, signal.SIGKILL)
        process.wait(10)
    finally:
        process.kill()
    assert contents(old_report) == complete("old")
    assert [
        p.name.split("-")[0] for p in old_report.parent.iterdir() if p.name.startswith(".")
    ] == [".report.tmp"]
    write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("new")
    assert leftovers(old_report.parent, old_report) == ["ready"]


def test_concurrent_writers_never_interleave(tmp_path):
    out = tmp_path / "report"
    errors = []

    def run(tag):
        try:
            for i in range(15):
                write_atomically(out, writer(f"{tag}{i}"))
        except Exception as exc:  # reported below: the test fails on any
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(tag,)) for tag in "ab"]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    tags = {text.split(":")[0] for name, text in contents(out).items() if name != MANIFEST}
    assert len(tags) == 1  # one writer's files only
    assert contents(out) == complete(tags.pop())
    assert leftovers(tmp_path, out) == []


def test_a_folder_removed_by_its_writer_while_another_cleans_up_is_skipped(old_report, monkeypatch):
    """A writer removes its previous report (now at a temporary name) after it has published,
    outside the parent's lock; another writer's clean-up may list that folder a moment before it
    vanishes. Reproduces the race seen once on a loaded machine (ENOENT from a concurrent write)."""
    parent = old_report.parent
    vanishing = parent / f".{old_report.name}.tmp-0000000000000001aaaaaaaa"
    vanishing.mkdir()
    listing = os.scandir

    def scandir_then_the_other_writer_removes_its_folder(path):
        if not isinstance(path, (str, Path)) or Path(path) != parent or not vanishing.exists():
            return listing(path)
        with listing(path) as found:
            entries = list(found)
        vanishing.rmdir()
        return iter(entries)

    monkeypatch.setattr(publish.os, "scandir", scandir_then_the_other_writer_removes_its_folder)
    write_atomically(old_report, writer("new"))
    assert contents(old_report) == complete("new")
    assert leftovers(parent, old_report) == []


@pytest.fixture
def parent_locked(tmp_path):
    """Another run holding the lock on ``tmp_path`` (the parent of the output folder)."""
    fd = os.open(tmp_path, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX)
    yield fd
    os.close(fd)


def test_second_writer_gives_up_after_the_timeout_with_a_message(tmp_path, parent_locked):
    started = time.monotonic()
    with pytest.raises(OutputError, match="another flexsat run has been publishing") as info:
        write_atomically(tmp_path / "report", writer("new"), timeout=0.3)
    assert info.value.errno == errno.EBUSY
    assert 0.3 <= time.monotonic() - started < 5
    assert not (tmp_path / "report").exists()


def test_second_writer_waits_for_the_first(tmp_path, parent_locked, caplog):
    release = threading.Timer(0.3, fcntl.flock, [parent_locked, fcntl.LOCK_UN])
    release.start()
    with caplog.at_level(logging.WARNING, logger="flexsat.report.publish"):
        write_atomically(tmp_path / "report", writer("new"), timeout=10)
    assert "waiting up to 10 s for another flexsat run" in caplog.text
    assert contents(tmp_path / "report") == complete("new")


def test_folder_with_other_files_is_refused(tmp_path):
    out = tmp_path / "project"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    (out / "metrics.json").write_text("an old report's")
    with pytest.raises(
        OutputError,
        match=r"holds notes.txt, not files of a flexsat report; a "
        r"report folder is replaced as a whole",
    ):
        write_atomically(out, writer("new"))
    assert contents(out) == {"notes.txt": "mine", "metrics.json": "an old report's"}
    assert leftovers(tmp_path, out) == []


def test_report_of_an_earlier_version_without_manifest_is_replaced(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    for name in NAMES[:2]:
        (out / name).write_text("old")
    write_atomically(out, writer("new"))
    assert contents(out) == complete("new")


def test_the_current_folder_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(OutputError, match="is the current folder"):
        write_atomically(".", writer("new"))
    with pytest.raises(OutputError, match="is the root folder"):
        check_output_folder("/")


def test_check_refuses_a_file_where_a_folder_is_expected(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputError, match="is a file, not a folder") as info:
        check_output_folder(tmp_path / "file")
    assert info.value.errno == errno.ENOTDIR
    with pytest.raises(OutputError, match=r"file' is a file, not a folder: cannot create"):
        check_output_folder(tmp_path / "file" / "sub" / "out")


def test_check_creates_nothing(tmp_path):
    assert check_output_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "code, reason, hint",
    [
        (errno.EROFS, "Read-only file system", "choose a folder you can write to"),
        (errno.ENOSPC, "No space left on device", "free some space or choose another folder"),
        (errno.EDQUOT, "Disk quota exceeded", "free some space or choose another folder"),
        (errno.EACCES, "Permission denied", "choose a folder you can write to"),
    ],
)
def test_write_errors_say_where_and_why(old_report, fail_opening, code, reason, hint):
    fail_opening("results.nc", code)
    with pytest.raises(OutputError) as info:
        write_atomically(old_report, writer("new"))
    message = str(info.value)
    assert message.startswith(
        f"cannot write the report to '{old_report}': {reason} (writing results.nc)"
    )
    assert hint in message and message.endswith(f"'{old_report}' is unchanged.")
    assert info.value.errno == code
    if code in (errno.ENOSPC, errno.EDQUOT):
        assert "MB free there; the earlier report stays until the new one is complete" in message


def test_check_probes_the_parent(tmp_path, monkeypatch):
    real = os.open

    def read_only(path, flags, *args):
        if ".probe-" in os.fspath(path):
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), os.fspath(path))
        return real(path, flags, *args)

    monkeypatch.setattr(os, "open", read_only)
    with pytest.raises(OutputError, match="Read-only file system") as info:
        check_output_folder(tmp_path / "out")
    assert info.value.errno == errno.EROFS
