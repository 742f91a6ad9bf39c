"""The whole run in one process: the world's and the coordinator's very cores on an in-process
bus, with every robot's Look-Compute-Move done in turn.

Nothing of the round is written here: `world.core.WorldCore` serves the looks, holds the moves,
commits through physics and keeps the record; `coordinator.rounds.CoordinatorCore` picks the
active sets and opens and closes the rounds, exactly as in a networked run. Each active robot
Looks (the world's snapshot, in the robot's private frame, as an agent's) and Moves. An
algorithm with a `round_planner` (the paper's: `SharedPlans`) makes the round's paths at once,
the very paths each robot's own `compute` returns; a `compute` passed in is called per robot.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable, Generator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Final

import numpy as np

from fatswarm.agent.params import Params
from fatswarm.agent.service import act_on
from fatswarm.agent.uniform_circle import ALGORITHM as UNIFORM_CIRCLE
from fatswarm.coordinator.async_rounds import coordinator_core
from fatswarm.coordinator.driver import Event, driving, run_out
from fatswarm.coordinator.rounds import Finished, Note, RoundTimes
from fatswarm.coordinator.schedule import Scheduler
from fatswarm.domain.adversary import ASYNC_NAMES, AsyncModel, make_async
from fatswarm.domain.figures import FigureValue
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import (
    MAX_SEGMENTS,
    Arc,
    Line,
    Path,
    Points,
    StraightMoves,
    vertices,
)
from fatswarm.domain.robot_model import PAPER_MODEL, Bodies, RobotModel
from fatswarm.domain.seam import AlgorithmFailure, Configured, checked, failure_text
from fatswarm.domain.tolerance import enclosing_circle
from fatswarm.domain.wire import MAX_COORD, MAX_SWEEP, ProtocolError
from fatswarm.world.core import WorldCore
from fatswarm.world.effects import Committed
from fatswarm.world.journal import Journal, perform
from fatswarm.world.looks import Seen
from fatswarm.world.physics import validate_configuration
from fatswarm.world.protocol import ControlReply, ControlRequest, MoveSubmitted
from fatswarm.world.record import Header, Result, RoundEntry, RunRecord, line_text
from fatswarm.world.setup import WorldSetup

# Default round cap = ROUNDS_PER_STEP[scheduler] * (n + STEP_SLACK). The algorithm needs about
# n + 2 sequential steps (one mover or one mirror pair each); a step costs 1 round under fsync,
# about 2 under ssync (p = 1/2), about n under centralized; the caps leave a factor 10 or more.
# Under the async models a "round" is an ended cycle: every robot cycles while one moves, and the
# fastest ones cycle up to 2n - 1 times as often under async-slowest (non-rigid 0.1 at n = 12
# took 2733 cycles), hence 40 n. A move of length L lasts L, and the others keep cycling (about
# once per 2 time units) all along: so the async cap grows with the distances, by one more 40 n
# (n + 10) for every ASYNC_REACH_UNIT of the run's reach (the larger of the start's and the
# target's circle), so that a run whose moves are long is not cut while every robot progresses.
STEP_SLACK: Final = 10
ROUNDS_PER_STEP: Final = {"fsync": 10, "ssync": 40}  # others (centralized, scripted): 10 n
CYCLES_PER_STEP_PER_ROBOT: Final = 40  # the async models: 40 n
ASYNC_REACH_UNIT: Final = 40.0  # robot radii of reach the plain async cap covers (moves ~ 80)
# A non-rigid adversary may stop a move after delta: a move then takes more cycles the smaller
# delta is (up to L / delta for a move of length L). The async cap above was calibrated down to
# delta = NON_RIGID_UNIT; below it, it grows by ceil(NON_RIGID_UNIT / delta) (at delta = 0.05 the
# plain cap cut runs that were still progressing, and 5 times it let all of them form).
NON_RIGID_UNIT: Final = 0.5
LOCKSTEP_SWARM: Final = "lockstep"
SHOWN_FAULTS: Final = 3  # moves the world refuses logged in full; the rest are counted
_FLOAT64: Final = np.dtype(np.float64)  # (an array's dtype is mostly this very object)
_BOOL: Final = np.dtype(np.bool_)

log = logging.getLogger("fatswarm.lockstep")

ComputeFn = Callable[[Points, Any], Path]
ARRAYS_FROM: Final = 2
"""`_hand_over_round` takes a round as arrays from this many lookers: one robot's move alone (the
centralized and async rounds) costs less as a Path (callgrind, no-compute at n = 8: 759k
instructions a centralized round robot by robot, 900k as arrays)."""
Decided = tuple[Path, int | None] | str
"""A robot's Compute as the lock step hands it over: its path (own frame) and next colour, or why
its compute failed (`failure_text`)."""


class HistoryMismatchError(ValueError):
    """Committed rounds to resume from that this run would not have produced."""


class LockstepStoppedError(RuntimeError):
    """A lock-step run asked to go on after it raised half-way."""


def default_max_rounds(
    n: int, scheduler: str, reach: float = 0.0, non_rigid: float | None = None
) -> int:
    """A round cap far above what a correct run needs under `scheduler` (see ROUNDS_PER_STEP);
    under an async model, in ended cycles, scaled by the run's `reach` (`run_reach`) and by a
    non-rigid delta below NON_RIGID_UNIT (None: rigid moves)."""
    per_robot = CYCLES_PER_STEP_PER_ROBOT if scheduler in ASYNC_NAMES else 10
    per_step = ROUNDS_PER_STEP.get(scheduler, per_robot * max(1, n))
    cap = per_step * (n + STEP_SLACK)
    if scheduler in ASYNC_NAMES and reach > ASYNC_REACH_UNIT:
        cap *= math.ceil(reach / ASYNC_REACH_UNIT)
    if scheduler in ASYNC_NAMES and non_rigid is not None and 0.0 < non_rigid < NON_RIGID_UNIT:
        cap *= math.ceil(NON_RIGID_UNIT / non_rigid)
    return cap


def run_reach(setting: Configured, initial: Points) -> float:
    """How far the run spreads: the radius of the start's smallest enclosing circle, or of the
    algorithm's target circle (its `target radius` figure, if it has one) when that is larger."""
    radius = enclosing_circle(initial)[2] if len(initial) else 0.0
    try:
        target = setting.figures(initial).get("target radius", 0.0)
    except AlgorithmFailure:  # an algorithm's figures that fail say nothing of its reach
        target = 0.0
    return max(radius, float(target))


