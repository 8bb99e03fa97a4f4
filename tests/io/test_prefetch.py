"""The read-ahead thread: same items in the same order, errors where the source raised them,
and the source closed when the consumer stops early."""

from __future__ import annotations

import threading
import time

import pytest

from surveil.errors import InputError
from surveil.io.prefetch import prefetched


def _numbers(n: int, log: list[str], fail_at: int | None = None):
    try:
        for i in range(n):
            if i == fail_at:
                raise InputError(f"frame {i} is unreadable")
            log.append(f"read {i}")
            yield i
    finally:
        log.append(f"closed in {threading.current_thread().name}")


def test_prefetched_yields_every_item_in_order_and_closes_the_source():
    log: list[str] = []
    assert list(prefetched(_numbers(50, log), depth=3)) == list(range(50))
    assert log[-1] == "closed in surveil-prefetch"


def test_prefetched_reads_at_most_depth_ahead():
    log: list[str] = []
    it = prefetched(_numbers(100, log), depth=2)
    assert next(it) == 0
    # item 0 consumed, 1 and 2 waiting in the queue, 3 read and waiting for a slot
    time.sleep(0.2)  # time for the reader to run ahead as far as it may
    assert len([e for e in log if e.startswith("read")]) <= 4
    it.close()


def test_prefetched_raises_the_sources_error_in_the_consumer_after_the_good_items():
    log: list[str] = []
    got = []
    with pytest.raises(InputError, match="frame 3 is unreadable"):
        for item in prefetched(_numbers(10, log, fail_at=3)):
            got.append(item)
    assert got == [0, 1, 2]
    assert log[-1].startswith("closed")


def test_prefetched_stops_the_reader_and_closes_the_source_when_the_consumer_leaves():
    log: list[str] = []
    it = prefetched(_numbers(10_000, log), depth=2)
    assert [next(it), next(it)] == [0, 1]
    it.close()  # joins the reader
    assert log[-1] == "closed in surveil-prefetch"
    assert len(log) < 10  # it did not read on to the end
    assert not any(t.name == "surveil-prefetch" for t in threading.enumerate())


def test_prefetched_empty_source_and_bad_depth():
    assert list(prefetched(iter([]))) == []
    with pytest.raises(ValueError, match="depth must be >= 1"):
        prefetched(iter([1]), depth=0)  # at the call, not at the first item
