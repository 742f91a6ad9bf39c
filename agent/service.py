"""The agent process: one robot. On activation it Looks, Computes in its private frame, Moves.

It keeps only its identity and its frame (an X mirroring drawn at start-up, never sent). The world
sends the others' positions relative to this robot with world axes; the agent mirrors them into its
own frame, computes, mirrors the path back and sends it relative to itself, so no global coordinate
ever reaches it or leaves it.
"""

from __future__ import annotations

import json
import logging
import queue
import threading
import time
from dataclasses import dataclass
from typing import Any

from fatswarm.agent.frames import compute_in_frame, draw_flip
from fatswarm.agent.path import Path
from fatswarm.agent.protocol import MoveSubmitted, alive_key, move_key
from fatswarm.agent.registry import DEFAULT
from fatswarm.agent.seam import Algorithm, AlgorithmParamsError, Configured, checked
from fatswarm.coordinator.protocol import MAX_ROUND_START_BYTES, RoundStart, round_key
from fatswarm.world.inbox import Inbox
from fatswarm.world.protocol import ProtocolError, Snapshot, snapshot_key

log = logging.getLogger("fatswarm.agent")

LOOK_TIMEOUT_S = 5.0
OPEN_RETRY_S = 0.2  # a client cannot open a session before its router is up: retry
WAIT_NOTICE_S = 5.0  # meanwhile, say this often that the robot still waits for its router


@dataclass(frozen=True, slots=True)
class AgentConfig:
    """One robot's identity and the seed its private frame is drawn from."""

    swarm: str
    robot: int
    seed: int
    algorithm: str = DEFAULT  # a registered name or module:attribute (agent/registry.py)


class WrongAlgorithmError(ValueError):
    """The world runs another algorithm than this agent: it stays put rather than guess."""


class Robot:
    """One robot's Compute: the algorithm, configured by what each snapshot says (n and the
    parameters), kept while they do not change."""

    def __init__(self, algorithm: Algorithm[Any], flip_x: bool) -> None:
        self.algorithm = algorithm
        self.flip_x = flip_x
        self._setting: Configured | None = None

    def look_compute(self, snapshot: Snapshot) -> Path:
        """The path relative to the robot, world axes; raises WrongAlgorithmError or
        AlgorithmParamsError for a snapshot it cannot act on."""
        if snapshot.algorithm != self.algorithm.name:
            raise WrongAlgorithmError(f"the world runs algorithm {snapshot.algorithm!r}, this "
                                      f"agent {self.algorithm.name!r}")
        setting = self._setting
        if setting is None or setting.n != snapshot.n or dict(setting.values) != snapshot.params:
            setting = self._setting = Configured.of(self.algorithm, snapshot.n, snapshot.params)
        path = compute_in_frame(snapshot.view, self.flip_x, checked(setting.compute))
        return path


def open_session(conf: Any, stop: threading.Event, waiting: str | None = None) -> Any:
    """Open a Zenoh session, retrying until the router answers; None if stopped first.

    With `waiting` (who waits, e.g. "robot 3"), say every WAIT_NOTICE_S that it still waits, where.
    """
    import zenoh

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
                log.warning("%s: still waiting for a Zenoh router at %s (%.0f s so far); retrying",
                            waiting, _endpoints(conf), waited)
            stop.wait(OPEN_RETRY_S)
            continue
        if noticed:
            log.warning("%s: the router at %s answered after %.0f s", waiting, _endpoints(conf),
                        time.monotonic() - started)
        return session
    return None


def _endpoints(conf: Any) -> str:
    """The config's connect endpoints, for a notice."""
    endpoints = json.loads(conf.get_json("connect/endpoints"))
    return ", ".join(map(str, endpoints)) if isinstance(endpoints, list) else str(endpoints)


def serve(
    cfg: AgentConfig,
    conf: Any,
    stop: threading.Event | None = None,
    waiting: str | None = None,
    algorithm: Algorithm[Any] | None = None,
) -> int:
    """Run one robot until `stop` is set; returns an exit code (`waiting`: see open_session).

    `algorithm`: loaded from `cfg.algorithm` if None (raises AlgorithmError if it cannot be)."""
    import zenoh

    from fatswarm.agent.registry import load_algorithm

    stop = stop or threading.Event()
    robot = Robot(algorithm or load_algorithm(cfg.algorithm), draw_flip(cfg.seed, cfg.robot))
    starts: Inbox[bytes] = Inbox(max_items=64)  # only the newest start matters
    session = open_session(conf, stop, waiting)
    if session is None:
        return 0
    with session:
        session.declare_subscriber(
            round_key(cfg.swarm), lambda s: _offer_start(starts, s)
        )
        mover = session.declare_publisher(
            move_key(cfg.swarm, cfg.robot),
            congestion_control=zenoh.CongestionControl.BLOCK,
            express=True,
        )
        querier = session.declare_querier(
            snapshot_key(cfg.swarm, cfg.robot),
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
            timeout=LOOK_TIMEOUT_S,
        )
        _token = session.liveliness().declare_token(alive_key(cfg.swarm, cfg.robot))
        log.info("robot %d up", cfg.robot)
        while not stop.is_set():
            start = _newest_start(starts)
            if start is not None and cfg.robot in start.active:
                try:
                    _cycle(cfg, start.round, robot, querier, mover)
                except zenoh.ZError as exc:  # the router is away: this round goes without us
                    log.warning("round %d: %s", start.round, exc)
    return 0


def _newest_start(starts: Inbox[bytes]) -> RoundStart | None:
    """The newest valid round start queued (waiting a little for one): a newer start supersedes
    an older one, and garbage after a real start does not hide it."""
    try:
        pending = [starts.get(timeout=0.2)]
    except queue.Empty:
        return None
    while len(starts):
        pending.append(starts.get_nowait())
    newest = None
    for data in pending:
        try:
            newest = RoundStart.decode(data)
        except ProtocolError as exc:
            log.warning("rejected round start: %s", exc)
    return newest


def _offer_start(starts: Inbox[bytes], sample: Any) -> None:
    """Queue a round start unless it is larger than any can be (then it is dropped unread)."""
    size = len(sample.payload)
    if size > MAX_ROUND_START_BYTES:
        starts.too_big("round-start")
        return
    starts.offer("round-start", sample.payload.to_bytes(), size)


def _cycle(cfg: AgentConfig, round_no: int, robot: Robot, querier: Any, mover: Any) -> None:
    """One Look-Compute-Move cycle for round `round_no`."""
    snapshot = None
    t_look = time.perf_counter()
    for reply in querier.get():
        if reply.ok is None:
            log.info("round %d: world refused the look", round_no)
            continue
        try:
            snapshot = Snapshot.decode(reply.ok.payload.to_bytes())
        except ProtocolError as exc:
            log.warning("rejected snapshot: %s", exc)
    if snapshot is None or snapshot.round != round_no:
        return
    t0, cpu0 = time.perf_counter(), time.thread_time()
    try:
        path = robot.look_compute(snapshot)
        move = MoveSubmitted(robot=cfg.robot, round=round_no, path=path).encode()
    except (WrongAlgorithmError, AlgorithmParamsError) as exc:
        log.error("round %d: staying put: %s", round_no, exc)
        return
    except Exception:  # a bug in compute must not kill the robot: it stays put this round
        log.exception("round %d: compute failed, staying put", round_no)
        return
    log.debug("round %d: look %.2f ms, compute %.2f ms (CPU %.2f ms)", round_no,
              1e3 * (t0 - t_look), 1e3 * (time.perf_counter() - t0),
              1e3 * (time.thread_time() - cpu0))
    mover.put(move)
