"""An agent whose Look may have been lost with a router asks again when a world comes up."""

from __future__ import annotations

import queue
import secrets
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from netharness import part

from fatswarm.deploy.net.children import Children
from fatswarm.deploy.net.zconf import loopback_endpoint, make_config
from fatswarm.world.protocol import LookRequest, MoveSubmitted, Snapshot, alive_key, snapshot_key

pytestmark = pytest.mark.integration
DEADLINE_S = 60.0  # generous: the machine is shared; waits are on predicates


def _next(looks: queue.Queue[tuple[LookRequest, Any]], log: Path) -> tuple[LookRequest, Any]:
    try:
        return looks.get(timeout=DEADLINE_S)
    except queue.Empty:
        pytest.fail(f"no Look came\n{log.read_text(errors='replace')}")


def test_a_look_held_when_a_world_comes_up_is_asked_again_with_its_move(tmp_path: Path) -> None:
    import zenoh

    endpoint, swarm = loopback_endpoint(), f"relook-{secrets.token_hex(3)}"
    looks: queue.Queue[tuple[LookRequest, Any]] = queue.Queue()

    def take(query: Any) -> None:  # a fake world that answers only the first Look
        payload = query.payload.to_bytes() if query.payload is not None else b""
        looks.put((LookRequest.decode(payload), query))

    log = tmp_path / "agent.log"
    held: list[Any] = []
    with (
        zenoh.open(make_config("router", listen=[endpoint])),
        zenoh.open(make_config("client", [endpoint])) as world,
        Children() as children,
    ):
        world.declare_queryable(snapshot_key(swarm, 0), take)
        with open(log, "ab") as out:
            children.start(
                "agent",
                part(
                    "agent",
                    "--connect",
                    endpoint,
                    "--swarm",
                    swarm,
                    "--robot",
                    "0",
                    "--seed",
                    "1",
                    "--log-level",
                    "info",
                ),
                stdout=out,
                stderr=out,
            )
        try:
            first, query = _next(looks, log)
            assert first == LookRequest()
            view = np.array([[6.0, 0.0]])
            query.reply(
                query.key_expr, Snapshot(1, 2, "uniform-circle", {"a": 4.0}, view, epoch=5).encode()
            )
            query.drop()
            second, query = _next(looks, log)  # the agent moved and Looks again: held here
            held.append(query)
            assert (second.epoch, second.after) == (5, 1)
            assert MoveSubmitted.decode(second.move).round == 1
            _token = world.liveliness().declare_token(alive_key(swarm))
            third, query = _next(looks, log)
            held.append(query)
            # asked again, the move included (it goes with every Look until one is answered),
            # and because a world came up, not because the Look timed out (the agent says why)
            assert third == second, log.read_text(errors="replace")
            deadline = time.monotonic() + DEADLINE_S
            while "a world came up; asking again" not in log.read_text(errors="replace"):
                assert time.monotonic() < deadline, log.read_text(errors="replace")
                time.sleep(0.05)
        finally:
            for q in held:
                q.drop()
