"""The bounded inbox between Zenoh callbacks and a service's thread, and the cut log lines."""

from __future__ import annotations

import logging
import queue
import threading

import pytest

from fatswarm.deploy.net.part_common import MAX_LOG_CHARS, ShortLines
from fatswarm.world.inbox import Inbox


def test_events_come_out_in_order_and_what_does_not_fit_is_dropped_and_counted() -> None:
    inbox: Inbox[int] = Inbox(max_items=3, max_bytes=100)
    assert [inbox.offer("move", k, 10) for k in range(4)] == [True, True, True, False]
    assert inbox.offer("look", 9) is False  # full by count
    assert [inbox.get_nowait() for _ in range(3)] == [0, 1, 2]
    assert inbox.offer("move", 5, 101) is False  # more bytes than it holds at all
    assert inbox.offer("move", 6, 100) and len(inbox) == 1
    assert inbox.offer("move", 7, 1) is False  # the bytes are taken until 6 is out
    assert inbox.get_nowait() == 6 and inbox.offer("move", 8, 1)
    inbox.too_big("control")
    assert inbox.dropped == {"move": 3, "look": 1, "control": 1}


def test_get_waits_for_an_offer_and_times_out_on_none() -> None:
    inbox: Inbox[str] = Inbox()
    with pytest.raises(queue.Empty):
        inbox.get(timeout=0.01)
    threading.Timer(0.05, lambda: inbox.offer("x", "late")).start()
    assert inbox.get(timeout=30.0) == "late"


def test_a_long_log_message_is_cut_saying_how_much() -> None:
    record = logging.LogRecord(
        "fatswarm.world",
        logging.WARNING,
        __file__,
        1,
        "rejected (move-garbage): %s",
        ("x" * 900_000,),
        None,
    )
    assert ShortLines().filter(record)
    message = record.getMessage()
    assert len(message) < MAX_LOG_CHARS + 60
    assert message.endswith(
        f"({900_000 + len('rejected (move-garbage): ') - MAX_LOG_CHARS} more characters cut)"
    )
    short = logging.LogRecord("x", logging.INFO, __file__, 1, "round %d", (3,), None)
    assert ShortLines().filter(short) and short.getMessage() == "round 3"
