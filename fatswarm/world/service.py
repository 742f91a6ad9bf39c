"""The world process: the Zenoh shell around `world.core.WorldCore`.

Its callbacks only enqueue; one thread decodes each event, hands it to the core and sends what the
core answers. Nothing of the round's logic lives here. A Look the core cannot answer yet is held
(the newest per robot) and answered when the robot is activated: that answer is its activation.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import dataclasses
import functools
import logging
import queue
import threading
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

import zenoh

from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.seam import AlgorithmFailure
from fatswarm.domain.wire import ProtocolError, robot_of_key
from fatswarm.world.core import WorldCore
from fatswarm.world.effects import Rejected
from fatswarm.world.inbox import Inbox
from fatswarm.world.instants import is_async
from fatswarm.world.journal import Journal, perform
from fatswarm.world.observers import WorldState
from fatswarm.world.protocol import (
    MAX_CONTROL_BYTES,
    MAX_LOOK_BYTES,
    MAX_MOVE_BYTES,
    ControlReply,
    LookRequest,
    MoveSubmitted,
    agent_alive_any_key,
    alive_key,
    control_key,
    decode_control,
    move_any_key,
    moves_held_key,
    robot_of_alive_key,
    snapshot_any_key,
    state_key,
)
from fatswarm.world.record import Header, RecordWriteError, Result, RoundEntry
from fatswarm.world.rejections import Rejections, tally

__all__ = [
    "REPUBLISH_S",
    "control_bytes",
    "look_bytes",
    "move_bytes",
    "observed_state",
    "serve",
]

log = logging.getLogger("fatswarm.world")

REPUBLISH_S = 1.0  # the state is re-published this often when nothing happens, for late observers
HOLD_LOOK_S = 20.0  # a held Look is let go (answered with nothing) after this, if its agent has
# not asked again first (it does after agent.service.LOOK_WAIT_S): Looks of agents that are gone
TWO_SESSIONS_S = 1.0  # a robot's agent asks again after agent.service.LOOK_WAIT_S (3 s), or at
# once after a Look that failed: two Looks of one robot this close, twice running, come from two
# sessions acting for its key


def inbox_caps(n: int) -> dict[str, int]:
    """How many events of each kind the world's inbox holds for a run of `n` robots: far above a
    round's (a Look per robot, a control request at a time; moves ride in Looks), so that only a
    flood is cut, and far below what would grow the process for good (measured, n = 4: 50,000
    rogue Looks queued up to 16,384 queries and grew the world from 58 to 171 MB; with 32 Looks
    at most, to 65 MB). Tokens coming and going are never capped but by the inbox's bound."""
    return {"look": 2 * n + 32, "move": n + 32, "control": 32}


# --- the Zenoh shell --------------------------------------------------------------------------


def serve(
    core: WorldCore, journal: Journal, session: Any, stop: threading.Event | None = None
) -> int:
    """Run the world on an open Zenoh session until `stop` is set, then close it and `journal`
    (the run record the core's lines go to); returns 0, 4 when the record cannot be written, or 1
    when the algorithm's goal raised (the world cannot decide the run any more).

    The caller opens the session (`deploy.zconf.open_client`: a deadline, one-line errors).
    """
    shell = _Shell(core, journal)
    with session:
        _token = shell.declare(session)
        code = shell.run(stop or threading.Event())
    try:
        journal.close()
    except RecordWriteError as exc:
        if code != ExitCode.RECORD_FAILED:  # (else said already, as the world stopped)
            log.error("%s", exc)
        code = ExitCode.RECORD_FAILED
    log.info("world stopped at round %d (%s)", core.readout.committed, core.readout.status)
    return code


