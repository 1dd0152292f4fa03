"""flexsat.file_locks: one holder at a time, released with the file; a file system without
locks says so (None) instead of pretending to lock, and any other error is raised."""

import errno
import os

import pytest

from flexsat import file_locks
from flexsat.file_locks import try_lock


def test_one_open_file_holds_the_lock_until_it_is_closed(tmp_path):
    path = tmp_path / "lock"
    path.touch()
    first, second = os.open(path, os.O_RDONLY), os.open(path, os.O_RDONLY)
    try:
        assert try_lock(first) is True
        assert try_lock(second) is False  # another open file holds it
        os.close(first)
        first = -1
        assert try_lock(second) is True  # released with the file
    finally:
        for fd in (first, second):
            if fd >= 0:
                os.close(fd)


@pytest.mark.parametrize("code", sorted(file_locks.NO_LOCKS))
def test_a_file_system_without_locks_is_told_apart(monkeypatch, code):
    def refuse(fd, operation):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(file_locks.fcntl, "flock", refuse)
    assert try_lock(3) is None


def test_any_other_error_is_raised(monkeypatch):
    def fail(fd, operation):
        raise OSError(errno.EIO, os.strerror(errno.EIO))

    monkeypatch.setattr(file_locks.fcntl, "flock", fail)
    with pytest.raises(OSError, match="Input/output error"):
        try_lock(3)