def _cap(
    max_rounds: int | None,
    setting: Configured,
    scheduler: str,
    initial: Points,
    non_rigid: float | None = None,
) -> int:
    """`max_rounds`, or the default cap of the run (`default_max_rounds`, with its reach and
    non-rigid delta under an async model)."""
    if max_rounds is not None:
        return max_rounds
    reach = run_reach(setting, initial) if scheduler in ASYNC_NAMES else 0.0
    return default_max_rounds(len(initial), scheduler, reach, non_rigid)


RoundReport = Committed  # what `on_round` gets: the round's record line and the figures after it


@dataclass(frozen=True, slots=True)
class RunResult:
    """How a run ended and what it cost. Positions are (n, 2), world frame."""

    status: Status
    rounds: int
    epochs: int
    moves: int
    total_distance: float
    collisions: int
    looks: int
    initial: Points
    positions: Points
    moves_by_robot: tuple[int, ...]
    time: float | None = None  # async models: the virtual time the run ended at
    lights: tuple[str, ...] = ()  # each robot's final colour (a luminous algorithm's), else ()
    # the run's figures that follow from the positions (fatswarm.domain.figures), by name
    derived: Mapping[str, FigureValue] = field(default_factory=dict)


def configured(params: Params | Configured) -> Configured:
    """The run's algorithm: a `Configured` as given, or the paper's algorithm for `Params`."""
    if isinstance(params, Configured):
        return params
    return Configured(
        UNIFORM_CIRCLE,
        params.n,
        {"a": float(params.a)},
        params,
        assumptions=UNIFORM_CIRCLE.assumptions,
    )


def run_lockstep(
    initial: Points,
    params: Params | Configured,
    scheduler: Scheduler,
    *,
    seed: int,
    max_rounds: int | None = None,
    record: Journal | None = None,
    on_round: Callable[[RoundReport], None] | None = None,
    compute: ComputeFn | None = None,
    history: Sequence[RoundEntry] | None = None,
    algorithm_ref: str | None = None,
    header_extra: dict[str, Any] | None = None,
    non_rigid: float | None = None,
    crash: int | None = None,
    robot_model: RobotModel = PAPER_MODEL,
    record_views: bool = False,
    settings: WorldSetup | None = None,
) -> RunResult:
    """Run until formed, stalled or `max_rounds` (default `default_max_rounds`): the run
    `start_lockstep` starts (the same arguments), to its end."""
    return start_lockstep(
        initial,
        params,
        scheduler,
        seed=seed,
        max_rounds=max_rounds,
        record=record,
        on_round=on_round,
        compute=compute,
        history=history,
        algorithm_ref=algorithm_ref,
        header_extra=header_extra,
        non_rigid=non_rigid,
        crash=crash,
        robot_model=robot_model,
        record_views=record_views,
        settings=settings,
    ).finish()