class _Shell:
    """The world's Zenoh shell: callbacks only enqueue; one loop hands each event to the core,
    performs what it asks (the record first), answers, and publishes the state."""

    def __init__(self, core: WorldCore, journal: Journal) -> None:
        self.core, self.journal = core, _Counted(journal, core.readout.progress().rounds)
        self.events: Inbox[tuple[str, Any]] = Inbox(caps=inbox_caps(core.readout.setup.n))
        self.looks = HeldLooks()
        self.refusals = Rejections()  # what was refused or dropped, said at most every few s
        self._tidied_at = 0  # refusals counted when the memory was last given back
        self.state_pub: Any = None
        self.held_pub: Any = None

    def declare(self, session: Any) -> Any:
        """Publishers, queryables, subscribers and the world's liveliness token (returned: it
        lives as long as the caller holds it)."""
        swarm = self.core.readout.setup.swarm
        self.state_pub = session.declare_publisher(
            state_key(swarm), congestion_control=zenoh.CongestionControl.DROP
        )
        self.held_pub = session.declare_publisher(
            moves_held_key(swarm), congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )
        session.declare_queryable(snapshot_any_key(swarm), self._on_query("look", MAX_LOOK_BYTES))
        session.declare_queryable(control_key(swarm), self._on_query("control", MAX_CONTROL_BYTES))
        session.declare_subscriber(move_any_key(swarm), self._on_move)
        session.liveliness().declare_subscriber(
            agent_alive_any_key(swarm), self._on_alive, history=True
        )
        return session.liveliness().declare_token(alive_key(swarm))

    def _on_alive(self, sample: Any) -> None:
        alive = sample.kind == zenoh.SampleKind.PUT
        self.events.offer("alive", ("alive", (str(sample.key_expr), alive)))

    def _on_move(self, sample: Any) -> None:
        size = len(sample.payload)
        if size > MAX_MOVE_BYTES:
            self.events.too_big("move")
            return
        self.events.offer("move", ("move", (str(sample.key_expr), sample.payload.to_bytes())), size)

    def _on_query(self, kind: str, limit: int) -> Callable[[Any], None]:
        def take(query: Any) -> None:
            size = len(query.payload) if query.payload is not None else 0
            if size > limit:
                self.events.too_big(kind)
                query.drop()  # answered at once (with nothing): the asker does not wait
            elif not self.events.offer(kind, (kind, query), size):
                query.drop()

        return take

    def _publish(self) -> float:
        """Publish the observers' state (and do what making it asked); when it was published."""
        self.state_pub.put(observed_state(self.core, self.refusals.totals).encode())
        perform(self.core.take_effects(), self.journal, self.refused)
        return time.monotonic()

    def refused(self, effect: Rejected) -> None:
        """Count what the core refused; say it if its kind is due (`world.rejections`)."""
        self.refuse(effect.reason, effect.detail)

    def refuse(self, kind: str, detail: str, times: int = 1) -> None:
        line = self.refusals.count(kind, detail, time.monotonic(), times)
        if line is not None:
            log.warning("%s", line)

    def _said_dropped(self, said: Counter[str]) -> None:
        """Count what the inbox dropped since `said` (updated) with the refusals."""
        fresh = self.events.dropped - said
        said.update(fresh)
        for kind, times in sorted(fresh.items()):
            self.refuse(f"{kind}-dropped", "too big, or more than the inbox holds", times)

    def _say_due(self, now: float, *, last: bool = False) -> None:
        """Say the kinds counted since they were last said, if due (`last`: all, and the
        totals)."""
        for line in self.refusals.flush(now) if last else self.refusals.due(now):
            log.warning("%s", line)
        if last and self.refusals.totals:
            totals = self.refusals.totals
            log.warning(
                "refused or dropped %s messages in all: %s",
                f"{sum(totals.values()):,}",
                tally(totals),
            )

    def _tidy(self) -> float:
        """Say the refusals due, and give back the memory a flood left (if one came since this
        was last done); now."""
        now = time.monotonic()
        self._say_due(now)
        total = sum(self.refusals.totals.values())
        if total != self._tidied_at:
            self._tidied_at = total
            give_back_memory()
        return now

    def run(self, stop: threading.Event) -> ExitCode:
        """Serve until `stop` is set or the world cannot go on; the exit code."""
        core, events, looks = self.core, self.events, self.looks
        setup = core.readout.setup
        log.info("world of %d robots serving swarm %r", setup.n, setup.swarm)
        published, dirty = self._publish(), False
        said: Counter[str] = Counter()  # the inbox's drops counted so far
        due_at = time.monotonic()  # when the refusals' lines were last looked at
        code = ExitCode.OK
        while not stop.is_set():
            try:
                kind, item = events.get(timeout=0.2)
            except queue.Empty:
                if dirty or time.monotonic() - published > REPUBLISH_S:  # late joiners see it
                    published, dirty = self._publish(), False
                looks.expire(time.monotonic())
                if time.monotonic() - due_at > self.refusals.every_s:  # the tail of a flood
                    due_at = self._tidy()
                continue
            now = time.monotonic()
            if now - looks.expired_at > HOLD_LOOK_S / 4:  # also when never idle
                looks.expire(now)
            if events.dropped != said:  # a flood: counted, said at most every few seconds
                self._said_dropped(said)
            if now - due_at > self.refusals.every_s:  # also when never idle
                due_at = self._tidy()
            outcome = self._step(kind, item)
            if isinstance(outcome, ExitCode):
                code = outcome
                break
            if outcome:
                published = time.monotonic()
            elif kind == "alive":
                dirty = True
        looks.let_go_all()
        self._said_dropped(said)
        self._say_due(time.monotonic(), last=True)
        return code

    def _step(self, kind: str, item: Any) -> bool | ExitCode:
        """One event: whether to publish the state at once, or the exit code if the world stops."""
        core, readout = self.core, self.core.readout
        try:
            publish = _handle(
                core, self.journal, kind, item, self.held_pub, self.looks, self.refused
            )
            if publish:
                self.state_pub.put(observed_state(core, self.refusals.totals).encode())
            perform(core.take_effects(), self.journal, self.refused)
            return publish
        except zenoh.ZError as exc:  # e.g. the asker left before its reply: not our problem
            log.warning("zenoh refused a %s reply or notice: %s", kind, exc)
            return False
        except RecordWriteError as exc:  # what is in the record stays; resume goes on from it
            log.error(
                "%s; the world stops after %s %d, the last its record holds (resume it once this "
                "is fixed)",
                exc,
                "cycle" if is_async(readout.setup) else "round",
                self.journal.rounds,
            )
            return ExitCode.RECORD_FAILED
        except AlgorithmFailure as exc:  # its round is durable; nobody can say what next
            with contextlib.suppress(RecordWriteError):  # said on its own when closing
                perform(core.take_effects(), self.journal, self.refused)
            log.error(
                "%s; the world stops at round %d (in its record)",
                exc,
                readout.open_round or readout.committed,
            )
            return ExitCode.NOT_FORMED


