"""The world process: owns the positions, serves snapshots, holds moves, commits rounds durably.

`WorldCore` is the state machine (bytes in, bytes out, no Zenoh); `serve` is the Zenoh shell: its
callbacks only enqueue, one thread owns the state. Physics and the end test are the core's
(`world.physics.apply_round`, `world.progress.ProgressTracker`); nothing of them lives here.
"""

from __future__ import annotations

import logging
import os
import queue
import threading
import time
from collections import Counter
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fatswarm.agent.path import Path, path_length, transform
from fatswarm.agent.protocol import MoveSubmitted, alive_any_key, move_any_key, robot_of_alive_key
from fatswarm.agent.tolerance import snap
from fatswarm.world.physics import Collision, RoundOutcome, apply_round
from fatswarm.world.progress import ProgressTracker
from fatswarm.world.protocol import (
    AgentInfo,
    Begin,
    Commit,
    ControlReply,
    Hello,
    MoveHeld,
    Points,
    ProtocolError,
    Snapshot,
    WorldState,
    alive_key,
    control_key,
    decode_control,
    moves_held_key,
    robot_of_key,
    snapshot_any_key,
    state_key,
)
from fatswarm.world.record import Header, RecordWriter, RoundEntry, RunRecord, read_record

log = logging.getLogger("fatswarm.world")

REPUBLISH_S = 1.0  # the state is re-published this often when nothing happens, for late observers

@dataclass(frozen=True, slots=True)
class WorldSetup:
    """What a run starts from (or what the state file's header says when resuming)."""

    swarm: str
    n: int
    a: float
    seed: int
    scheduler: str
    initial: Points  # (n, 2)
    max_rounds: int | None


# --- the durable log: the run record itself, fsynced line by line ----------------------------


def cut_torn_line(path: str) -> None:
    """Drop a torn last line (the world died mid-write): it was never committed nor announced."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.rfind(b"\n") + 1
    if end < len(data):
        log.warning("state file %s: dropping a torn last line of %d bytes", path, len(data) - end)
        with open(path, "r+b") as f:
            f.truncate(end)
            f.flush()
            os.fsync(f.fileno())


def setup_from_header(header: Header, swarm: str, max_rounds: int | None) -> WorldSetup:
    """The run described by a state file's header line."""
    saved = header.extra.get("max_rounds", max_rounds)
    return WorldSetup(
        swarm=swarm,
        n=header.n,
        a=header.a,
        seed=int(header.seed or 0),
        scheduler=header.scheduler,
        initial=np.asarray(header.initial, dtype=np.float64),
        max_rounds=int(saved) if isinstance(saved, int) else max_rounds,
    )


# --- the state machine ------------------------------------------------------------------------