def start_lockstep(
    initial: Points,
    params: Params | Configured,
    scheduler: Scheduler,
    *,
    seed: int,
    max_rounds: int | None = None,
    record: Journal | None = None,
    on_round: Callable[[RoundReport], None] | None = None,
    compute: ComputeFn | None = None,
    history: Sequence[RoundEntry] | None = None,
    algorithm_ref: str | None = None,
    header_extra: dict[str, Any] | None = None,
    non_rigid: float | None = None,
    crash: int | None = None,
    robot_model: RobotModel = PAPER_MODEL,
    record_views: bool = False,
    settings: WorldSetup | None = None,
) -> Lockstep:
    """A run that goes until formed, stalled or `max_rounds` (default `default_max_rounds`),
    started: its header recorded, its rounds to come as it is advanced (`Lockstep`).

    `params`: the paper's `Params`, or any algorithm `Configured` for n robots.
    `seed` fixes the robots' private frames and view orders; the scheduler carries its own seed.
    `compute(view, params)` replaces the algorithm's compute (called per robot and Look).
    `history`: resume a run from `initial` after these committed rounds (a record's, maybe none):
    the world and the coordinator replay them as they do after a restart, and they are not
    recorded again (nor the header); the run then goes on exactly as it would have without the
    break. `algorithm_ref` (how to load the algorithm again; default its name) and
    `header_extra` go into the record's header. `non_rigid`: the adversary's delta (moves may be
    stopped after delta, `world.faults.cut_path`); None for rigid moves. `crash`: f robots the
    adversary crashes for good (`world.core.crash_plan`); None for none. `robot_model`: sight,
    obstruction, lights and frames (docs/model.md); `record_views`: each record line names what
    each looker saw. `settings`: the run's settings whole (`RunConfig.resolve`'s), in place of
    `algorithm_ref` ... `record_views`: what its header says, how the run was made among it.
    Raises InvalidConfigurationError for an invalid start, the algorithm's refusal of the start
    (UnsupportedInputError for the paper's, outside the supported range), ValueError if n
    disagrees with params, HistoryMismatchError for a history this run would not have produced.
    """
    setting = configured(params)
    model = robot_model if settings is None else settings.robot_model
    points = model.bodies is Bodies.POINTS  # point robots may share a point
    positions = validate_configuration(initial, bodies_are_points=points)  # a copy, on the grid
    n = len(positions)
    if n != setting.n:
        raise ValueError(f"the start has {n} robots but params say n={setting.n}")
    cap = _cap(max_rounds, setting, scheduler.name, positions, non_rigid)
    setup = (
        replace(settings, swarm=LOCKSTEP_SWARM, initial=positions, max_rounds=cap)
        if settings is not None
        else WorldSetup(
            swarm=LOCKSTEP_SWARM,
            n=n,
            seed=seed,
            scheduler=scheduler.name,
            initial=positions,
            max_rounds=cap,
            algorithm=algorithm_ref or setting.name,
            params=dict(setting.values),
            extra=dict(header_extra or {}),
            non_rigid=non_rigid,
            crash=crash,
            robot_model=robot_model,
            record_views=record_views,
        )
    )
    world, checked = _open(setup, setting, scheduler, history)
    if history is not None and isinstance(scheduler, AsyncModel):  # replayed from its start
        log.info("resuming %s after cycle %d", getattr(record, "path", "a run"), len(history))
        replayed = ReplayedRecord(record, history)
        bus: _Bus = _ReplayBus(world, setting, compute, replayed, replayed.fresh(on_round))
        return Lockstep(world, bus, bus.steps(checked), positions, 0)  # its Looks come again
    if history is not None:
        committed = world.readout.committed
        log.info("resumed %s after round %d", getattr(record, "path", "a run"), committed)
    bus = _Bus(world, setting, compute, record, on_round)
    looks = sum(len(entry.active) for entry in history or ())
    return Lockstep(world, bus, bus.steps(checked), positions, looks)


class Lockstep:
    """A lock-step run under way: the world core and the coordinator's one loop on the bus
    (`coordinator.driver.driving`), advanced an exchange at a time (`advance`: a round opened or
    committed, an async instant) or to the end (`finish`)."""

    def __init__(
        self,
        world: WorldCore,
        bus: _Bus,
        steps: Generator[None, None, Finished],
        initial: Points,
        looks_before: int,
    ) -> None:
        self.world = world  # read through its readout (the result's figures)
        self.readout = world.readout
        self.setting = bus.setting  # the run's algorithm, configured
        self.finished: Finished | None = None  # how the coordinator finished, once it has
        self.raised: BaseException | None = None  # what stopped the run half-way, if anything
        self._bus, self._steps = bus, steps
        self._initial, self._looks_before = initial, looks_before

    @property
    def looks(self) -> int:
        """Looks so far (those of the rounds resumed from, too)."""
        return self._bus.looks + self._looks_before

    def advance(self) -> bool:
        """One exchange of the coordinator with the world (a control request answered); False
        once the run has ended (then nothing is done). Raises what the run raises (the
        algorithm's goal failing: `AlgorithmFailure`, an interrupt); after that, every call
        raises `LockstepStoppedError`: the world may be half-way through a round."""
        if self.finished is not None:
            return False
        self._check_going()
        try:
            next(self._steps)
        except StopIteration as done:
            self.finished = done.value
            return False
        except BaseException as exc:
            self.raised = exc
            raise
        return True

    def finish(self) -> RunResult:
        """Run on to the end; how the run ended and what it cost (raises as `advance` does)."""
        if self.finished is None:
            self._check_going()
            try:
                self.finished = run_out(self._steps)
            except BaseException as exc:
                self.raised = exc
                raise
        return _result(self.world, self.finished, self.looks, self._initial)

    def _check_going(self) -> None:
        if self.raised is not None:
            said = f": {self.raised}" if str(self.raised) else ""
            raise LockstepStoppedError(
                f"the run stopped after round {self.readout.committed} when it raised "
                f"{type(self.raised).__name__}{said}"
            )