def give_back_memory() -> None:
    """Hand the memory freed after a flood back to the system (glibc's `malloc_trim`; nothing
    elsewhere): what Zenoh's threads allocated for a flood's messages stays in their malloc
    arenas otherwise (measured: 50,000 garbage Looks left the world 10 MB larger for good)."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


@functools.cache
def _malloc_trim() -> Any:
    """glibc's malloc_trim, or None (another C library)."""
    name = ctypes.util.find_library("c")
    try:
        return getattr(ctypes.CDLL(name), "malloc_trim", None) if name else None
    except OSError:
        return None


class _Counted:
    """The world's journal, counting the round lines (ended cycles, async) its record holds: where
    a resume goes on from, which the world names when the record cannot be written."""

    def __init__(self, journal: Journal, rounds: int) -> None:
        self.journal, self.rounds = journal, rounds

    def append(self, line: Header | RoundEntry | Result) -> None:
        self.journal.append(line)
        if isinstance(line, RoundEntry):
            self.rounds += 1

    def close(self) -> None:
        self.journal.close()


def observed_state(core: WorldCore, refused: Counter[str] | None = None) -> WorldState:
    """The state observers are shown: the core's, its `round` counting what the record counts,
    with the counts of what the world refused or dropped (`refused`, if any).
    An async run's record counts ended cycles, and the coordinator's instants are not rounds: its
    state says how many cycles have ended, as its progress lines and its summary do."""
    state = core.state()
    if is_async(core.readout.setup):
        state = dataclasses.replace(state, round=core.readout.progress().rounds)
    if refused:
        state = dataclasses.replace(state, refused=dict(refused))
    return state


