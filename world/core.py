"""The world's state machine: looks, moves, control requests and commits, with no I/O but its
journal (an injected sink: the run record, or nothing).

The Zenoh shell (world/service.py) and the in-process lock step (deploy/engine/lockstep.py) drive
this very core, so a networked run and a lock-step run of the same configuration are one
computation. Physics and the end test are the core's (`world.physics.apply_round`,
`world.progress`).
"""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Final, Protocol

import numpy as np

from fatswarm.domain.draws import crash_plan, cut_fraction, view_order
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Path, Point, Points, path_length, transform, truncate
from fatswarm.domain.registry import DEFAULT, load_algorithm
from fatswarm.domain.seam import AlgorithmFailure, Configured, ParamValue
from fatswarm.domain.tolerance import snap
from fatswarm.world.physics import Collision, RoundOutcome, apply_round
from fatswarm.world.progress import ProgressTracker
from fatswarm.world.protocol import (
    AgentInfo,
    Begin,
    Commit,
    ControlReply,
    ControlRequest,
    Hello,
    LookRequest,
    MovesHeld,
    MoveSubmitted,
    Snapshot,
    WorldState,
)
from fatswarm.world.record import Header, RoundEntry, RunRecord

log = logging.getLogger("fatswarm.world")

CRASH_MIN_ROUNDS: Final = 10
FIRST_LOOK: Final = LookRequest()  # an agent's first Look: any round


def crash_after(n: int) -> int:
    """Committed rounds a robot's agent may be gone before it counts as crashed: twice the
    default fairness bound (every live robot is active at least once in 2n rounds), >= 10."""
    return max(CRASH_MIN_ROUNDS, 4 * n)


class Journal(Protocol):
    """Where committed rounds go: `world.record.RecordWriter`, or `NullJournal`."""

    def header(
        self,
        n: int,
        seed: int | None,
        scheduler: str,
        initial: Points,
        *,
        algorithm: str,
        params: Mapping[str, ParamValue],
        **extra: Any,
    ) -> None: ...

    def round(
        self,
        round_no: int,
        active: Sequence[int],
        moves: Mapping[int, tuple[Path, float]],
        positions: Points,
        collisions: Sequence[Collision] = (),
        **extra: Any,
    ) -> None: ...

    def result(self, status: str, rounds: int, positions: Points, **extra: Any) -> None: ...

    def close(self) -> None: ...


class NullJournal:
    """A journal that keeps nothing (a lock-step run without a record)."""

    def header(
        self,
        n: int,
        seed: int | None,
        scheduler: str,
        initial: Points,
        *,
        algorithm: str,
        params: Mapping[str, ParamValue],
        **extra: Any,
    ) -> None:
        del n, seed, scheduler, initial, algorithm, params, extra

    def round(
        self,
        round_no: int,
        active: Sequence[int],
        moves: Mapping[int, tuple[Path, float]],
        positions: Points,
        collisions: Sequence[Collision] = (),
        **extra: Any,
    ) -> None:
        del round_no, active, moves, positions, collisions, extra

    def result(self, status: str, rounds: int, positions: Points, **extra: Any) -> None:
        del status, rounds, positions, extra

    def close(self) -> None:
        return None


@dataclass(frozen=True, slots=True)
class WorldSetup:
    """What a run starts from (or what the state file's header says when resuming)."""

    swarm: str
    n: int
    seed: int
    scheduler: str
    initial: Points  # (n, 2)
    max_rounds: int | None
    algorithm: str = DEFAULT  # how every process loads it: a name or module:attribute
    params: Mapping[str, ParamValue] = field(default_factory=dict)  # given ones; defaults fill in
    extra: Mapping[str, Any] = field(default_factory=dict)  # more header fields (how it was run)
    non_rigid: float | None = None  # the adversary's delta (non-rigid moves); None: rigid moves
    crash: int | None = None  # f: robots the adversary crashes for good (`crash_plan`); None: 0


@dataclass(frozen=True, slots=True)
class Committed:
    """The round just committed: who was active, the world-frame paths applied, what physics did."""

    round: int
    active: tuple[int, ...]
    paths: dict[int, Path]
    outcome: RoundOutcome


def cut_path(start: Point, path: Path, delta: float, u: float) -> Path:
    """`path` (from `start`) as the non-rigid adversary stops it: whole if its length L is at most
    `delta`, else its prefix of length delta + u (L - delta), u in [0, 1) (issue 10's model: the
    robot travels at least delta, or reaches its end)."""
    length = path_length(start, path)
    if length <= delta:
        return path
    return truncate(start, path, delta + u * (length - delta))