def _result(world: WorldCore, finished: Finished, looks: int, initial: Points) -> RunResult:
    """How the run ended and what it cost, from the world's books."""
    readout = world.readout
    progress = readout.progress()
    assert progress.status is not None and finished.status == progress.status
    return RunResult(
        status=progress.status,
        rounds=progress.rounds,
        epochs=progress.epochs,
        moves=progress.moves,
        total_distance=progress.total_distance,
        collisions=progress.collisions,
        looks=looks,
        initial=np.array(initial),
        positions=readout.positions,
        moves_by_robot=progress.moves_by_robot,
        time=readout.time(),
        lights=readout.lights(),
        derived=dict(progress.derived),
    )


def _open(
    setup: WorldSetup,
    setting: Configured,
    scheduler: Scheduler,
    history: Sequence[RoundEntry] | None,
) -> tuple[WorldCore, Scheduler]:
    """The world core of a new run, or of a run resumed after `history` (replayed, and the
    scheduler checked against it); raises HistoryMismatchError for a history this run would
    not have produced. An async run's history is replayed by the bus from the start instead
    (`ReplayedRecord`): its world core is a new run's."""
    if history is None or isinstance(scheduler, AsyncModel):
        setting.check_start(setup.initial)
        return WorldCore(setup, setting), scheduler
    _check_history(history)
    header = Header(setup.n, setup.seed, scheduler.name, setup.initial)
    try:
        world = WorldCore(setup, setting, RunRecord(header, tuple(history), None))
    except RuntimeError as exc:  # the tracker saw a round after the run had ended
        raise HistoryMismatchError(str(exc)) from None
    status = world.readout.status
    if status != Status.RUNNING:
        raise HistoryMismatchError(f"the run already ended ({status}) after round {len(history)}")
    return world, _CheckedScheduler(scheduler, history)


