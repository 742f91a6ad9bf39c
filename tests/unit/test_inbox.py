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


def test_a_kind_with_a_cap_is_dropped_past_it_while_the_others_still_come_in() -> None:
    inbox: Inbox[str] = Inbox(max_items=100, caps={"look": 2})
    assert [inbox.offer("look", f"l{k}") for k in range(4)] == [True, True, False, False]
    assert inbox.offer("alive", "a") and inbox.offer("alive", "b")  # not capped
    assert inbox.get_nowait() == "l0" and inbox.offer("look", "l4")  # room again once taken
    assert inbox.dropped == {"look": 2} and len(inbox) == 4


def test_the_worlds_caps_hold_a_round_of_every_robot_and_little_more() -> None:
    from fatswarm.world.service import inbox_caps

    for n in (1, 8, 4096):
        caps = inbox_caps(n)
        assert caps["look"] >= 2 * n and caps["move"] >= n and caps["control"] >= 8
    assert inbox_caps(4)["look"] < 100  # what a flood of Looks may queue (each costs memory)


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
