"""The event timeline of a run as text: a table for people, JSON lines for programs
(``surveil events OUT.mcap``). Pure formatting; reading the MCAP is ``surveil.io``'s job."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence

from surveil.datatypes import ActivityEvent

COLUMNS = ("time_s", "activity", "actors", "from -> to", "object", "confidence", "span_s")


def _object(ev: ActivityEvent, colour_name: Callable[[float], str]) -> str:
    if ev.object_hue_deg is None:
        return "-"
    return f"{colour_name(ev.object_hue_deg)} ({ev.object_hue_deg:.0f} deg)"


def event_row(ev: ActivityEvent, colour_name: Callable[[float], str]) -> tuple[str, ...]:
    """One table row: climax time (s), activity, actors, giver -> taker, object, confidence,
    and the start-end span (s)."""
    transfer = f"{ev.from_actor} -> {ev.to_actor}" if ev.from_actor and ev.to_actor else "-"
    return (
        f"{ev.climax_ns / 1e9:.2f}",
        ev.activity,
        ", ".join(ev.actors) or "-",
        transfer,
        _object(ev, colour_name),
        # rounded as /events stores it (3 decimals) first, so that the table printed by a
        # run and the one `surveil events` reads back from its MCAP agree (0.985 vs 0.9851)
        f"{float(f'{ev.confidence:.3f}'):.2f}",
        f"{ev.start_ns / 1e9:.2f}-{ev.end_ns / 1e9:.2f}",
    )


def format_event_table(
    events: Sequence[ActivityEvent], colour_name: Callable[[float], str]
) -> str:
    """A fixed-width table of events, in the given order.

    Parameters
    ----------
    events : sequence of ActivityEvent
        Times are ns from t = 0 (shown in seconds).
    colour_name : callable
        Hue in degrees -> colour word (e.g. ``surveil.io.mcap_writer.hue_name``).

    Examples
    --------
    >>> ev = ActivityEvent("clap", 1_000_000_000, 1_500_000_000, 2_000_000_000,
    ...                    ("p1/left_hand", "p1/right_hand"), ("p1",), "default.toml:clap", 0.9)
    >>> print(format_event_table([ev], str))  # doctest: +NORMALIZE_WHITESPACE
    time_s  activity  actors                      from -> to  object  confidence  span_s
    1.50    clap      p1/left_hand, p1/right_hand  -          -       0.90        1.00-2.00
    """
    rows = [COLUMNS, *(event_row(ev, colour_name) for ev in events)]
    widths = [max(len(r[i]) for r in rows) for i in range(len(COLUMNS))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    return "\n".join(lines)


def event_json(ev: ActivityEvent, colour_name: Callable[[float], str]) -> str:
    """One JSON line per event; times in ns from t = 0, keys as the ``/events`` metadata of
    formats.md plus ``start_ns``, ``end_ns`` and ``object_colour``.

    >>> ev = ActivityEvent("pick", 0, 5, 9, ("p1/right_hand",), ("p1",), "d.toml:pick", 0.5, 215.0)
    >>> json.loads(event_json(ev, lambda h: "blue"))["object_colour"]
    'blue'
    """
    from surveil.io.ground_truth import event_to_dict

    record = event_to_dict(ev)  # the one mapping of an event's fields to JSON keys
    record.pop("object")
    record["object_colour"] = None if ev.object_hue_deg is None else colour_name(ev.object_hue_deg)
    record.update(confidence=ev.confidence, rule=ev.rule)
    return json.dumps(record)