class _Bus:
    """The in-process bus: carries the coordinator's actions to the world and the agents, and
    their answers back, until the coordinator finishes."""

    def __init__(
        self,
        world: WorldCore,
        setting: Configured,
        compute: ComputeFn | None,
        record: Journal | None,
        on_round: Callable[[RoundReport], None] | None,
    ) -> None:
        self.world = world  # the commands go to the core, the reads to its readout
        self.readout = world.readout
        self.setting = setting
        self.record = record
        self.on_round = on_round
        self.clock = 0.0  # virtual time: it moves only to a deadline nothing else can meet first
        self.events: list[Event] = []  # for the coordinator: the open round's moves notice
        self.looks = 0
        self.faults = 0  # moves the world refused (the robot timed out)
        self.compute: Callable[[Seen], tuple[Path, int | None]]
        if compute is not None:
            user, params = compute, setting.params
            self.compute = lambda seen: (checked(lambda v: user(v, params))(seen[0]), None)
        else:
            self.compute = lambda seen: act_on(setting, *seen)
        # the round planner gives the paper's model's paths: every view whole, fixed frames
        setup = self.readout.setup
        plain = setup.robot_model.is_paper and not setting.luminous and not setup.record_views
        self.planner = setting.round_planner() if compute is None and plain else None
        # the round hook: every active robot's path in one call, each from its own view (used
        # where the world builds the round's views at once, `WorldCore.views_of`)
        self.batch = setting.views_compute() if compute is None and self.planner is None else None
        # an algorithm without either: each robot's own compute on its row of the round's views,
        # built at once where the world can, its moves handed over as arrays where they allow
        # (`_act_each`); a luminous one goes per robot (its colours)
        self.each = (
            compute is None and self.planner is None and self.batch is None and not setting.luminous
        )
        self.flips = [self.readout.frame(robot, 0).mirror for robot in range(setup.n)]

    def steps(self, scheduler: Scheduler) -> Generator[None, None, Finished]:
        """Every robot's agent up for the whole run and the header recorded (at once), then the
        coordinator's core driven on this bus (`driving`) as the steps are taken, until the run
        ends."""
        return _finished(self.driven(scheduler))

    def driven(self, scheduler: Scheduler) -> Generator[None, None, Finished]:
        """`steps` until the run ends or this bus is `stopped` (then as the coordinator's core
        stopped: RUNNING)."""
        n = self.readout.setup.n
        for robot in range(n):
            self.world.set_alive(robot, True)
        self.perform()  # the header of a new run
        coordinator = coordinator_core(
            scheduler.name, lambda _n: scheduler, RoundTimes(), resume_live=range(n)
        )
        for robot in range(n):
            coordinator.on_alive(robot, True, 0.0)
        return driving(coordinator, self)

    # -- the link `drive` runs on: a virtual clock, the world core in this process ------------

    def now(self) -> float:
        return self.clock

    def ask(self, request: ControlRequest) -> ControlReply:
        """The world core answers at once; a round it opens has every robot Look, Compute and
        Move at once too (each Look is held at the world until then), and its moves notice
        comes back as the next event."""
        world = self.world
        opened = self.readout.open_round
        try:
            reply, _ = world.control(request)
        finally:  # what was committed is recorded, even when the algorithm's goal raised
            self.perform()
        # The reply says where the world stands after the request (it is made last). A round it
        # opened is acted at once (unless stopped: a replay's agents take the round over).
        if reply.ok and reply.open_round and reply.open_round != opened and not self.stopped():
            self._act(reply.open_round, self.readout.active)
            self.perform()
            notice = world.moves_notice()
            if notice is not None:
                self.events.append(notice)
        return reply

    def wait(self, deadline: float | None) -> list[Event] | None:
        """The moves notice of the round just opened, if any; else the clock jumps to the
        deadline (time passes only when nothing else can happen first); None if there is none."""
        if self.events:
            events, self.events = self.events, []
            return events
        if deadline is None:
            return None
        self.clock = max(self.clock, deadline)
        return []

    def stopped(self) -> bool:
        return False

    def note(self, notes: Sequence[Note]) -> None:
        del notes  # a lock step keeps the coordinator's notes to itself, as it always has

    def _act(self, round_no: int, active: Sequence[int]) -> None:
        """Every active robot's Look, Compute and Move; a move reaches the world one way only,
        through the wire codec (`_delivered`), as a networked agent's does."""
        world = self.world
        # the others' Looks stay held (robots the async adversary crashed)
        lookers = world.lookers(active)
        if self.planner is not None:
            planned = self.planner.paths(self.readout.positions, active, self.flips)
            admitted = world.admit_looks(lookers)
            planned_paths: list[Decided | None] = [
                (planned[robot], None) if ok else None
                for robot, ok in zip(lookers, admitted, strict=True)
            ]
            self._hand_over_round(round_no, lookers, admitted, planned_paths)
            return
        if self._acted_at_once(round_no, lookers):
            return
        world.prepare_looks(lookers)
        decided: list[Decided | None] = []
        for robot in lookers:
            seen = world.view_of(robot)  # what its snapshot would carry (None: refused, counted)
            decided.append(None if seen is None else self._computed(seen))
        self._hand_over_round(round_no, lookers, [each is not None for each in decided], decided)

    def _acted_at_once(self, round_no: int, lookers: Sequence[int]) -> bool:
        """Whether the round was acted with its views built at once: through the round hook, or
        each robot's compute on its row of them."""
        if self.batch is not None:
            return self._act_at_once(round_no, lookers)
        return self.each and self._act_each(round_no, lookers)

    def _hand_over(self, robot: int, round_no: int, decided: Decided) -> None:
        """Robot `robot`'s decision (its path and colour, or why its compute failed) to the world
        as its agent's move would reach it (`_delivered`)."""
        move = decided if isinstance(decided, str) else self._delivered(robot, round_no, *decided)
        if isinstance(move, str):  # its compute raised: it stays and says why, as an agent
            self.world.hold(robot, round_no, Path(), None, move)
        elif move is not None:  # else as a move the world refuses: it times out
            self.world.hold(robot, round_no, *move)

    def _act_at_once(self, round_no: int, lookers: Sequence[int]) -> bool:
        """`_act` through the round hook: the lookers' views as one array, their paths in one
        call, handed over as `_act` hands a round (`_hand_over_round`); False (nothing done) where
        the world cannot build the views at once. A hook that raises, or gives something that is
        not a Path for a robot, has that robot's own compute say why (its failure, as alone)."""
        assert self.batch is not None
        world = self.world
        views = world.views_of(lookers)
        if views is None:
            return False
        admitted = world.admit_looks(lookers)
        try:
            answer: Sequence[Path] | StraightMoves | None = self.batch(views)
        except Exception:  # each robot's own compute then says what it says alone
            answer = None
        if isinstance(answer, StraightMoves) and self._straight(
            round_no, lookers, admitted, answer
        ):
            return True
        try:
            if answer is None:
                raise TypeError("compute_views raised")
            paths: Sequence[object] = (
                answer.paths() if isinstance(answer, StraightMoves) else answer
            )
            if len(paths) != len(lookers):
                raise TypeError(f"compute_views gave {len(paths)} paths for {len(lookers)} views")
        except Exception:  # each robot's own compute then says what it says alone
            paths = [None] * len(lookers)
        decided: list[Decided | None] = []
        for ok, view, path in zip(admitted, views, paths, strict=True):
            if not ok:
                decided.append(None)  # its Look was refused, counted
            elif type(path) is Path:
                decided.append((path, None))
            else:  # the hook gave it no path: its own compute says what it says alone
                decided.append(self._computed((view, None, None)))
        self._hand_over_round(round_no, lookers, admitted, decided)
        return True

    def _act_each(self, round_no: int, lookers: Sequence[int]) -> bool:
        """`_act` for an algorithm without a round hook where the world builds the round's views
        at once: each looker's own compute on its row of them (the very view `view_of` gives),
        in turn; their moves handed over as arrays (`_straight`) where every one is a straight
        line or a stay of floats without a colour, else each as `_act` hands it over; False
        (nothing done) where the world cannot build the views at once."""
        world = self.world
        views = world.views_of(lookers)
        if views is None:
            return False
        admitted = world.admit_looks(lookers)
        computed = self._computed
        decided = [
            computed((view, None, None)) if ok else None
            for ok, view in zip(admitted, views, strict=True)
        ]
        self._hand_over_round(round_no, lookers, admitted, decided)
        return True

    def _hand_over_round(
        self,
        round_no: int,
        lookers: Sequence[int],
        admitted: Sequence[bool],
        decided: Sequence[Decided | None],
    ) -> None:
        """The lookers' decisions (None: its Look was refused, counted) to the world: as arrays
        (`_straight`) where every one is a straight line or a stay (`straight_lines`), else each
        as `_hand_over` gives it."""
        lines = straight_lines(decided) if len(decided) >= ARRAYS_FROM else None
        if lines is not None and self._straight(round_no, lookers, admitted, lines):
            return
        for robot, each in zip(lookers, decided, strict=True):
            if each is not None:
                self.looks += 1
                self._hand_over(robot, round_no, each)

    def _straight(
        self, round_no: int, lookers: Sequence[int], admitted: Sequence[bool], moves: StraightMoves
    ) -> bool:
        """The round hook's StraightMoves for `lookers` delivered and held as arrays: what `_act`
        does per robot (`_delivered`'s wire checks: `plain_path` of each row, then `hold`), the
        lines kept as arrays (`WorldCore.hold_lines`); False (nothing done) unless the arrays
        are of the contract's shapes and kinds and every row passes the wire's checks as it is
        (a row that breaks them goes the per-robot way with the rest, refused and counted)."""
        ends, goes, k = moves.ends, moves.goes, len(lookers)
        if not (
            type(ends) is np.ndarray
            and (ends.dtype is _FLOAT64 or ends.dtype == np.float64)
            and ends.shape == (k, 2)
            and type(goes) is np.ndarray
            and (goes.dtype is _BOOL or goes.dtype == np.bool_)
            and goes.shape == (k,)
        ):
            return False
        # plain_path of one Line of floats: finite and inside the wire's bounds (NaN fails);
        # count_nonzero: one C loop where .all() is a ufunc reduction (the same answer), and
        # `False in a` a comparison ufunc and a reduction: both about 4 to 9 times its cost
        every = np.count_nonzero(goes) == k
        going = ends if every else ends[goes]
        if np.count_nonzero(np.abs(going) <= MAX_COORD) != going.size:
            return False
        if all(admitted):
            robots = lookers
        else:
            ok = np.array(admitted, dtype=np.bool_)
            robots = [robot for robot, admit in zip(lookers, admitted, strict=True) if admit]
            ends, goes = ends[ok], goes[ok]
            every = every or np.count_nonzero(goes) == len(robots)
        self.looks += len(robots)
        self.world.hold_lines(robots, round_no, ends, None if every else goes)
        return True

    def _computed(self, seen: Seen) -> Decided:
        """The robot's path in its frame and next colour, or why its compute failed (raised, or
        returned something that is not a path: `failure_text`), as its agent would send it."""
        try:
            return self.compute(seen)
        except Exception as exc:  # the algorithm's failure: the robot stays, as networked
            return failure_text(exc)

    def _delivered(
        self, robot: int, round_no: int, path: Path, colour: int | None
    ) -> tuple[Path, int | None] | str | None:
        """The path and colour as the world receives them from an agent (the wire's checks,
        `MoveSubmitted.of`); None if the world would refuse them (counted, said on the log); why,
        if the path cannot even be encoded (an agent's encoding raises: its compute failed)."""
        try:
            if colour is None and plain_path(path):
                return path, None
            msg = MoveSubmitted.of(robot, round_no, path, colour)
            return msg.path, msg.colour
        except ProtocolError as exc:
            self.world.reject("move-garbage", f"robot {robot} round {round_no}: {exc}")
            self._fault(robot, round_no, f"sent a move the world refuses: {exc}")
        except Exception as exc:  # a path that cannot even be encoded: the algorithm's bug
            return failure_text(exc)
        return None

    def _fault(self, robot: int, round_no: int, problem: str) -> None:
        """Count a robot that stays put for a move the world refuses; the first ones in full."""
        self.faults += 1
        if self.faults <= SHOWN_FAULTS:
            log.warning(
                "robot %d, round %d: %s; it stays put (timed out)%s",
                robot,
                round_no,
                problem,
                "; further faults are only counted" if self.faults == SHOWN_FAULTS else "",
            )

    def perform(self) -> None:
        """Do what the world asked: its record lines to the run record, its notes to the log,
        and every committed round (an ended cycle, under an async model) to `on_round`."""
        effects = self.world.take_effects()
        if effects:  # (most calls have none: the round's Looks and moves ask for nothing)
            for committed in perform(effects, self.record):
                if self.on_round is not None:
                    self.on_round(committed)


