"""The dask cluster of a sweep (flexsat.design.batch_cluster): a scheduler address checked before
a client waits on it, the choice of cluster refused by field, and a cluster torn down after
Ctrl-C without its cancelled callbacks' tracebacks. (A silent or non-dask server at the address:
tests/design/test_batch_store.py, with the command line's exit code.)"""

import logging
import socket

import pytest

from flexsat.design.batch_cluster import (
    CLUSTER_LOGGERS,
    batch_client,
    check_scheduler,
    quiet_shutdown,
)
from flexsat.input_checks import FieldError


def _closed_port() -> int:
    """A local port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_refused_address_is_refused_by_field_at_once():
    address = f"tcp://127.0.0.1:{_closed_port()}"
    with pytest.raises(FieldError, match=f"no dask scheduler answered at '{address}'") as err:
        check_scheduler(address)
    assert err.value.field == "scheduler"


@pytest.mark.parametrize("address", ["", "tcp://", "tcp://host:notaport", "nonsense://x:1"])
def test_what_is_no_address_is_refused_by_field(address):
    with pytest.raises(FieldError) as err:
        check_scheduler(address)
    assert err.value.field == "scheduler"


def test_a_local_cluster_and_a_scheduler_are_not_asked_for_together():
    with pytest.raises(FieldError, match="give workers .* or scheduler .*, not both") as err:
        batch_client(2, "tcp://127.0.0.1:1")
    assert err.value.field == "workers"


def test_an_interrupted_cluster_is_torn_down_quietly_and_the_log_levels_come_back(caplog):
    # the cancelled callbacks of a cluster stopped mid-task log tracebacks at ERROR (some of the
    # loggers with a level of their own, as dask's configuration sets): silenced while it is
    # torn down after Ctrl-C, every level restored after
    own = logging.getLogger("tornado.application")
    own.setLevel(logging.ERROR)
    before = [logging.getLogger(n).level for n in CLUSTER_LOGGERS] + [own.level]
    with caplog.at_level(logging.DEBUG):
        with quiet_shutdown():
            own.error("Exception in callback")
            logging.getLogger("distributed.comm").error("CommClosedError")
        own.error("after")
    messages = [r.getMessage() for r in caplog.records]
    assert "Exception in callback" not in messages and "CommClosedError" not in messages
    assert "after" in messages
    assert [logging.getLogger(n).level for n in CLUSTER_LOGGERS] + [own.level] == before
