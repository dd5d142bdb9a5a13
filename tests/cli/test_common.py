"""cli/common.Spread hands the Dask connection deadline (--connect-timeout) to the parallel layer with the scheduler
(a parallel.executors.Scheduler), never through a module global (issue 40, item 3)."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from brdfnorm.cli.common import Spread
from brdfnorm.errors import ArgumentError
from brdfnorm.parallel import executors
from brdfnorm.parallel.executors import Scheduler, Workers


@pytest.fixture
def silent_server():
    """A TCP server that accepts connections (the kernel's backlog) and never says a byte: a client waits on it
    until its own deadline."""
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(8)
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"


def test_each_spread_carries_its_own_deadline_and_sets_nothing_global():
    before = executors.DASK_CONNECT_TIMEOUT
    short = Spread(scheduler="tcp://127.0.0.1:8786", connect_timeout=0.5)
    long = Spread(scheduler="TCP://127.0.0.1:8786", connect_timeout=30.0)
    assert short.dask_scheduler() == Scheduler("tcp://127.0.0.1:8786", 0.5)
    assert long.dask_scheduler() == Scheduler("tcp://127.0.0.1:8786", 30.0)  # the address normalized
    assert Spread(scheduler="tcp://127.0.0.1:8786").dask_scheduler() == "tcp://127.0.0.1:8786"
    assert Spread(connect_timeout=3.0).dask_scheduler() is None
    assert executors.DASK_CONNECT_TIMEOUT == before
    assert Workers(scheduler="tcp://127.0.0.1:8786").connect_timeout == before
    assert Workers(scheduler=short.dask_scheduler()).connect_timeout == 0.5


@pytest.mark.parametrize("timeout", [0, -1.0, float("nan"), float("inf"), True, "5"])
def test_a_bad_deadline_is_refused_by_its_api_name(timeout):
    with pytest.raises(ArgumentError, match="connect_timeout") as caught:
        Scheduler("tcp://127.0.0.1:8786", timeout)
    assert caught.value.where == "connect_timeout"


def test_two_spreads_with_different_deadlines_connecting_at_once_keep_their_own(silent_server):
    pytest.importorskip("distributed")
    outcomes: dict[float, tuple[str, float]] = {}

    def connect(timeout: float) -> None:
        start = time.monotonic()
        try:
            with Workers(scheduler=Spread(scheduler=silent_server, connect_timeout=timeout).dask_scheduler()) as pool:
                pool.start()
        except ArgumentError as error:
            outcomes[timeout] = (str(error), time.monotonic() - start)

    threads = [threading.Thread(target=connect, args=(timeout,)) for timeout in (0.3, 1.5)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    (short, short_s), (long, long_s) = outcomes[0.3], outcomes[1.5]
    assert "within 0.3 s" in short and "within 1.5 s" in long
    assert 0.3 <= short_s < 1.4 and long_s >= 1.5  # the short one did not wait for the long one's deadline
