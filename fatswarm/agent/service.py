"""The agent process: one robot. It Looks, Computes in its private frame, Moves, and Looks again.

Its Look is a query the world holds until the robot is activated: the answer is both the activation
and the snapshot, so a round reaches an agent in one message. Its Move rides in its next Look
(`LookRequest.move`, sent again with every Look until one is answered): the robot still sends its
own move, in one message a round instead of two.
The Look names the last round it moved in (and at which world process), all it keeps between
rounds besides its frame and that move until it is sent; compute stays a pure function of the
snapshot. It keeps only its identity and its frame (an X mirroring drawn at start-up, never
sent). The world sends the others' positions relative to this robot with world axes; the agent
mirrors them into its own frame, computes, mirrors the path back and sends it relative to itself,
so no global coordinate ever reaches it or leaves it.
"""

from __future__ import annotations

import json
import logging
import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from fatswarm.domain.lights import glance_of
from fatswarm.domain.path import Path, Points
from fatswarm.domain.registry import DEFAULT, load_algorithm
from fatswarm.domain.seam import (
    Algorithm,
    AlgorithmParamsError,
    Configured,
    failure_kind,
    failure_text,
)
from fatswarm.domain.wire import ProtocolError
from fatswarm.world.protocol import (
    LookRequest,
    MoveSubmitted,
    Snapshot,
    agent_alive_key,
    snapshot_key,
)
from fatswarm.world.protocol import alive_key as world_alive_key

log = logging.getLogger("fatswarm.agent")

LOOK_WAIT_S = 3.0  # a Look waits this long for its answer, then asks again (the world keeps the
# newest per robot): a query routed to a world that had just died is never answered, and must not
# keep its robot out of the rounds of the new world for longer than a move timeout (5 s)
RELOOK_S = 0.05  # after a Look that came back empty at once (no world yet), wait this long
OPEN_RETRY_S = 0.2  # a client cannot open a session before its router is up: retry
WAIT_NOTICE_S = 5.0  # meanwhile, say this often that the robot still waits for its router


@dataclass(frozen=True, slots=True)
class AgentConfig:
    """One robot's identity (its private frame is the world's: it draws none)."""

    swarm: str
    robot: int
    algorithm: str = DEFAULT  # a registered name or module:attribute (fatswarm/domain/registry.py)


class WrongAlgorithmError(ValueError):
    """The world runs another algorithm than this agent: it stays put rather than guess."""


class Robot:
    """One robot's Compute: the algorithm, configured by what each snapshot says (n and the
    parameters), kept while they do not change. Its frame is the world's secret: the view comes
    in it, and the path goes back in it."""

    def __init__(self, algorithm: Algorithm[Any]) -> None:
        self.algorithm = algorithm
        self._setting: Configured | None = None
        self.failure_kinds: set[str] = set()  # the kinds of failed compute said on the log

    def look_compute(self, snapshot: Snapshot) -> tuple[Path, int | None]:
        """The path relative to the robot in its frame, and the colour it shows next (a luminous
        algorithm's, else None); raises WrongAlgorithmError or AlgorithmParamsError for a
        snapshot it cannot act on, TypeError or LightsError for an algorithm's bad answer."""
        if snapshot.algorithm != self.algorithm.name:
            raise WrongAlgorithmError(
                f"the world runs algorithm {snapshot.algorithm!r}, this "
                f"agent {self.algorithm.name!r}"
            )
        setting = self._setting
        if setting is None or setting.n != snapshot.n or dict(setting.values) != snapshot.params:
            setting = self._setting = Configured.of(self.algorithm, snapshot.n, snapshot.params)
        return act(setting, snapshot)


def act(setting: Configured, snapshot: Snapshot) -> tuple[Path, int | None]:
    """One Compute on a snapshot, as every agent makes it: the path in the robot's frame and its
    next colour (None without lights)."""
    return act_on(setting, snapshot.view, snapshot.colours, snapshot.own)


def act_on(
    setting: Configured, view: Points, colours: tuple[int, ...] | None, own: int | None
) -> tuple[Path, int | None]:
    """`act` on what a snapshot carries (the lock step hands it over without the snapshot)."""
    return setting.decide(view, glance_of(setting.colours, own, colours))