def look_bytes(core: WorldCore, key: str) -> bytes | None:
    """The encoded snapshot for a look on `key`, or None (refused, counted)."""
    robot = robot_of_key(key)
    if robot is None:
        core.reject("look-bad-key", key)
        return None
    snapshot = core.look(robot)
    return None if snapshot is None else snapshot.encode()


def move_bytes(core: WorldCore, key: str, payload: bytes) -> bool:
    """Decode a move that came on `key` and hand it to the core; False if refused (counted)."""
    try:
        msg = MoveSubmitted.decode(payload)
    except ProtocolError as exc:
        core.reject("move-garbage", f"on {key}: {exc}")
        return False
    return core.move(robot_of_key(key), msg)


def control_bytes(core: WorldCore, payload: bytes) -> tuple[ControlReply, bool]:
    """Decode a control request and answer it; the flag says whether the state changed."""
    try:
        request = decode_control(payload)
    except ProtocolError as exc:
        core.reject("control-garbage", str(exc))
        return core.reply(False, f"bad request: {exc}"), False
    return core.control(request)


class HeldLooks:
    """Looks waiting for their robot's activation: the newest query per robot, and when it came;
    and what the robots' Looks carried before (at most one entry per robot of the run).

    A query is always finalised: answered, let go when a newer one replaces it (an agent asks
    again every agent.service.LOOK_WAIT_S), or let go after HOLD_LOOK_S.
    """

    def __init__(self) -> None:
        self._held: dict[int, tuple[Any, LookRequest, float]] = {}
        self.expired_at = 0.0  # when `expire` last ran
        self.taken: dict[int, tuple[int, bytes]] = {}  # robot -> (round, move) last taken from
        # its Looks: the agent sends it again until a Look is answered, and a repeat is no news
        self._close_calls: dict[int, int] = {}  # robot -> its Looks replaced in quick succession
        self.shared: set[int] = set()  # robots whose key two sessions were seen acting for

    def __len__(self) -> int:
        return len(self._held)

    def hold(self, robot: int, query: Any, request: LookRequest, now: float) -> bool:
        """Hold `query` for `robot`, letting go the one held before; True the first time the
        robot's Looks show two sessions acting for its key (a held Look replaced within
        TWO_SESSIONS_S, twice running: each session's agent asks again when it loses its Look)."""
        old = self._held.pop(robot, None)
        self._held[robot] = (query, request, now)
        if old is None:
            return False
        old[0].drop()
        close = now - old[2] < TWO_SESSIONS_S
        self._close_calls[robot] = self._close_calls.get(robot, 0) + 1 if close else 0
        if self._close_calls[robot] < 2 or robot in self.shared:
            return False
        self.shared.add(robot)
        return True

    def answer_ready(self, core: WorldCore) -> None:
        """Answer every held Look the core can answer now (its robot was just activated)."""
        for robot in [r for r, (_, req, _) in self._held.items() if core.may_look(r, req)]:
            self._close_calls.pop(robot, None)
            try:
                _answer_look(core, self._held.pop(robot)[0])
            except zenoh.ZError as exc:  # its agent left meanwhile: it asks again if it comes back
                log.debug("robot %d's held look: %s", robot, exc)

    def expire(self, now: float) -> None:
        self.expired_at = now
        for robot in [r for r, (_, _, since) in self._held.items() if now - since > HOLD_LOOK_S]:
            self._held.pop(robot)[0].drop()

    def let_go_all(self) -> None:
        for query, _, _ in self._held.values():
            query.drop()
        self._held.clear()


def _handle(
    core: WorldCore,
    journal: Journal,
    kind: str,
    item: Any,
    held_pub: Any,
    looks: HeldLooks,
    refused: Callable[[Rejected], None],
) -> bool:
    """Apply one event; True when the observers' state changed enough to publish at once."""
    if kind == "look":
        _take_look(core, item, looks, held_pub)
    elif kind == "move":
        if move_bytes(core, *item):
            _notify(core, held_pub)
    elif kind == "control":
        return _answer_control(core, journal, item, looks, refused)
    elif kind == "alive":
        key, alive = item
        robot = robot_of_alive_key(key)
        if robot is not None and core.set_alive(robot, alive):
            _notify(core, held_pub)  # a robot gone mid-round is not waited for
    return False