def straight_lines(decided: Sequence[Decided | None]) -> StraightMoves | None:
    """The decisions as StraightMoves, row i decided[i]'s, where every one is a straight line or a
    stay in its robot's frame, of Python floats, with no colour (None, a robot whose Look was
    refused: a stay nobody reads); None where any is not (a failure, a colour, an arc, several
    pieces, another type of path, point or number): those go robot by robot."""
    ends: list[float] = []
    goes: list[bool] = []
    for each in decided:
        if each is None:
            ends += _NOWHERE
            goes.append(False)
            continue
        if type(each) is not tuple:  # why its compute failed
            return None
        path, colour = each
        if colour is not None or type(path) is not Path or type(path.segments) is not tuple:
            return None
        if not path.segments:  # a stay
            ends += _NOWHERE
            goes.append(False)
            continue
        if len(path.segments) != 1 or type(path.segments[0]) is not Line:
            return None
        end = path.segments[0].end
        if not (type(end) is tuple and len(end) == 2):
            return None
        x, y = end
        if not (type(x) is float and type(y) is float):
            return None
        ends += end
        goes.append(True)
    return StraightMoves(
        np.array(ends, dtype=np.float64).reshape(len(goes), 2), np.array(goes, dtype=np.bool_)
    )


_NOWHERE: Final = (0.0, 0.0)  # `straight_lines`' end of a stay (read by nobody)


