"""Floods of rogue messages the world must refuse, from a client that is no part of the swarm (on
a swarm without access control, where they reach the world). Reused by
tests/integration/test_flood.py and bench/bench_flood.py.

`flood`: one of every kind of rejection the world names, none of which changes the run (moves for
another robot, for a round that is not open, garbage, Looks for a robot the run does not have
carrying a move, garbage Looks and control requests). `burst`: Looks on one robot's key, fired
without waiting.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from fatswarm.domain.path import Line, Path
from fatswarm.world.protocol import (
    Hello,
    LookRequest,
    MoveSubmitted,
    control_key,
    move_key,
    snapshot_key,
)

FAR = Path((Line((0.0, 25.0)),))
# the reasons the world names for what `flood` sends (the world's log says them)
REASONS = (
    "move-wrong-robot",
    "move-wrong-round",
    "move-garbage",
    "look-bad-key",
    "look-garbage",
    "control-garbage",
)
ASK_EVERY = 10  # one message in ASK_EVERY is a query (a get waits for its answer)


def _messages(swarm: str, n: int) -> list[tuple[str, str, bytes]]:
    """One of each rogue message: (put or get, key, payload)."""
    robot = n - 1
    return [
        ("put", move_key(swarm, robot), MoveSubmitted((robot + 1) % n, 1, FAR).encode()),
        ("put", move_key(swarm, robot), MoveSubmitted(robot, 10**9, FAR).encode()),
        ("put", move_key(swarm, robot), b"\x93garbage"),
        ("put", move_key(swarm, 0), b"\xc1"),
        ("put", move_key(swarm, 0), MoveSubmitted(0, 10**9 + 1, FAR).encode()),
        ("put", move_key(swarm, 1), MoveSubmitted(2, 1, FAR).encode()),
        ("put", move_key(swarm, 1), b"\x81\xa1v\x01"),
        ("put", move_key(swarm, 2), MoveSubmitted(2, 10**9 + 2, FAR).encode()),
        ("put", move_key(swarm, 2), b"not msgpack at all"),
        (
            "get",
            snapshot_key(swarm, n + 70),
            LookRequest(move=MoveSubmitted(n + 70, 1, FAR).encode()).encode(),
        ),
        ("get", snapshot_key(swarm, robot), b"\x81"),
        ("get", control_key(swarm), b"\x00\x01"),
    ]


def flood(session: Any, swarm: str, n: int, count: int) -> None:
    """Send `count` rogue messages from `session` (puts, and one get in ASK_EVERY, each waited
    for), then wait until the world has taken them all in (a Hello behind them is answered)."""
    puts = [(k, p) for how, k, p in _messages(swarm, n) if how == "put"]
    gets = [(k, p) for how, k, p in _messages(swarm, n) if how == "get"]
    for i in range(count):
        if i % ASK_EVERY == ASK_EVERY - 1:
            key, payload = gets[(i // ASK_EVERY) % len(gets)]
            list(session.get(key, payload=payload, timeout=5.0))
        else:
            key, payload = puts[i % len(puts)]
            session.put(key, payload)
    wait_answered(session, swarm)


def burst(session: Any, swarm: str, robot: int, count: int) -> None:
    """Fire `count` Looks on robot `robot`'s key without waiting for their answers, garbage and
    valid ones in turn (what its stolen key could do), then wait until the world has taken them
    in. The Looks the world queues cost it the most memory of any message."""
    key = snapshot_key(swarm, robot)
    payloads = (b"\x81garbage" * 3, LookRequest().encode())
    for i in range(count):
        session.get(key, payload=payloads[i % 2], timeout=1.0)
    wait_answered(session, swarm)


def wait_answered(session: Any, swarm: str, deadline_s: float = 120.0) -> None:
    """Wait until the world answers a Hello from `session` (it is behind whatever it sent)."""
    _until(lambda: _answered(session, swarm), deadline_s, "the world to answer a Hello")


def _answered(session: Any, swarm: str) -> bool:
    replies = session.get(control_key(swarm), payload=Hello().encode(), timeout=2.0)
    return any(r.ok is not None for r in replies)


def _until(predicate: Callable[[], bool], deadline_s: float, what: str) -> None:
    end = time.monotonic() + deadline_s
    while not predicate():
        if time.monotonic() > end:
            raise TimeoutError(f"timed out waiting for {what}")
        time.sleep(0.05)


def rss_kb(pid: int) -> int:
    """The resident memory of process `pid`, in kB."""
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise ValueError(f"no VmRSS for {pid}")