def _notify(core: WorldCore, held_pub: Any) -> None:
    notice = core.moves_notice()
    if notice is not None:
        held_pub.put(notice.encode())


def _take_look(core: WorldCore, query: Any, looks: HeldLooks, held_pub: Any) -> None:
    """Take the move a Look carries, then answer the Look now, hold it until its robot is
    activated, or refuse it (a key with no robot of this run, or garbage)."""
    key = str(query.key_expr)
    robot = robot_of_key(key)
    try:
        request = LookRequest.decode(
            query.payload.to_bytes() if query.payload is not None else LookRequest().encode()
        )
    except ProtocolError as exc:
        core.reject("look-garbage", str(exc))
        try:
            query.reply_err(b"not a look request")
        finally:
            query.drop()
        return
    if request.move:
        _take_carried_move(core, robot, key, request.move, held_pub, looks)
    if robot is None or not 0 <= robot < core.readout.setup.n or core.may_look(robot, request):
        _answer_look(core, query)
    elif looks.hold(robot, query, request, time.monotonic()):
        core.reject(
            "look-two-sessions",
            f"robot {robot}'s Looks come from two sessions at once (they take each other's "
            "place): its key is used twice, and the last move sent wins (said once a robot)",
        )


def _take_carried_move(
    core: WorldCore, robot: int | None, key: str, data: bytes, held_pub: Any, looks: HeldLooks
) -> None:
    """A move that a Look carries. The agent sends it again with every Look until one is answered
    (so that a Look lost with a router does not lose the move): a repeat of the move taken last
    from this robot's Looks is no news, dropped without a word. Any other move that is not for
    the open round is refused and counted: another move for a round it already moved in (a
    second session acting for its key), or a move that came after its round was committed
    (late, e.g. after the move timeout)."""
    try:
        msg = MoveSubmitted.decode(data)
    except ProtocolError as exc:
        core.reject("move-garbage", f"in a look on {key}: {exc}")
        return
    readout = core.readout
    if robot is None or not 0 <= robot < readout.setup.n:
        return  # the Look itself is refused (look-bad-key)
    if msg.round == readout.open_round and robot not in readout.held:
        if core.move(robot, msg):
            looks.taken[robot] = (msg.round, data)
            _notify(core, held_pub)
        return
    taken = looks.taken.get(robot)
    if taken == (msg.round, data):
        return
    if msg.round == readout.open_round:
        core.reject(
            "move-already-moved",
            f"robot {robot} round {msg.round}: another move than the one it sent",
        )
    elif msg.round > readout.committed:
        core.move(robot, msg)  # refused: not the open round (counted)
    elif taken is not None:  # (none: a repeat of the move a world before this one took)
        core.reject(
            "move-round-closed",
            f"robot {robot} round {msg.round}: its round was committed without it "
            f"(late: after the move timeout?), round {readout.committed} is the last",
        )


def _answer_look(core: WorldCore, query: Any) -> None:
    try:
        data = look_bytes(core, str(query.key_expr))
        if data is None:
            query.reply_err(b"not a robot of this run")
        else:
            query.reply(query.key_expr, data)
    finally:
        query.drop()


def _answer_control(
    core: WorldCore,
    journal: Journal,
    query: Any,
    looks: HeldLooks,
    refused: Callable[[Rejected], None],
) -> bool:
    """Answer a control request once what it committed is in the record (durable first)."""
    try:
        payload = query.payload.to_bytes() if query.payload is not None else b""
        reply, changed = control_bytes(core, payload)
        perform(core.take_effects(), journal, refused)
        if changed:
            looks.answer_ready(core)  # a round opened: its robots start computing first
        query.reply(query.key_expr, reply.encode())
        return changed
    finally:
        query.drop()