# --- the durable log: the run record itself, fsynced line by line ----------------------------


def header_non_rigid(header: Header) -> float | None:
    """The non-rigid adversary's delta a record's header gives (None: rigid moves)."""
    delta = header.extra.get("non_rigid")
    return float(delta) if isinstance(delta, (int, float)) else None


def header_crash(header: Header) -> int | None:
    """The crash adversary's f a record's header gives (None: no crashes)."""
    crash = header.extra.get("crash")
    return crash if isinstance(crash, int) and not isinstance(crash, bool) else None


def setup_from_header(header: Header, swarm: str, max_rounds: int | None) -> WorldSetup:
    """The run described by a state file's header line."""
    saved = header.extra.get("max_rounds", max_rounds)
    return WorldSetup(
        swarm=swarm,
        n=header.n,
        seed=int(header.seed or 0),
        scheduler=header.scheduler,
        initial=np.asarray(header.initial, dtype=np.float64),
        max_rounds=int(saved) if isinstance(saved, int) else max_rounds,
        algorithm=header.algorithm_ref,
        params=dict(header.params),
        extra={
            k: v
            for k, v in header.extra.items()
            if k not in ("max_rounds", "swarm", "non_rigid", "crash")
        },
        non_rigid=header_non_rigid(header),
        crash=header_crash(header),
    )


# --- the state machine ------------------------------------------------------------------------