def open_session(conf: Any, stop: threading.Event, waiting: str | None = None) -> Any:
    """Open a Zenoh session, retrying until the router answers; None if stopped first.

    With `waiting` (who waits, e.g. "robot 3"), say every WAIT_NOTICE_S that it still waits, where.
    """
    import zenoh  # the CLI imports this module for its flags: zenoh loads when a robot runs

    started = time.monotonic()
    noticed = 0  # notices given so far
    while not stop.is_set():
        try:
            session = zenoh.open(conf)
        except zenoh.ZError as exc:
            log.debug("router not reachable yet: %s", exc)
            waited = time.monotonic() - started
            if waiting and waited >= (noticed + 1) * WAIT_NOTICE_S:
                noticed = int(waited // WAIT_NOTICE_S)
                log.warning(
                    "%s: still waiting for a Zenoh router at %s (%.0f s so far); retrying",
                    waiting,
                    _endpoints(conf),
                    waited,
                )
            stop.wait(OPEN_RETRY_S)
            continue
        if noticed:
            log.warning(
                "%s: the router at %s answered after %.0f s",
                waiting,
                _endpoints(conf),
                time.monotonic() - started,
            )
        return session
    return None


def _endpoints(conf: Any) -> str:
    """The config's connect endpoints, for a notice."""
    endpoints = json.loads(conf.get_json("connect/endpoints"))
    return ", ".join(map(str, endpoints)) if isinstance(endpoints, list) else str(endpoints)


class Stopped(Exception):
    """A stop signal came while the agent waited for its Look's answer."""


class Relook(Exception):
    """A world came up while the agent waited for its Look's answer: the Look may have been lost
    with a router or world that went away, so it is asked again (with its move, if it had one)."""


def serve(
    cfg: AgentConfig,
    conf: Any,
    stop: threading.Event | None = None,
    waiting: str | None = None,
    algorithm: Algorithm[Any] | None = None,
) -> int:
    """Run one robot until `stop` is set; returns an exit code (`waiting`: see open_session).

    `algorithm`: loaded from `cfg.algorithm` if None (raises AlgorithmError if it cannot be).
    Call it from the process's main thread: a stop signal interrupts a Look's wait there, and
    before the process's first session, with its Zenoh runtime settled
    (`deploy.net.zconf.settle_runtime`: the callers in deploy do).
    """
    import zenoh  # the CLI imports this module for its flags: zenoh loads when a robot runs

    stop = stop or threading.Event()
    robot = Robot(algorithm or load_algorithm(cfg.algorithm))
    session = open_session(conf, stop, waiting)
    if session is None:
        return 0
    with session:
        querier = session.declare_querier(
            snapshot_key(cfg.swarm, cfg.robot),
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
            timeout=LOOK_WAIT_S,
        )
        _token = session.liveliness().declare_token(agent_alive_key(cfg.swarm, cfg.robot))
        look_wait = _LookWait(stop)
        # A router that restarts can lose a Look on its way (it is then never answered, and the
        # agent would wait LOOK_WAIT_S): when the world's token (re)appears, ask again at once.
        _world = session.liveliness().declare_subscriber(
            world_alive_key(cfg.swarm), look_wait.world_seen, history=True
        )
        log.info("robot %d up", cfg.robot)
        _cycle(cfg, robot, querier, look_wait, stop)
    return 0


def _cycle(
    cfg: AgentConfig, robot: Robot, querier: Any, look_wait: _LookWait, stop: threading.Event
) -> None:
    """Look, Compute, Move until `stop` is set.

    The world process and round it last answered, and the move for that round: the Move travels
    in every Look until the world answers one (a Look lost with a router that went away must not
    lose the move with it; the world takes a move once).
    """
    import zenoh  # the CLI imports this module for its flags: zenoh loads when a robot runs

    request = LookRequest()
    with look_wait.install():
        while not stop.is_set():
            asked = time.monotonic()
            try:
                snapshot = _look(querier, request, look_wait)
            except Stopped:
                break
            except Relook:
                log.info("robot %d: a world came up; asking again", cfg.robot)
                continue
            except zenoh.ZError as exc:  # the router is away: ask again (move and all)
                log.warning("look failed: %s", exc)
                snapshot = None
            if snapshot is None:
                if time.monotonic() - asked < RELOOK_S:  # no world to hold it: do not spin
                    stop.wait(RELOOK_S)
                continue
            request = LookRequest(
                epoch=snapshot.epoch, after=snapshot.round, move=_move(cfg, snapshot, robot)
            )


class _LookWait:
    """How a Look's wait ends early. SIGTERM and SIGINT set `stop`, and while a Look waits they
    also raise Stopped in the main thread, so that a Look the world holds does not hold up the
    exit. A world that comes up cancels the waiting Look's query (its cancellation token)."""

    def __init__(self, stop: threading.Event) -> None:

        self.stop = stop
        self.cancel: Any = None  # the waiting Look's zenoh.CancellationToken (None: none waits)
        self.world_up = False  # a world came up while it waited
        self._lock = threading.Lock()  # the callback's view of (cancel, world_up)
        self._raised = False  # Stopped was raised once: a second signal only sets `stop`

    @property
    def waiting(self) -> bool:
        """A Look waits for its answer."""
        return self.cancel is not None

    def handle(self, signum: int, frame: object) -> None:
        del signum, frame
        self.stop.set()
        # once: a second signal may come while the first Stopped unwinds (in `end`, or as the
        # handlers are put back), where raising again would escape the loop as a traceback
        if self.waiting and not self._raised:
            self._raised = True
            raise Stopped

    def world_seen(self, sample: Any) -> None:
        """Liveliness callback on the world's token: a world that (re)appears while a Look waits
        ends the wait, and the Look is asked again."""
        import zenoh  # the CLI imports this module for its flags: zenoh loads when a robot runs

        if sample.kind != zenoh.SampleKind.PUT:
            return
        with self._lock:
            if self.cancel is None:
                return
            self.world_up, cancel = True, self.cancel
        cancel.cancel()

    def begin(self) -> Any:
        """A cancellation token for the next Look's query (set as the waiting one)."""
        import zenoh  # the CLI imports this module for its flags: zenoh loads when a robot runs

        with self._lock:
            self.cancel, self.world_up = zenoh.CancellationToken(), False
            return self.cancel

    def end(self) -> bool:
        """The Look's wait is over; True if a world came up meanwhile."""
        with self._lock:
            self.cancel = None
            return self.world_up

    @contextmanager
    def install(self) -> Iterator[None]:
        """The handlers, for the loop's lifetime (not in the main thread: a Look waits out its
        answer or timeout)."""
        try:
            before = {
                sig: signal.signal(sig, self.handle) for sig in (signal.SIGTERM, signal.SIGINT)
            }
        except ValueError:
            yield
            return
        try:
            yield
        finally:
            for sig, handler in before.items():
                signal.signal(sig, handler)


def _look(querier: Any, last: LookRequest, wait: _LookWait) -> Snapshot | None:
    """Ask for this robot's snapshot of a round after `last` and wait until the world answers
    (it holds the query until the robot is activated); None if it let the query go or sent
    nothing valid. Raises Relook when a world came up and cut the wait short (no reply came),
    Stopped on a stop signal."""
    import zenoh  # the CLI imports this module for its flags: zenoh loads when a robot runs

    snapshot = None
    replied = False  # a cancelled query ends with no reply at all, not even its timeout's
    cancel = wait.begin()
    try:
        if wait.stop.is_set():  # a stop that came before the wait
            raise Stopped
        try:
            replies = querier.get(payload=last.encode(), cancellation_token=cancel)
        except zenoh.ZError:
            if not cancel.is_cancelled:
                raise
            replies = []  # a world came up before the query left: it is asked again
        for reply in replies:
            replied = True
            if reply.ok is None:  # the query's timeout, or the world's refusal
                log.debug("no snapshot: %s", _err_text(reply))
                continue
            try:
                snapshot = Snapshot.decode(reply.ok.payload.to_bytes())
            except ProtocolError as exc:
                log.warning("rejected snapshot: %s", exc)
    finally:
        world_up = wait.end()
    if world_up and not replied:
        raise Relook
    return snapshot


def _err_text(reply: Any) -> str:
    """What an error reply says (Zenoh's timeout, or the world's reason), for the debug log."""
    try:
        return str(reply.err.payload.to_string())[:200]
    except Exception:  # a reply without a readable error payload
        return "(no reason given)"


def _move(cfg: AgentConfig, snapshot: Snapshot, robot: Robot) -> bytes:
    """Compute in the private frame: the encoded move for the snapshot's round. A compute that
    raises gives a move that stays and says why (`MoveSubmitted.failed`: the world books it at
    once, no move timeout); b"" for a snapshot it cannot act on (another algorithm, refused
    parameters): it stays out of this round, and says why on its log."""
    debug = log.isEnabledFor(logging.DEBUG)
    t0, cpu0 = (time.perf_counter(), time.thread_time()) if debug else (0.0, 0.0)
    round_no = snapshot.round
    try:
        path, colour = robot.look_compute(snapshot)
        move = MoveSubmitted(robot=cfg.robot, round=round_no, path=path, colour=colour).encode()
    except (WrongAlgorithmError, AlgorithmParamsError) as exc:
        log.error("round %d: staying put: %s", round_no, exc)
        return b""
    except Exception as exc:  # a bug in compute must not kill the robot: it stays this round
        failed = failure_text(exc)
        kind = failure_kind(failed)
        if kind not in robot.failure_kinds:  # one line per kind of failure, no traceback
            robot.failure_kinds.add(kind)
            log.info(  # the world says it on the run's log, once a kind, for every robot
                "round %d: compute failed (%s); staying (failures of this kind are counted by "
                "the world, not logged again)",
                round_no,
                failed,
            )
        log.debug("round %d: compute failed", round_no, exc_info=True)
        return MoveSubmitted.failing(cfg.robot, round_no, failed).encode()
    if debug:
        log.debug(
            "round %d: compute %.2f ms (CPU %.2f ms)",
            round_no,
            1e3 * (time.perf_counter() - t0),
            1e3 * (time.thread_time() - cpu0),
        )
    return move