def plain_path(path: Path) -> bool:
    """Whether the wire's checks give `path` back as it is: `MoveSubmitted.of` would return a
    move with an equal path (made of the same floats), no refusal. True only for a Path of Line
    and Arc segments of exact floats in tuples, finite and inside the wire's bounds
    (`checked_path`: every vertex, every arc's centre and sweep); False for anything else, which
    goes the codec's way (a property test pins the two together)."""
    if type(path) is not Path or type(path.segments) is not tuple:
        return False
    if len(path.segments) > MAX_SEGMENTS:
        return False
    arcs = False
    for seg in path.segments:
        if type(seg) is Line:
            point: object = seg.end  # a line's end is its vertex
        elif type(seg) is Arc:
            if not (type(seg.sweep) is float and abs(seg.sweep) <= MAX_SWEEP):  # NaN fails too
                return False
            point, arcs = seg.center, True
        else:
            return False
        if not (type(point) is tuple and len(point) == 2):
            return False
        x, y = point
        if not (type(x) is float and type(y) is float):
            return False
        if not (abs(x) <= MAX_COORD and abs(y) <= MAX_COORD):
            return False
    # an arc's end is a vertex too
    return not arcs or all(
        abs(x) <= MAX_COORD and abs(y) <= MAX_COORD for x, y in vertices((0.0, 0.0), path)
    )


def _finished(steps: Generator[None, None, Finished]) -> Generator[None, None, Finished]:
    """The coordinator's `steps`, checked to finish the run."""
    finished = yield from steps
    if finished.status == Status.RUNNING:
        raise RuntimeError("the coordinator stopped without finishing the run")  # a bug
    return finished


class _CheckedScheduler:
    """The run's scheduler, checked against the recorded active sets while the coordinator
    replays the committed rounds into it."""

    def __init__(self, scheduler: Scheduler, history: Sequence[RoundEntry]) -> None:
        self.scheduler = scheduler
        self.name = scheduler.name
        self.history = history

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        active = self.scheduler.active(round_no, live)
        if round_no <= len(self.history):
            recorded = list(self.history[round_no - 1].active)
            if recorded != active:
                raise HistoryMismatchError(
                    f"round {round_no} activated robots {recorded} where this "
                    f"{self.scheduler.name} schedule activates {active}"
                )
        return active


class ReplayedRecord:
    """The journal of an async run resumed by replaying it: the lines its record holds already
    (`lines`) come again, each checked to be that very line (as written: the same bytes) and
    not written again, nor the header; the lines after them go to `journal`.

    Why a replay: an async record's lines are ended cycles, and what was in flight between them
    (Looks made, moves computed or under way, the adversary's clock) is in no line. The run is a
    pure function of its settings (the adversary's draws are keyed by seed, robot and cycle), so
    running it again from its start, unrecorded, puts the world exactly where it was after the
    last line: the lock step goes on from there, a restarted networked world serves from there
    (`replay_async`). No side file; the cost is the run so far, computed again.
    """

    def __init__(self, journal: Journal | None, lines: Sequence[RoundEntry | Result]) -> None:
        self.journal = journal
        self.path = getattr(journal, "path", None)
        self.lines = tuple(lines)
        self.checked = 0  # lines of `lines` replayed so far
        # (robot, cycle) of the cycles the record says timed out (a networked run's slow agents):
        # the replay holds no move for them either (a robot's n-th line is its n-th cycle)
        self.timed_out: set[tuple[int, int]] = set()
        cycles: dict[int, int] = {}
        for line in self.lines:
            if isinstance(line, RoundEntry):
                for robot in line.active:
                    cycles[robot] = cycles.get(robot, 0) + 1
                    if robot in line.extra.get("timed_out", ()):
                        self.timed_out.add((robot, cycles[robot]))

    @property
    def done(self) -> bool:
        """Whether every line of the record has come again."""
        return self.checked >= len(self.lines)

    def fresh(
        self, on_round: Callable[[RoundReport], None] | None
    ) -> Callable[[RoundReport], None] | None:
        """`on_round` for the lines after the record's (those replayed were reported before)."""
        if on_round is None:
            return None
        known = len(self.lines)
        return lambda report: None if report.entry.round <= known else on_round(report)

    def append(self, line: Header | RoundEntry | Result) -> None:
        if isinstance(line, Header):
            return  # the record's own, written when it began
        if not self.done:
            expected = self.lines[self.checked]
            if line_text(line) != line_text(expected):
                raise HistoryMismatchError(_difference(self.checked + 1, expected, line))
            self.checked += 1
            return
        if self.journal is not None:
            self.journal.append(line)

    def close(self) -> None:
        if self.journal is not None:
            self.journal.close()