class WorldCore:
    """The world's state and its answers to looks, moves and control requests (no I/O but the log).

    Robot identity comes from the key a message arrives on and must match the robot it names; a
    move counts only for the open round, from an active robot that has looked, once. A Look that
    comes before its robot may look (`may_look`) is for the shell to hold and answer once the
    robot is activated; `moves_notice` says when every live active robot has moved.
    """

    def __init__(
        self,
        setup: WorldSetup,
        journal: Journal | None = None,
        history: RunRecord | None = None,
        algorithm: Configured | None = None,
        epoch: int = 0,
    ) -> None:
        """`algorithm`: the run's algorithm, configured; loaded from `setup.algorithm` if None.
        `epoch`: this world process among the run's (a restarted world draws a new one).

        Raises AlgorithmError or AlgorithmParamsError for an algorithm it cannot load or
        configure, and the algorithm's own refusal of the start (`check_start`).
        """
        self.setup = setup
        self.epoch = epoch
        self.journal: Journal = NullJournal() if journal is None else journal
        n = setup.n
        if algorithm is None:
            algorithm = Configured.of(load_algorithm(setup.algorithm), n, setup.params)
        self.algorithm = algorithm
        # On the grid, so that every robot's view is exact (fatswarm/domain/tolerance.py); a start
        # that came through validate_configuration is there already.
        self.positions: Points = snap(np.array(setup.initial, dtype=np.float64).reshape(n, 2))
        if history is None:
            algorithm.check_start(self.positions)
        # the crash adversary's plan (robot -> round it crashes in) and the robots crashed so far
        self.crash_plan = {} if setup.crash is None else crash_plan(setup.seed, n, setup.crash)
        self.stuck: frozenset[int] = frozenset()
        self._live_goals: dict[int, Configured | None] = {n: algorithm}
        self.tracker = ProgressTracker(n, self._goal, setup.max_rounds)
        self.status: str = Status.RUNNING
        self.committed = 0
        self.open_round = 0
        self.active: tuple[int, ...] = ()
        self._active_set: frozenset[int] = frozenset()  # the same, for O(1) membership
        self.looked: set[int] = set()
        self.held: dict[int, Path] = {}
        self._missing: set[int] = set()  # live active robots of the open round without a move
        self._noticed: tuple[int, tuple[int, ...]] | None = None  # last moves notice sent
        self.moved: tuple[int, ...] = ()
        self.stopped: tuple[int, ...] = ()
        self.collisions_total = 0
        self.alive = [False] * n
        self.gone_since: list[int | None] = [0] * n  # committed round its agent was last seen
        # (None while it is alive)
        self.last_active = [-1] * n
        self.last_length = [0.0] * n
        self.timeouts = [0] * n
        self.rejected: Counter[str] = Counter()
        self._agents: tuple[AgentInfo, ...] | None = None  # cache of state().agents
        self._figures: dict[str, float] | None = None  # cache of state().figures
        self.last_commit: Committed | None = None
        self.last_timed_out: tuple[int, ...] = ()  # of the round committed last (its reply says)
        self._figures_failed = False
        if history is None:
            self.journal.header(
                n,
                setup.seed,
                setup.scheduler,
                self.positions,
                algorithm=algorithm.name,
                params=algorithm.values,
                algorithm_ref=setup.algorithm,
                max_rounds=setup.max_rounds,
                swarm=setup.swarm,
                **({} if setup.non_rigid is None else {"non_rigid": setup.non_rigid}),
                **({} if setup.crash is None else {"crash": setup.crash}),
                **setup.extra,
            )
        else:
            self._replay(history)
        self.gone_since = [self.committed] * n  # no agent seen yet: counted from here

    # -- resume ---------------------------------------------------------------------------------

    def _replay(self, record: RunRecord) -> None:
        """Rebuild the state from the committed rounds of a state file."""
        for entry in record.rounds:
            self._replay_round(entry)
        if record.result is not None:
            self.status = record.result.status
        elif self.tracker.status is not None:
            self._finish()  # died between the last round line and the result line
        log.info(
            "resumed %s after round %d (%s)",
            getattr(self.journal, "path", "a run"),
            self.committed,
            self.status,
        )

    def _replay_round(self, entry: RoundEntry) -> None:
        before = self.positions
        after = np.asarray(entry.positions, dtype=np.float64)
        timed_out = {int(r) for r in entry.extra.get("timed_out", [])}
        traveled = {m.robot: m.traveled for m in entry.moves}
        paths = {m.robot: m.path for m in entry.moves}
        self._account(
            entry.round,
            entry.active,
            paths,
            timed_out,
            before,
            after,
            traveled,
            entry.collisions,
            entry.extra.get("crashed", ()),
            entry.extra.get("recovered", ()),
            self._stuck_in(entry.round),
        )

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
        crashed: Collection[int] = (),
        recovered: Collection[int] = (),
        stuck: Collection[int] = (),
    ) -> None:
        """Book one committed round (live or replayed) into the state and the progress tracker.
        `stuck`: the robots the crash adversary crashes in this round (for good)."""
        if stuck:
            log.info(
                "robots %s crash in round %d (the crash adversary): they stay where they "
                "are for good",
                sorted(stuck),
                round_no,
            )
            self.stuck |= frozenset(stuck)
            self.tracker.crash(stuck)
        if crashed:
            log.warning(
                "robots %s count as crashed from round %d: their agents have been gone "
                "for %d rounds; they stay where they are, and are not waited for",
                sorted(crashed),
                round_no,
                crash_after(self.setup.n),
            )
        self.tracker.crash(crashed)
        self.tracker.recover(recovered)
        self._agents = None
        self._figures = None
        for robot in active:
            self.last_active[robot] = round_no
        for robot in timed_out:
            self.timeouts[robot] += 1
        for robot, path in paths.items():
            self.last_length[robot] = path_length(
                (float(before[robot, 0]), float(before[robot, 1])), path
            )
        self.collisions_total += len(collisions)
        self.tracker.observe(
            [r for r in active if r not in timed_out],
            paths.keys(),
            before,
            after,
            traveled,
            len(collisions),
        )
        self.positions, self.committed = after, round_no
        self.active = tuple(active)
        self._active_set = frozenset(self.active)
        self.moved = tuple(sorted(paths))
        self.stopped = tuple(sorted({c.robot for c in collisions}))

    # -- requests -------------------------------------------------------------------------------

    def reject(self, reason: str, detail: str) -> None:
        """Count and log a refused input (never raised, never applied)."""
        self.rejected[reason] += 1
        log.warning("rejected (%s): %s [total %d]", reason, detail, self.rejected[reason])

    def may_look(self, robot: int, request: LookRequest = FIRST_LOOK) -> bool:
        """Whether robot `robot`'s Look is answered now: it is active in the open round, has not
        moved in it, and asks for a round after the last it moved in (at this world process);
        otherwise the shell holds the Look until this becomes true."""
        after = request.after if request.epoch == self.epoch else 0
        return self.open_round > after and robot in self._active_set and robot not in self.held

    def look(self, robot: int) -> Snapshot | None:
        """Robot `robot`'s snapshot, or None (refused, counted) if it is not active now."""
        if not 0 <= robot < self.setup.n:
            self.reject("look-bad-key", f"robot {robot}")
            return None
        if not self.open_round or robot not in self._active_set:
            self.reject("look-not-active", f"robot {robot} round {self.open_round}")
            return None
        self.looked.add(robot)
        pos = self.positions
        others = np.concatenate((pos[:robot], pos[robot + 1 :])) - pos[robot]
        others = others[view_order(self.setup.seed, self.open_round, robot, len(others))]
        return Snapshot(
            round=self.open_round,
            n=self.setup.n,
            algorithm=self.algorithm.name,
            params=dict(self.algorithm.values),
            view=others,
            epoch=self.epoch,
        )

    def admit_look(self, robot: int) -> bool:
        """Count robot `robot`'s Look without building its view (a lock step that plans the round
        at once); False (refused, counted) if it is not active now."""
        if not self.open_round or robot not in self._active_set:
            self.reject("look-not-active", f"robot {robot} round {self.open_round}")
            return False
        self.looked.add(robot)
        return True

    def move(self, robot: int | None, msg: MoveSubmitted) -> bool:
        """Hold a move for the open round from the robot `robot` it came from (None: a key with no
        robot); False if refused (counted)."""
        if robot != msg.robot:
            self.reject("move-wrong-robot", f"robot {msg.robot} sent as robot {robot}")
        elif msg.round != self.open_round:
            self.reject("move-wrong-round", f"robot {robot} round {msg.round} != {self.open_round}")
        elif robot not in self._active_set:
            self.reject("move-not-active", f"robot {robot} round {msg.round}")
        elif robot not in self.looked:
            self.reject("move-without-look", f"robot {robot} round {msg.round}")
        elif robot in self.held:
            self.reject("move-duplicate", f"robot {robot} round {msg.round}")
        else:
            self.held[robot] = msg.path
            self._missing.discard(robot)
            return True
        return False

    def moves_notice(self) -> MovesHeld | None:
        """The notice to send the coordinator when every live active robot of the open round has
        moved (once, and again only when a late move joins them); None otherwise."""
        if not self.open_round or self._missing:
            return None
        robots = tuple(sorted(self.held))
        if self._noticed == (self.open_round, robots):
            return None
        self._noticed = (self.open_round, robots)
        return MovesHeld(self.open_round, robots, self.epoch)

    def control(self, req: ControlRequest) -> tuple[ControlReply, bool]:
        """Answer a coordinator request; the flag says whether the state changed (publish it)."""
        if isinstance(req, Hello):
            return self.reply(True), False
        if self.status != Status.RUNNING:
            return self.reply(False, f"the run has ended ({self.status})"), False
        if isinstance(req, Begin):
            return self._begin(req)
        if req.then_active and max(req.then_active) >= self.setup.n:  # refused whole, not halfway
            return self.reply(False, "next round's active set names robots not of this run"), False
        reply, changed = self._commit(req)
        then = req.then
        if reply.ok and changed and then is not None and self.status == Status.RUNNING:
            reply = self._begin(then)[0]
        if reply.ok and changed:
            reply = replace(reply, timed_out=self.last_timed_out)
        return reply, changed

    def reply(self, ok: bool, reason: str = "") -> ControlReply:
        return ControlReply(
            ok=ok,
            reason=reason,
            n=self.setup.n,
            committed=self.committed,
            open_round=self.open_round,
            status=self.status,
            collisions=self.collisions_total,
            held=tuple(sorted(self.held)) if self.open_round else (),
            epoch=self.epoch,
        )

    def _begin(self, req: Begin) -> tuple[ControlReply, bool]:
        if req.round != self.committed + 1:
            return self.reply(False, f"next round is {self.committed + 1}, not {req.round}"), False
        if not req.active or req.active[-1] >= self.setup.n:
            return self.reply(False, "active set empty or not robots of this run"), False
        if self.open_round == req.round and self.active == req.active:
            return self.reply(True), False  # a coordinator retrying: keep what is held
        self.open_round, self.active = req.round, req.active
        self._active_set = frozenset(req.active)
        self.looked, self.held, self._noticed = set(), {}, None
        self._missing = {r for r in req.active if self.alive[r]}
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
        stuck = self._stuck_in(round_no)
        for robot in self.stuck | frozenset(stuck):  # a crashed robot's moves are not applied
            paths.pop(robot, None)
        cut = self._cut(round_no, before, paths)
        outcome = apply_round(before, paths) if paths else RoundOutcome(before.copy())
        after = np.asarray(outcome.positions, dtype=np.float64)
        traveled = {r: float(outcome.traveled.get(r, 0.0)) for r in paths}
        timed_out = [r for r in self.active if r not in self.held]
        self.last_timed_out = tuple(timed_out)
        down, back = self._crashes(round_no)
        extra: dict[str, list[int]] = {}
        for key, robots in (
            ("timed_out", timed_out),
            ("crashed", down),
            ("recovered", back),
            ("cut", cut),
            ("crash", stuck),
        ):
            if robots:
                extra[key] = robots
        self.journal.round(
            round_no,
            self.active,
            {r: (p, traveled[r]) for r, p in paths.items()},
            after,
            outcome.collisions,
            **extra,
        )
        self._account(
            round_no,
            self.active,
            paths,
            timed_out,
            before,
            after,
            traveled,
            outcome.collisions,
            down,
            back,
            stuck,
        )
        self.last_commit = Committed(round_no, self.active, paths, outcome)
        self.open_round, self.looked, self.held, self._missing = 0, set(), {}, set()
        if self.tracker.status is not None:
            self._finish()

    def _cut(self, round_no: int, before: Points, paths: dict[int, Path]) -> list[int]:
        """Non-rigid moves: the adversary stops each path of `paths` (world frame, replaced in
        place) where `cut_path` says; returns the robots it stopped short."""
        delta = self.setup.non_rigid
        if delta is None:
            return []
        cut = []
        for robot, path in paths.items():
            start = (float(before[robot, 0]), float(before[robot, 1]))
            short = cut_path(start, path, delta, cut_fraction(self.setup.seed, round_no, robot))
            if short is not path:
                paths[robot] = short
                cut.append(robot)
        return cut

    def _stuck_in(self, round_no: int) -> list[int]:
        """The robots the crash adversary crashes in round `round_no` (`crash_plan`)."""
        return sorted(r for r, at in self.crash_plan.items() if at == round_no)

    def _goal(self, positions: Points) -> bool:
        """The run's goal: the algorithm's for all robots, or once the crash adversary has crashed
        some, the algorithm's for the live robots alone, configured for their number (False if
        the algorithm refuses that number): README, "Faults"."""
        if not self.stuck:
            return self.algorithm.goal(positions)
        live = [r for r in range(self.setup.n) if r not in self.stuck]
        if len(live) not in self._live_goals:
            try:
                self._live_goals[len(live)] = Configured.of(
                    self.algorithm.algorithm, len(live), self.algorithm.values
                )
            except ValueError:  # AlgorithmParamsError, or a refusal of that n
                self._live_goals[len(live)] = None
        setting = self._live_goals[len(live)]
        return setting is not None and setting.goal(positions[live])

    def _finish(self) -> None:
        progress = self.tracker.snapshot()
        status = progress.status or Status.STALLED
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
        self.gone_since[robot] = None if alive else self.committed
        self._agents = None
        if alive and robot in self._active_set and robot not in self.held:
            self._missing.add(robot)
        elif not alive:
            self._missing.discard(robot)  # a robot gone mid-round is not waited for
        return True

    def _crashes(self, round_no: int) -> tuple[list[int], list[int]]:
        """(robots that count as crashed from this round, crashed robots whose agent is back):
        the rule of the record's `crashed` and `recovered` round fields (README, "Faults")."""
        limit = crash_after(self.setup.n)
        crashed = self.tracker.crashed
        down = [
            r
            for r, since in enumerate(self.gone_since)
            if since is not None and round_no - since >= limit and r not in crashed
        ]
        back = sorted(r for r in crashed if self.alive[r] and r not in self.stuck)
        return down, back

    def state(self) -> WorldState:
        """The observers' view of the world now."""
        n = self.setup.n
        return WorldState(
            round=self.committed,
            n=n,
            algorithm=self.algorithm.name,
            params=dict(self.algorithm.values),
            figures=self._algorithm_figures(),
            scheduler=self.setup.scheduler,
            swarm=self.setup.swarm,
            positions=self.positions,
            active=self.active,
            open_round=self.open_round,
            moved=self.moved,
            stopped=self.stopped,
            collisions_total=self.collisions_total,
            status=self.status,
            agents=self._agent_infos(),
        )

    def _algorithm_figures(self) -> dict[str, float]:
        """The algorithm's figures for the positions, made once per committed round."""
        if self._figures is None:
            try:
                self._figures = self.algorithm.figures(self.positions)
            except AlgorithmFailure as exc:  # only the dashboard misses them: say it once
                if not self._figures_failed:
                    log.warning("%s; the dashboard goes without figures", exc)
                self._figures_failed, self._figures = True, {}
        return self._figures

    def _agent_infos(self) -> tuple[AgentInfo, ...]:
        """Per-robot agent info, rebuilt only after it changed (it is published twice a round)."""
        if self._agents is None:
            self._agents = tuple(
                AgentInfo(self.alive[i], self.last_active[i], self.last_length[i], self.timeouts[i])
                for i in range(self.setup.n)
            )
        return self._agents