class WorldCore:
    """The world's state and its answers to looks, moves and control requests (no I/O but the log).

    Robot identity comes from the key a message arrives on and must match the robot it names; a
    move counts only for the open round, from an active robot that has looked, once.
    """

    def __init__(
        self, setup: WorldSetup, journal: RecordWriter, history: RunRecord | None = None
    ) -> None:
        self.setup = setup
        self.journal = journal
        n = setup.n
        # On the grid, so that every robot's view is exact (agent/tolerance.py); a start that came
        # through validate_configuration is there already.
        self.positions: Points = snap(np.array(setup.initial, dtype=np.float64).reshape(n, 2))
        self.tracker = ProgressTracker(n, setup.a, setup.max_rounds)
        self.status = "running"
        self.committed = 0
        self.open_round = 0
        self.active: tuple[int, ...] = ()
        self.looked: set[int] = set()
        self.held: dict[int, Path] = {}
        self.moved: tuple[int, ...] = ()
        self.stopped: tuple[int, ...] = ()
        self.collisions_total = 0
        self.alive = [False] * n
        self.last_active = [-1] * n
        self.last_length = [0.0] * n
        self.timeouts = [0] * n
        self.rejected: Counter[str] = Counter()
        self._agents: tuple[AgentInfo, ...] | None = None  # cache of state().agents
        self._rng = np.random.default_rng([0x5A0F, setup.seed & 0xFFFFFFFF])
        if history is None:
            self.journal.header(
                n, setup.a, setup.seed, setup.scheduler, self.positions,
                max_rounds=setup.max_rounds, swarm=setup.swarm,
            )
        else:
            self._replay(history)

    # -- resume ---------------------------------------------------------------------------------

    def _replay(self, record: RunRecord) -> None:
        """Rebuild the state from the committed rounds of a state file."""
        for entry in record.rounds:
            self._replay_round(entry)
        if record.result is not None:
            self.status = record.result.status
        elif self.tracker.status is not None:
            self._finish()  # died between the last round line and the result line
        log.info("resumed %s after round %d (%s)", self.journal.path, self.committed, self.status)

    def _replay_round(self, entry: RoundEntry) -> None:
        before = self.positions
        after = np.asarray(entry.positions, dtype=np.float64)
        timed_out = {int(r) for r in entry.extra.get("timed_out", [])}
        traveled = {m.robot: m.traveled for m in entry.moves}
        paths = {m.robot: m.path for m in entry.moves}
        self._account(entry.round, entry.active, paths, timed_out, before, after, traveled,
                      entry.collisions)

    def _account(
        self,
        round_no: int,
        active: Sequence[int],
        paths: dict[int, Path],
        timed_out: Collection[int],
        before: Points,
        after: Points,
        traveled: dict[int, float],
        collisions: Sequence[Collision],
    ) -> None:
        """Book one committed round (live or replayed) into the state and the progress tracker."""
        self._agents = None
        for robot in active:
            self.last_active[robot] = round_no
        for robot in timed_out:
            self.timeouts[robot] += 1
        for robot, path in paths.items():
            self.last_length[robot] = path_length((float(before[robot, 0]),
                                                   float(before[robot, 1])), path)
        self.collisions_total += len(collisions)
        self.tracker.observe(
            [r for r in active if r not in timed_out], paths.keys(), before, after, traveled,
            len(collisions),
        )
        self.positions, self.committed = after, round_no
        self.active = tuple(active)
        self.moved = tuple(sorted(paths))
        self.stopped = tuple(sorted({c.robot for c in collisions}))

    # -- requests -------------------------------------------------------------------------------

    def reject(self, reason: str, detail: str) -> None:
        """Count and log a refused input (never raised, never applied)."""
        self.rejected[reason] += 1
        log.warning("rejected (%s): %s [total %d]", reason, detail, self.rejected[reason])

    def look(self, key: str) -> bytes | None:
        """The snapshot for the robot of `key`, or None (refused) if it is not active now."""
        robot = robot_of_key(key)
        if robot is None or robot >= self.setup.n:
            self.reject("look-bad-key", key)
            return None
        if not self.open_round or robot not in self.active:
            self.reject("look-not-active", f"robot {robot} round {self.open_round}")
            return None
        self.looked.add(robot)
        pos = self.positions
        others = np.concatenate((pos[:robot], pos[robot + 1 :])) - pos[robot]
        others = others[self._rng.permutation(len(others))]  # 10x faster than shuffle(axis=0)
        snap = Snapshot(round=self.open_round, n=self.setup.n, a=self.setup.a, view=others)
        return snap.encode()

    def move(self, key: str, payload: bytes) -> MoveHeld | None:
        """Hold a move for the open round; returns the notice to publish, None if refused."""
        robot = robot_of_key(key)
        try:
            msg = MoveSubmitted.decode(payload)
        except ProtocolError as exc:
            self.reject("move-garbage", f"on {key}: {exc}")
            return None
        if robot != msg.robot:
            self.reject("move-wrong-robot", f"robot {msg.robot} on {key}")
        elif msg.round != self.open_round:
            self.reject("move-wrong-round", f"robot {robot} round {msg.round} != {self.open_round}")
        elif robot not in self.active:
            self.reject("move-not-active", f"robot {robot} round {msg.round}")
        elif robot not in self.looked:
            self.reject("move-without-look", f"robot {robot} round {msg.round}")
        elif robot in self.held:
            self.reject("move-duplicate", f"robot {robot} round {msg.round}")
        else:
            self.held[robot] = msg.path
            return MoveHeld(round=msg.round, robot=robot)
        return None

    def control(self, payload: bytes) -> tuple[ControlReply, bool]:
        """Answer a coordinator request; the flag says whether the state changed (publish it)."""
        try:
            req = decode_control(payload)
        except ProtocolError as exc:
            self.reject("control-garbage", str(exc))
            return self.reply(False, f"bad request: {exc}"), False
        if isinstance(req, Hello):
            return self.reply(True), False
        if self.status != "running":
            return self.reply(False, f"the run has ended ({self.status})"), False
        if isinstance(req, Begin):
            return self._begin(req)
        return self._commit(req)

    def reply(self, ok: bool, reason: str = "") -> ControlReply:
        return ControlReply(
            ok=ok,
            reason=reason,
            n=self.setup.n,
            committed=self.committed,
            open_round=self.open_round,
            status=self.status,
        )

    def _begin(self, req: Begin) -> tuple[ControlReply, bool]:
        if req.round != self.committed + 1:
            return self.reply(False, f"next round is {self.committed + 1}, not {req.round}"), False
        if not req.active or req.active[-1] >= self.setup.n:
            return self.reply(False, "active set empty or not robots of this run"), False
        if self.open_round == req.round and self.active == req.active:
            return self.reply(True), False  # a coordinator retrying: keep what is held
        self.open_round, self.active = req.round, req.active
        self.looked, self.held = set(), {}
        return self.reply(True), True

    def _commit(self, req: Commit) -> tuple[ControlReply, bool]:
        if req.round == self.committed and not self.open_round:
            return self.reply(True), False  # the reply to a commit was lost: it is durable
        if req.round != self.open_round:
            return self.reply(False, f"round {req.round} is not open"), False
        self.commit_open_round()
        return self.reply(True), True

    def commit_open_round(self) -> None:
        """Apply the held moves through physics, log the round durably, then update the state."""
        round_no, before = self.open_round, self.positions
        paths = {  # the lockstep runner applies and records non-empty paths only: so do we
            robot: transform(path, (float(before[robot, 0]), float(before[robot, 1])), False)
            for robot, path in sorted(self.held.items())
            if path
        }
        outcome = apply_round(before, paths) if paths else RoundOutcome(before.copy())
        after = np.asarray(outcome.positions, dtype=np.float64)
        traveled = {r: float(outcome.traveled.get(r, 0.0)) for r in paths}
        timed_out = [r for r in self.active if r not in self.held]
        extra = {"timed_out": timed_out} if timed_out else {}
        self.journal.round(
            round_no,
            self.active,
            {r: (p, traveled[r]) for r, p in paths.items()},
            after,
            outcome.collisions,
            **extra,
        )
        self._account(round_no, self.active, paths, timed_out, before, after, traveled,
                      outcome.collisions)
        self.open_round, self.looked, self.held = 0, set(), {}
        if self.tracker.status is not None:
            self._finish()

    def _finish(self) -> None:
        progress = self.tracker.snapshot()
        status = progress.status or "stalled"
        self.journal.result(
            status,
            progress.rounds,
            self.positions,
            epochs=progress.epochs,
            moves=progress.moves,
            total_distance=progress.total_distance,
            collisions=progress.collisions,
        )
        self.status = status

    def set_alive(self, robot: int, alive: bool) -> bool:
        """Note an agent's liveliness; True if it changed."""
        if not 0 <= robot < self.setup.n or self.alive[robot] == alive:
            return False
        self.alive[robot] = alive
        self._agents = None
        return True

    def state(self) -> WorldState:
        """The observers' view of the world now."""
        n = self.setup.n
        return WorldState(
            round=self.committed,
            n=n,
            a=self.setup.a,
            seed=self.setup.seed,
            scheduler=self.setup.scheduler,
            swarm=self.setup.swarm,
            positions=self.positions,
            active=self.active,
            moved=self.moved,
            stopped=self.stopped,
            collisions_total=self.collisions_total,
            status=self.status,
            agents=self._agent_infos(),
        )

    def _agent_infos(self) -> tuple[AgentInfo, ...]:
        """Per-robot agent info, rebuilt only after it changed (it is published twice a round)."""
        if self._agents is None:
            self._agents = tuple(
                AgentInfo(self.alive[i], self.last_active[i], self.last_length[i], self.timeouts[i])
                for i in range(self.setup.n)
            )
        return self._agents