def _difference(k: int, recorded: RoundEntry | Result, made: RoundEntry | Result) -> str:
    """What differs between the record's line `k` and the replay's (one line)."""
    if isinstance(recorded, Result) or isinstance(made, Result):
        if isinstance(made, Result):
            return f"the run ends ({made.status}) after cycle {made.rounds}; the record goes on"
        return f"the record ends after cycle {k - 1}; this run goes on"
    theirs, mine = json.loads(line_text(recorded)), json.loads(line_text(made))
    keys = [key for key in dict.fromkeys([*theirs, *mine]) if theirs.get(key) != mine.get(key)]
    return (
        f"cycle {k} is not the one this run makes (it differs in {', '.join(keys) or 'order'}): "
        "the record was made with other settings or another version"
    )


class _ReplayBus(_Bus):
    """The bus of a replayed async run (`ReplayedRecord`): the cycles the record says timed out
    time out again; `stop_replayed`: the bus stops once the record's lines have all come again
    (a networked world's replay: its agents go on from there)."""

    def __init__(
        self,
        world: WorldCore,
        setting: Configured,
        compute: ComputeFn | None,
        replayed: ReplayedRecord,
        on_round: Callable[[RoundReport], None] | None,
        *,
        stop_replayed: bool = False,
    ) -> None:
        super().__init__(world, setting, compute, replayed, on_round)
        self.replayed = replayed
        self.stop_replayed = stop_replayed

    def stopped(self) -> bool:
        return self.stop_replayed and self.replayed.done

    def _act(self, round_no: int, active: Sequence[int]) -> None:
        if self.replayed.timed_out and not self.replayed.done:
            began = dict(self.world.reply(True).cycles)
            active = [r for r in active if (r, began.get(r, 0)) not in self.replayed.timed_out]
        super()._act(round_no, active)


def replay_async(
    setup: WorldSetup, setting: Configured, record: RunRecord, journal: Journal, epoch: int = 0
) -> WorldCore:
    """The world core of a networked async run resumed from `record` (a restarted world, or
    `fatswarm run --resume`): the run replayed in process from its start (`ReplayedRecord`)
    until every line of the record has come again, then no agent seen yet. Lines the replay
    makes past the record's in the same step (a world killed while writing them) go to
    `journal`. Raises HistoryMismatchError for a record this run does not make."""
    world = WorldCore(setup, setting, epoch=epoch)
    lines: list[RoundEntry | Result] = [*record.rounds]
    if record.result is not None:
        lines.append(record.result)
    replayed = ReplayedRecord(journal, lines)
    bus = _ReplayBus(world, setting, None, replayed, None, stop_replayed=True)
    run_out(bus.driven(make_async(setup.scheduler, setup.n, setup.seed)))
    if not replayed.done:
        raise HistoryMismatchError(
            f"the run ends after cycle {replayed.checked}; the record goes on to cycle "
            f"{len(record.rounds)}"
        )
    for robot in range(setup.n):  # the agents of the run say themselves that they are there
        world.set_alive(robot, False)
    return world


def _check_history(history: Sequence[RoundEntry]) -> None:
    """Refuse rounds out of order, or with robots timed out (a networked run's slow agents cannot
    be redone in lock step; a compute that failed is no time-out: the line's `failed` says it,
    and a lock step redoes it)."""
    for round_no, entry in enumerate(history, start=1):
        if entry.round != round_no:
            raise HistoryMismatchError(f"round {entry.round} comes where round {round_no} should")
        crashed = entry.extra.get("crashed")
        if crashed:
            raise HistoryMismatchError(
                f"round {round_no}: robots {crashed} counted as crashed "
                "(their agents were gone), which a lock step cannot redo"
            )
        timed_out = entry.extra.get("timed_out")
        if timed_out:
            raise HistoryMismatchError(
                f"round {round_no}: robots {timed_out} timed out (slow or "
                "gone agents, or moves the world refused), which a lock "
                "step cannot redo"
            )


__all__ = [
    "ComputeFn",
    "HistoryMismatchError",
    "Lockstep",
    "LockstepStoppedError",
    "ReplayedRecord",
    "RoundReport",
    "RunResult",
    "configured",
    "default_max_rounds",
    "line_text",
    "replay_async",
    "run_lockstep",
    "run_reach",
    "start_lockstep",
]
