"""An agent waiting for its router says so every WAIT_NOTICE_S, how long so far, and once the
router answers, after how long; it says nothing if the router answers before the first notice.
Driven on a clock of its own (a stand-in for zenoh whose open fails until the router is "up"), so
the notices' rhythm is pinned without waiting for it; tests/integration/test_part_errors.py pins
that every kind of agent host prints the notice, for the robots it runs, over a real Zenoh."""

from __future__ import annotations

import logging
import re
import sys
import types
from typing import Any

import pytest

from fatswarm.agent import service
from fatswarm.agent.service import OPEN_RETRY_S, WAIT_NOTICE_S, open_session

ENDPOINT = "tcp/127.0.0.1:7447"
SESSION = object()  # what the stand-in's open returns once the router is up


class Clock:
    """time.monotonic, advanced only by the agent's own retry waits."""

    def __init__(self) -> None:
        self.now = 1000.0

    def monotonic(self) -> float:
        return self.now


class Stop:
    """The agent's stop event: never set unless `stop_at` is reached; each wait moves the clock."""

    def __init__(self, clock: Clock, stop_at: float = float("inf")) -> None:
        self.clock, self.stop_at = clock, stop_at
        self.waits: list[float] = []

    def is_set(self) -> bool:
        return self.clock.now >= self.stop_at

    def wait(self, seconds: float) -> bool:
        self.waits.append(seconds)
        self.clock.now += seconds
        return self.is_set()


class Conf:
    """A Zenoh config as `_endpoints` reads it."""

    def get_json(self, key: str) -> str:
        assert key == "connect/endpoints"
        return f'["{ENDPOINT}"]'


def stand_in_zenoh(clock: Clock, up_at: float) -> types.ModuleType:
    """A zenoh module whose open fails (as with no router) until the clock reaches `up_at`."""
    module = types.ModuleType("zenoh")

    class ZError(Exception):
        pass

    def open_(conf: Any) -> object:
        if clock.now < up_at:
            raise ZError("Unable to connect to any of [tcp/127.0.0.1:7447]!")
        return SESSION

    module.ZError = ZError  # type: ignore[attr-defined]
    module.open = open_  # type: ignore[attr-defined]
    return module


def wait_for_router(
    caplog: pytest.LogCaptureFixture, up_after: float, waiting: str | None, stop_after: float
) -> tuple[object, list[str], Stop]:
    """open_session against a router up after `up_after` s (stopped after `stop_after` s): what it
    returned, the warnings it logged, and its stop event."""
    clock = Clock()
    stop = Stop(clock, clock.now + stop_after)
    with pytest.MonkeyPatch.context() as patch:  # undone before the unit tests' guard is
        patch.setitem(sys.modules, "zenoh", stand_in_zenoh(clock, clock.now + up_after))
        patch.setattr(service, "time", clock)
        with caplog.at_level(logging.WARNING, logger="fatswarm.agent"):
            got = open_session(Conf(), stop, waiting)  # type: ignore[arg-type]
    return got, [r.getMessage() for r in caplog.records if r.name == "fatswarm.agent"], stop


def test_a_waiting_agent_says_every_few_seconds_how_long_it_has_waited_and_when_it_got_through(
    caplog: pytest.LogCaptureFixture,
) -> None:
    up_after = 3 * WAIT_NOTICE_S + 1.0
    got, said, stop = wait_for_router(caplog, up_after, "robot 7", stop_after=float("inf"))
    assert got is SESSION
    waiting = [m for m in said if "still waiting" in m]
    assert len(waiting) == 3, said  # one per WAIT_NOTICE_S, not one per retry
    for k, line in enumerate(waiting, start=1):
        match = re.fullmatch(
            rf"robot 7: still waiting for a Zenoh router at {ENDPOINT} \((\d+) s so far\); "
            "retrying",
            line,
        )
        assert match, line
        assert int(match.group(1)) == pytest.approx(k * WAIT_NOTICE_S, abs=1), line
    assert said[-1] == f"robot 7: the router at {ENDPOINT} answered after {up_after:.0f} s"
    assert len(said) == 4, said
    assert set(stop.waits) == {OPEN_RETRY_S}  # it retried at its pace between the notices


def test_an_agent_whose_router_answers_before_the_first_notice_says_nothing(
    caplog: pytest.LogCaptureFixture,
) -> None:
    got, said, _ = wait_for_router(caplog, WAIT_NOTICE_S / 2, "robot 7", stop_after=float("inf"))
    assert got is SESSION and said == []


def test_an_agent_told_to_keep_quiet_waits_without_a_notice(
    caplog: pytest.LogCaptureFixture,
) -> None:
    got, said, _ = wait_for_router(caplog, 2 * WAIT_NOTICE_S + 1, None, stop_after=float("inf"))
    assert got is SESSION and said == []


def test_an_agent_stopped_while_it_waits_returns_no_session(
    caplog: pytest.LogCaptureFixture,
) -> None:
    got, said, _ = wait_for_router(caplog, float("inf"), "robot 7", WAIT_NOTICE_S + 1.0)
    assert got is None
    assert [m for m in said if "still waiting" in m] != [] and not any(
        "answered" in m for m in said
    )
