"""Where the chunks of a batch run: an in-process cluster, local worker processes, or an existing
dask scheduler, which is asked who it is before anything is sent to it.

An address is checked by :func:`check_scheduler` before a :class:`distributed.Client` is made
for it, because a client that cannot connect fails in ways that name neither the field nor the
address: it retries a refused connection until its timeout, reads the reply of something that
is not a scheduler (an HTTP proxy) as a message length and raises ``MemoryError``, and the
half-made client then spends another 10 s closing when it is collected. The check opens one
connection (a refused one fails at once), does distributed's handshake and asks the
``identity`` of what answers (a scheduler says ``{"type": "Scheduler", ...}``), all within
:data:`CONNECT_TIMEOUT` seconds, and refuses the address with a
:class:`~flexsat.input_checks.FieldError` of the field ``scheduler`` otherwise.
"""

from __future__ import annotations

import asyncio
import logging
import socket
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from typing import Any

from flexsat.input_checks import FieldError, require_count

#: seconds to wait for an existing scheduler to answer before refusing its address
CONNECT_TIMEOUT = 5.0


async def _identity(address: str) -> Any:
    """What the server at ``address`` says it is (distributed's ``identity`` operation)."""
    from distributed.comm import connect

    comm = await connect(address, timeout=CONNECT_TIMEOUT)  # with distributed's handshake
    try:
        await comm.write({"op": "identity", "reply": True})
        return await comm.read()
    finally:
        comm.abort()


def _ask_identity(address: str) -> Any:
    """:func:`_identity` within :data:`CONNECT_TIMEOUT` s in all (distributed's handshake has
    no timeout of its own: a server that accepts and stays silent would hold it forever)."""
    return asyncio.run(asyncio.wait_for(_identity(address), CONNECT_TIMEOUT))


def check_scheduler(address: str) -> None:
    """Refuse ``address`` unless a dask scheduler answers there within :data:`CONNECT_TIMEOUT`
    seconds (module docstring).

    Parameters
    ----------
    address : str
        ``tcp://HOST:PORT`` (or another scheme distributed knows).

    Raises
    ------
    FieldError
        Of the field ``scheduler``: nothing answers, the connection fails, or what answers is
        not a dask scheduler.
    """
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port

    def refuse(why: str) -> FieldError:
        return FieldError("scheduler", f"no dask scheduler answered at {address!r}: {why}")

    try:
        scheme, location = parse_address(address)
    except (TypeError, ValueError) as exc:
        raise FieldError("scheduler", f"not a scheduler address ({exc})") from None
    if scheme == "tcp":  # a refused or unroutable address fails here at once, not after retries
        try:
            host, port = parse_host_port(location)
            socket.create_connection((host, port), timeout=CONNECT_TIMEOUT).close()
        except (OSError, ValueError) as exc:
            raise refuse(f"{type(exc).__name__}: {exc}") from None
    # in a thread of its own: the caller may be running an event loop already (a notebook)
    with ThreadPoolExecutor(1) as pool:
        try:
            reply = pool.submit(_ask_identity, address).result()
        except TimeoutError:
            raise refuse(f"nothing answered within {CONNECT_TIMEOUT:g} s") from None
        except Exception as exc:  # noqa: BLE001 - whatever fails, nothing usable answered
            raise refuse(
                f"the connection failed ({type(exc).__name__}: {str(exc)[:200]})"
            ) from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise refuse(f"what answers there is a {kind!s}, not a dask scheduler")


#: the loggers of a dask cluster's event loop and comms
CLUSTER_LOGGERS = ("distributed", "tornado", "asyncio")


@contextmanager
def quiet_shutdown() -> Iterator[None]:
    """Silence the cluster's loggers below CRITICAL while it is torn down after an interruption
    (restored on exit): :data:`CLUSTER_LOGGERS` and every logger under them, since dask's
    configuration gives some of those (``tornado.application``) a level of their own."""
    names = set(CLUSTER_LOGGERS) | {
        name
        for name in list(logging.root.manager.loggerDict)
        if name.split(".")[0] in CLUSTER_LOGGERS
    }
    loggers = [logging.getLogger(name) for name in sorted(names)]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels):
            logger.setLevel(level)


def batch_client(workers: int | None, scheduler: str | None) -> tuple[Any, Any]:
    """(client, cluster or None): in-process, a local cluster of ``workers`` processes, or the
    existing cluster at ``scheduler`` (checked first, :func:`check_scheduler`).

    Parameters
    ----------
    workers : int or None
        Worker processes of a local cluster.
    scheduler : str or None
        Address of an existing scheduler.
    """
    from distributed import Client, LocalCluster

    if scheduler is not None:
        if workers is not None:
            raise FieldError(
                "workers", "give workers (a local cluster) or scheduler (an existing one), not both"
            )
        check_scheduler(scheduler)
        try:
            return Client(scheduler, timeout=f"{CONNECT_TIMEOUT}s", set_as_default=False), None
        except (OSError, TimeoutError) as exc:  # it answered a moment ago
            raise FieldError(
                "scheduler",
                f"the dask scheduler at {scheduler!r} stopped answering "
                f"({type(exc).__name__}: {exc})",
            ) from None
    # no dashboard; the scheduler's own HTTP server (health checks) on a free port of this host:
    # on its default, 8787, a second cluster (another sweep) would warn that the port is taken
    quiet = {"dashboard_address": None, "scheduler_kwargs": {"dashboard_address": "127.0.0.1:0"}}
    if workers is None:
        cluster = LocalCluster(processes=False, n_workers=1, threads_per_worker=1, **quiet)
    else:
        cluster = LocalCluster(
            n_workers=require_count(workers, "workers"),
            threads_per_worker=1,
            processes=True,
            **quiet,
        )
    return Client(cluster, set_as_default=False), cluster


__all__ = [
    "CLUSTER_LOGGERS",
    "CONNECT_TIMEOUT",
    "batch_client",
    "check_scheduler",
    "quiet_shutdown",
]