def open_world(
    state_path: str,
    make_setup: Callable[[], WorldSetup],
    swarm: str,
    max_rounds: int | None,
    fsync: bool = True,
) -> WorldCore:
    """Resume from `state_path` if it holds a record, else start a new one from `make_setup()`.

    Raises RecordFormatError (a file that is not a run record) or what `make_setup` raises.
    """
    if os.path.exists(state_path) and os.path.getsize(state_path) > 0:
        cut_torn_line(state_path)
        record = read_record(state_path)
        setup = setup_from_header(record.header, swarm, max_rounds)
        return WorldCore(setup, RecordWriter(state_path, fsync=fsync, append=True), record)
    return WorldCore(make_setup(), RecordWriter(state_path, fsync=fsync))


# --- the Zenoh shell --------------------------------------------------------------------------


def serve(core: WorldCore, session: Any, stop: threading.Event | None = None) -> int:
    """Run the world on an open Zenoh session until `stop` is set, then close it; returns 0.

    The caller opens the session (`deploy.zconf.open_client`: a deadline, one-line errors).
    """
    import zenoh

    stop = stop or threading.Event()
    events: queue.Queue[tuple[str, Any]] = queue.Queue()
    swarm = core.setup.swarm

    def on_alive(sample: zenoh.Sample) -> None:
        events.put(("alive", (str(sample.key_expr), sample.kind == zenoh.SampleKind.PUT)))

    def on_move(sample: zenoh.Sample) -> None:
        events.put(("move", (str(sample.key_expr), sample.payload.to_bytes())))

    with session:
        state_pub = session.declare_publisher(
            state_key(swarm), congestion_control=zenoh.CongestionControl.DROP
        )
        held_pub = session.declare_publisher(
            moves_held_key(swarm), congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )
        session.declare_queryable(snapshot_any_key(swarm), lambda q: events.put(("look", q)))
        session.declare_queryable(control_key(swarm), lambda q: events.put(("control", q)))
        session.declare_subscriber(move_any_key(swarm), on_move)
        session.liveliness().declare_subscriber(alive_any_key(swarm), on_alive, history=True)
        _token = session.liveliness().declare_token(alive_key(swarm))
        log.info("world of %d robots serving swarm %r", core.setup.n, swarm)
        state_pub.put(core.state().encode())
        dirty, published = False, time.monotonic()
        while not stop.is_set():
            try:
                kind, item = events.get(timeout=0.2)
            except queue.Empty:
                if dirty or time.monotonic() - published > REPUBLISH_S:  # late joiners see it
                    state_pub.put(core.state().encode())
                    dirty, published = False, time.monotonic()
                continue
            try:
                if _handle(core, kind, item, held_pub):
                    state_pub.put(core.state().encode())
                    published = time.monotonic()
                elif kind == "alive":
                    dirty = True
            except zenoh.ZError as exc:  # e.g. the asker left before its reply: not our problem
                log.warning("zenoh refused a %s reply or notice: %s", kind, exc)
    core.journal.close()
    log.info("world stopped at round %d (%s)", core.committed, core.status)
    return 0


def _handle(core: WorldCore, kind: str, item: Any, held_pub: Any) -> bool:
    """Apply one event; True when the observers' state changed enough to publish at once."""
    if kind == "look":
        _answer_look(core, item)
    elif kind == "move":
        notice = core.move(*item)
        if notice is not None:
            held_pub.put(notice.encode())
    elif kind == "control":
        return _answer_control(core, item)
    elif kind == "alive":
        key, alive = item
        robot = robot_of_alive_key(key)
        if robot is not None:
            core.set_alive(robot, alive)
    return False


def _answer_look(core: WorldCore, query: Any) -> None:
    try:
        data = core.look(str(query.key_expr))
        if data is None:
            query.reply_err(b"not active in the open round")
        else:
            query.reply(query.key_expr, data)
    finally:
        query.drop()


def _answer_control(core: WorldCore, query: Any) -> bool:
    try:
        payload = query.payload.to_bytes() if query.payload is not None else b""
        reply, changed = core.control(payload)
        query.reply(query.key_expr, reply.encode())
        return changed
    finally:
        query.drop()
