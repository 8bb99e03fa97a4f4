"""Read ahead of the consumer: decode the next frame sets while the pipeline works on this one.

Decoding a 640x480 frame costs about 0.7 ms (`cv2.VideoCapture.read`), 2.5-3 ms per frame set
of four cameras, 7-8 % of a run on one core. OpenCV releases the GIL while it decodes, so a
reader thread overlaps that work with the pipeline's wherever a second core has time for it;
on one core it costs only the thread switches. The items and their order are exactly those of
the source, so a run's output does not change.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Iterable, Iterator
from typing import TypeVar

T = TypeVar("T")

_DONE = object()  # the source is exhausted


class _Failure:
    """An exception the source raised, carried to the consumer's thread."""

    __slots__ = ("exc",)

    def __init__(self, exc: BaseException) -> None:
        self.exc = exc


def prefetched(items: Iterable[T], depth: int = 2) -> Iterator[T]:
    """The items of ``items``, in order, produced by a reader thread at most ``depth`` ahead.

    Memory stays bounded: at most ``depth`` items wait besides the one being produced. An
    exception of the source is raised here, in the consumer, where the source would have
    raised it. When the consumer stops early (``close()``, an exception, garbage collection),
    the reader stops after its current item and the source is closed in the reader's thread,
    so a generator's ``finally`` (closing video files) still runs.

    Parameters
    ----------
    items : iterable, typically a generator of frame sets
    depth : int, >= 1

    >>> list(prefetched(iter(range(5)), depth=1))
    [0, 1, 2, 3, 4]
    """
    if depth < 1:
        raise ValueError(f"depth must be >= 1, got {depth}")
    return _read_ahead(items, depth)


def _read_ahead(items: Iterable[T], depth: int) -> Iterator[T]:
    """:func:`prefetched`'s generator (the reader thread starts with the first ``next``)."""
    ready: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def put(item: object) -> bool:
        """Hand ``item`` over unless the consumer has left; False once it has."""
        while not stop.is_set():
            try:
                ready.put(item, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def read() -> None:
        source = iter(items)
        try:
            for item in source:
                if not put(item):
                    break
            else:
                put(_DONE)
        except BaseException as exc:  # carried to the consumer, re-raised there
            put(_Failure(exc))
        finally:
            close = getattr(source, "close", None)
            if close is not None:
                close()

    reader = threading.Thread(target=read, name="surveil-prefetch", daemon=True)
    reader.start()
    try:
        while True:
            item = ready.get()
            if item is _DONE:
                return
            if isinstance(item, _Failure):
                raise item.exc
            yield item
    finally:
        stop.set()
        reader.join()
