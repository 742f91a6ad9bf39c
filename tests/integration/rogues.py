"""Rogue clients: a part of the swarm (its own certificate) trying what only another part may do.

Each try is a real, well-formed message, so that a router that let it through would change the
run: a move for another robot, Begin/Commit as the coordinator, another robot's snapshot, a fake
agent liveliness token, a fake world answering snapshots and control (with a ControlReply saying
"formed"), fake MovesHeld notices. `Rogue` counts everything that came back; with the access
control of `fatswarm secure` every count stays 0.

Also a script, for a rogue on another host (a network namespace):
`python rogues.py --config FILE --connect EP --swarm S -n N --victim V --report PATH`
tries everything every 50 ms until SIGTERM, prints "armed" once armed, and writes its counts.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Line, Path
from fatswarm.world.protocol import (
    Begin,
    Commit,
    ControlReply,
    Hello,
    MovesHeld,
    MoveSubmitted,
    Snapshot,
    agent_alive_key,
    control_key,
    move_key,
    moves_held_key,
    snapshot_any_key,
    snapshot_key,
    state_key,
)

TRY_TIMEOUT_S = 1.0


@dataclass
class Seen:
    """What came back to a rogue: all zero when every try was refused."""

    control_replies: int = 0  # replies to its Hello/Begin/Commit
    snapshot_replies: int = 0  # replies to its get of the victim's snapshot
    snapshot_queries: int = 0  # queries its fake world's snapshot queryable received
    control_queries: int = 0  # queries its fake world's control queryable received
    samples: int = 0  # moves, notices... it received by subscribing where it may not
    state_samples: int = 0  # world states it received (a dashboard's job, no other part's)
    tries: int = 0  # rounds of tries made


class Rogue:
    """One rogue: `session` armed with fake queryables, tokens and subscribers, `striker` (another
    session of the same identity) sending and asking, so that nothing it sends reaches its own
    fakes inside one session: whatever they count came through the router."""

    def __init__(self, session: Any, striker: Any, swarm: str, n: int, victim: int) -> None:
        self.session, self.striker = session, striker
        self.swarm, self.n, self.victim = swarm, n, victim
        self.seen = Seen()
        self._lock = threading.Lock()
        self._keep: list[Any] = []

    def _count(self, field: str) -> None:
        with self._lock:
            setattr(self.seen, field, getattr(self.seen, field) + 1)

    def arm(self) -> None:
        """Declare the fake world (snapshots, control), fake agent tokens and eavesdroppers."""
        s, swarm = self.session, self.swarm

        def fake_snapshot(query: Any) -> None:
            self._count("snapshot_queries")
            view = np.zeros((self.n - 1, 2))
            view[:, 0] = np.arange(1, self.n) * 3.0  # far from anything real
            with query:
                query.reply(
                    query.key_expr,
                    Snapshot(
                        round=1, n=self.n, algorithm="uniform-circle", params={"a": 4.0}, view=view
                    ).encode(),
                )

        def fake_control(query: Any) -> None:
            self._count("control_queries")
            with query:
                query.reply(
                    query.key_expr,
                    ControlReply(
                        ok=True,
                        reason="",
                        n=self.n,
                        committed=1,
                        open_round=0,
                        status=Status.FORMED,
                    ).encode(),
                )

        self._keep += [
            s.declare_queryable(snapshot_any_key(swarm), fake_snapshot),
            s.declare_queryable(snapshot_key(swarm, self.victim), fake_snapshot),
            s.declare_queryable(control_key(swarm), fake_control),
            # a token for the victim, and one for a robot the run does not have
            s.liveliness().declare_token(agent_alive_key(swarm, self.victim)),
            s.liveliness().declare_token(agent_alive_key(swarm, self.n + 1)),
        ]

        def heard(sample: Any) -> None:
            state = str(sample.key_expr) == state_key(swarm)
            self._count("state_samples" if state else "samples")

        for key in (
            f"fatswarm/{swarm}/robot/*/move",
            moves_held_key(swarm),
            f"fatswarm/{swarm}/**",
        ):  # one sample counts once per subscriber it reaches
            self._keep.append(s.declare_subscriber(key, heard))

    def strike(self, round_no: int) -> None:
        """One of each try, for round `round_no` (none waits longer than TRY_TIMEOUT_S)."""
        s, swarm = self.striker, self.swarm
        far = Path((Line((0.0, 25.0)),))
        s.put(
            move_key(swarm, self.victim),
            MoveSubmitted(robot=self.victim, round=round_no, path=far).encode(),
        )
        s.put(moves_held_key(swarm), MovesHeld(round=round_no, robots=(self.victim,)).encode())
        s.put(state_key(swarm), b"not a state")
        for request in (Hello(), Begin(round_no, (self.victim,)), Commit(round_no)):
            for reply in s.get(control_key(swarm), payload=request.encode(), timeout=TRY_TIMEOUT_S):
                if reply.ok is not None:
                    self._count("control_replies")
        for reply in s.get(snapshot_key(swarm, self.victim), timeout=TRY_TIMEOUT_S):
            if reply.ok is not None:
                self._count("snapshot_replies")
        self._count("tries")

    def report(self) -> dict[str, int]:
        with self._lock:
            return asdict(self.seen)


def main(argv: list[str] | None = None) -> int:
    """The rogue as a process: try everything until SIGTERM, then write what came back."""
    import zenoh

    from fatswarm.deploy.net.zconf import make_config

    p = argparse.ArgumentParser()
    p.add_argument("--config", required=True)
    p.add_argument("--connect", required=True)
    p.add_argument("--swarm", required=True)
    p.add_argument("-n", type=int, required=True)
    p.add_argument("--victim", type=int, required=True)
    p.add_argument("--report", required=True)
    args = p.parse_args(argv)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    conf = make_config("client", [args.connect], config_file=args.config, shared_memory=False)
    sessions: list[Any] = []
    while len(sessions) < 2 and not stop.is_set():
        try:
            sessions.append(zenoh.open(conf))
        except zenoh.ZError:
            stop.wait(0.2)
    if len(sessions) < 2:
        return 1
    session, striker = sessions
    with session, striker:
        rogue = Rogue(session, striker, args.swarm, args.n, args.victim)
        rogue.arm()
        round_no = 1
        rogue.strike(round_no)
        print("armed", flush=True)
        while not stop.wait(0.05):
            round_no = round_no % 200 + 1
            rogue.strike(round_no)
        with open(args.report, "w", encoding="utf-8") as f:
            json.dump(rogue.report(), f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
