"""The world process: the Zenoh shell around `world.core.WorldCore`.

Its callbacks only enqueue; one thread decodes each event, hands it to the core and sends what the
core answers. Nothing of the round's logic lives here.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

from fatswarm.agent.protocol import (
    MAX_MOVE_BYTES,
    MoveSubmitted,
    alive_any_key,
    move_any_key,
    robot_of_alive_key,
)
from fatswarm.agent.seam import AlgorithmFailure
from fatswarm.world.core import WorldCore, WorldSetup, open_world
from fatswarm.world.inbox import Inbox
from fatswarm.world.outcome import ExitCode
from fatswarm.world.protocol import (
    MAX_CONTROL_BYTES,
    ControlReply,
    MoveHeld,
    ProtocolError,
    alive_key,
    control_key,
    decode_control,
    moves_held_key,
    robot_of_key,
    snapshot_any_key,
    state_key,
)
from fatswarm.world.record import RecordWriteError

__all__ = [
    "REPUBLISH_S",
    "WorldCore",
    "WorldSetup",
    "control_bytes",
    "look_bytes",
    "move_bytes",
    "open_world",
    "serve",
]

log = logging.getLogger("fatswarm.world")

REPUBLISH_S = 1.0  # the state is re-published this often when nothing happens, for late observers
DROPPED_EVERY_S = 5.0  # dropped messages are counted in one log line at most this often

# --- the Zenoh shell --------------------------------------------------------------------------


def serve(core: WorldCore, session: Any, stop: threading.Event | None = None) -> int:
    """Run the world on an open Zenoh session until `stop` is set, then close it; returns 0, or 1
    when the algorithm's goal raised (the world cannot decide the run any more).

    The caller opens the session (`deploy.zconf.open_client`: a deadline, one-line errors).
    """
    import zenoh

    stop = stop or threading.Event()
    events: Inbox[tuple[str, Any]] = Inbox()
    swarm = core.setup.swarm

    def on_alive(sample: zenoh.Sample) -> None:
        alive = sample.kind == zenoh.SampleKind.PUT
        events.offer("alive", ("alive", (str(sample.key_expr), alive)))

    def on_move(sample: zenoh.Sample) -> None:
        size = len(sample.payload)
        if size > MAX_MOVE_BYTES:
            events.too_big("move")
            return
        events.offer("move", ("move", (str(sample.key_expr), sample.payload.to_bytes())), size)

    def on_query(kind: str, limit: int) -> Callable[[Any], None]:
        def take(query: Any) -> None:
            size = len(query.payload) if query.payload is not None else 0
            if size > limit:
                events.too_big(kind)
                query.drop()  # answered at once (with nothing): the asker does not wait
            elif not events.offer(kind, (kind, query), size):
                query.drop()

        return take

    with session:
        state_pub = session.declare_publisher(
            state_key(swarm), congestion_control=zenoh.CongestionControl.DROP
        )
        held_pub = session.declare_publisher(
            moves_held_key(swarm), congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )
        session.declare_queryable(snapshot_any_key(swarm), on_query("look", 0))
        session.declare_queryable(control_key(swarm), on_query("control", MAX_CONTROL_BYTES))
        session.declare_subscriber(move_any_key(swarm), on_move)
        session.liveliness().declare_subscriber(alive_any_key(swarm), on_alive, history=True)
        _token = session.liveliness().declare_token(alive_key(swarm))
        log.info("world of %d robots serving swarm %r", core.setup.n, swarm)
        state_pub.put(core.state().encode())
        dirty, published = False, time.monotonic()
        code = ExitCode.OK
        said: Counter[str] = Counter()
        said_at = -DROPPED_EVERY_S
        while not stop.is_set():
            try:
                kind, item = events.get(timeout=0.2)
            except queue.Empty:
                if dirty or time.monotonic() - published > REPUBLISH_S:  # late joiners see it
                    state_pub.put(core.state().encode())
                    dirty, published = False, time.monotonic()
                continue
            if events.dropped != said:  # a flood: say so, at most every few seconds
                said_at = _say_dropped(events, said, said_at)
            try:
                if _handle(core, kind, item, held_pub):
                    state_pub.put(core.state().encode())
                    published = time.monotonic()
                elif kind == "alive":
                    dirty = True
            except zenoh.ZError as exc:  # e.g. the asker left before its reply: not our problem
                log.warning("zenoh refused a %s reply or notice: %s", kind, exc)
            except RecordWriteError as exc:  # what is in the record stays; resume goes on from it
                log.error("%s; the world stops at round %d (resume it once this is fixed)", exc,
                          core.open_round or core.committed)
                code = ExitCode.RECORD_FAILED
                break
            except AlgorithmFailure as exc:  # its round is durable; nobody can say what next
                log.error("%s; the world stops at round %d (in its record)", exc,
                          core.open_round or core.committed)
                code = ExitCode.NOT_FORMED
                break
    try:
        core.journal.close()
    except RecordWriteError as exc:
        log.error("%s", exc)
        code = ExitCode.RECORD_FAILED
    log.info("world stopped at round %d (%s)", core.committed, core.status)
    return code


def look_bytes(core: WorldCore, key: str) -> bytes | None:
    """The encoded snapshot for a look on `key`, or None (refused, counted)."""
    robot = robot_of_key(key)
    if robot is None:
        core.reject("look-bad-key", key)
        return None
    snapshot = core.look(robot)
    return None if snapshot is None else snapshot.encode()


def move_bytes(core: WorldCore, key: str, payload: bytes) -> MoveHeld | None:
    """Decode a move that came on `key` and hand it to the core; the notice, None if refused."""
    try:
        msg = MoveSubmitted.decode(payload)
    except ProtocolError as exc:
        core.reject("move-garbage", f"on {key}: {exc}")
        return None
    return core.move(robot_of_key(key), msg)


def control_bytes(core: WorldCore, payload: bytes) -> tuple[ControlReply, bool]:
    """Decode a control request and answer it; the flag says whether the state changed."""
    try:
        request = decode_control(payload)
    except ProtocolError as exc:
        core.reject("control-garbage", str(exc))
        return core.reply(False, f"bad request: {exc}"), False
    return core.control(request)


def _say_dropped(events: Inbox[Any], said: Counter[str], said_at: float) -> float:
    """Log how many messages were dropped (too big, or the inbox full) since it last said, at most
    every DROPPED_EVERY_S; when it last said."""
    now = time.monotonic()
    if now - said_at < DROPPED_EVERY_S:
        return said_at
    fresh = events.dropped - said
    log.warning("dropped %s messages (too big, or more than the inbox holds)",
                ", ".join(f"{k} {v}" for k, v in sorted(fresh.items())))
    said.update(fresh)
    return now


def _handle(core: WorldCore, kind: str, item: Any, held_pub: Any) -> bool:
    """Apply one event; True when the observers' state changed enough to publish at once."""
    if kind == "look":
        _answer_look(core, item)
    elif kind == "move":
        notice = move_bytes(core, *item)
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
        data = look_bytes(core, str(query.key_expr))
        if data is None:
            query.reply_err(b"not active in the open round")
        else:
            query.reply(query.key_expr, data)
    finally:
        query.drop()


def _answer_control(core: WorldCore, query: Any) -> bool:
    try:
        payload = query.payload.to_bytes() if query.payload is not None else b""
        reply, changed = control_bytes(core, payload)
        query.reply(query.key_expr, reply.encode())
        return changed
    finally:
        query.drop()
