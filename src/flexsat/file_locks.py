"""Advisory file locks without waiting, for the writers that must not run twice on one target
(a report folder, a sweep store): :func:`try_lock`."""

from __future__ import annotations

import errno
import fcntl

__all__ = ["NO_LOCKS", "try_lock"]

#: errors of flock that mean the file system has no locks (NFS emulates flock with POSIX locks,
#: whose exclusive kind needs a file open for writing: EBADF)
NO_LOCKS = frozenset({errno.ENOLCK, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EINVAL, errno.EBADF})


def try_lock(fd: int) -> bool | None:
    """Take an exclusive lock on ``fd`` without waiting: True if taken, False if another open
    file holds it, None where the file system has no locks (:data:`NO_LOCKS`)."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    except OSError as exc:
        if exc.errno in NO_LOCKS:
            return None
        raise
    return True
