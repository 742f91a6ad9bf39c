"""The agent's Look wait: a world that comes up cuts it short (its query cancelled) and the Look
is asked again; a reply or the query's own end do not count as cut short."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest
import zenoh

from fatswarm.agent.service import Relook, _look, _LookWait
from fatswarm.world.protocol import LookRequest


class WorldToken:
    """A liveliness sample as the agent's subscriber on the world's token gets it."""

    def __init__(self, kind: Any = zenoh.SampleKind.PUT) -> None:
        self.kind = kind


class Querier:
    """A querier whose get lets `during` run first (a world coming up at that moment)."""

    def __init__(self, wait: _LookWait, replies: list[Any], during: str) -> None:
        self.wait, self.replies, self.during = wait, replies, during

    def get(self, payload: bytes, cancellation_token: Any) -> Iterator[Any]:
        assert LookRequest.decode(payload) == LookRequest()
        if self.during == "before-send":
            self.wait.world_seen(WorldToken())
        if cancellation_token.is_cancelled:
            raise zenoh.ZError("Query was cancelled")
        return self._replies(cancellation_token)

    def _replies(self, token: Any) -> Iterator[Any]:
        if self.during == "while-held":
            self.wait.world_seen(WorldToken())
            assert token.is_cancelled
            return  # a cancelled query ends with no reply
        yield from self.replies
        if self.during == "after-reply":
            self.wait.world_seen(WorldToken())


@dataclass
class Timeout:
    ok: Any = None
    err: Any = None


@pytest.mark.parametrize("during", ["before-send", "while-held"])
def test_a_world_that_comes_up_while_a_look_waits_has_it_asked_again(during: str) -> None:
    wait = _LookWait(threading.Event())
    with pytest.raises(Relook):
        _look(Querier(wait, [], during), LookRequest(), wait)
    assert wait.cancel is None and not wait.waiting


def test_a_look_that_ran_out_is_not_cut_short_by_a_world_that_came_up_after() -> None:
    wait = _LookWait(threading.Event())
    assert _look(Querier(wait, [Timeout()], "after-reply"), LookRequest(), wait) is None
    assert wait.cancel is None


def test_a_world_that_came_up_during_an_earlier_look_does_not_cut_the_next_one_short() -> None:
    wait = _LookWait(threading.Event())
    wait.begin()
    wait.world_seen(WorldToken())
    wait.end()
    assert _look(Querier(wait, [Timeout()], ""), LookRequest(), wait) is None


def test_a_failed_get_that_was_not_cancelled_is_raised() -> None:
    class Broken(Querier):
        def get(self, payload: bytes, cancellation_token: Any) -> Iterator[Any]:
            raise zenoh.ZError("no route")

    wait = _LookWait(threading.Event())
    with pytest.raises(zenoh.ZError):
        _look(Broken(wait, [], ""), LookRequest(), wait)


def test_a_world_seen_while_no_look_waits_changes_nothing() -> None:
    wait = _LookWait(threading.Event())
    wait.world_seen(WorldToken())
    wait.world_seen(WorldToken(kind=zenoh.SampleKind.DELETE))
    assert wait.cancel is None and not wait.world_up


def test_a_second_stop_signal_while_the_first_unwinds_raises_nothing() -> None:
    """SIGTERM then SIGINT (the launcher's stop and a Ctrl-C) may both reach an agent: the first
    ends its Look's wait; the second, arriving while the first unwinds (the wait not yet marked
    over, or the handlers being put back), only sets `stop` (it once escaped as a traceback)."""
    from fatswarm.agent.service import Stopped

    stop = threading.Event()
    wait = _LookWait(stop)
    wait.begin()  # a Look waits
    with pytest.raises(Stopped):
        wait.handle(15, None)
    wait.handle(2, None)  # still marked waiting: the first Stopped is unwinding
    assert stop.is_set()
