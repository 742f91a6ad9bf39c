"""The whole run in one process: the very compute, scheduler, physics and progress of the swarm.

Each active robot Looks at the same snapshot in its own private frame (seeded X flip, as a
networked agent), the paths are mapped back to the world frame and applied at once by the physics.
By default the reference algorithm runs for a whole round at once (`SharedPlans`): the canonical
form of the configuration is made once, the plan once, and each robot gets exactly the path its
own `compute` returns (every robot would have computed those very bits). A `compute` passed in is
called once per robot and Look, on its own shuffled view.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from fatswarm.agent.algorithm import Plan, plan
from fatswarm.agent.canonical import SharedForm
from fatswarm.agent.frames import draw_flip, path_to_world, to_local
from fatswarm.agent.params import Params
from fatswarm.agent.path import STAY, Path, Points
from fatswarm.agent.tolerance import check_supported
from fatswarm.coordinator.schedule import Scheduler
from fatswarm.world.physics import RoundOutcome, apply_round, validate_configuration
from fatswarm.world.progress import Progress, ProgressTracker
from fatswarm.world.record import RecordWriter, RoundEntry

LOOK_STREAM: Final = 0x100C  # orders the others in a robot's view (compute must ignore the order)

# Default round cap = ROUNDS_PER_STEP[scheduler] * (n + STEP_SLACK). The algorithm needs about
# n + 2 sequential steps (one mover or one mirror pair each); a step costs 1 round under fsync,
# about 2 under ssync (p = 1/2), about n under centralized; the caps leave a factor 10 or more.
STEP_SLACK: Final = 10
ROUNDS_PER_STEP: Final = {"fsync": 10, "ssync": 40}  # others (centralized, scripted): 10 n

ComputeFn = Callable[[Points, Params], Path]
SHARED_PLANS: Final = 8  # canonical forms remembered: a round has one; ssync revisits a few


class SharedPlans:
    """The reference algorithm for all the robots of a round at once, exactly as each computes it.

    Every robot's own `algorithm.compute` puts its view in canonical form (the same bits for all,
    agent/canonical.py) and plans there. This makes the canonical form once a round
    (`SharedForm`), the plan once per distinct canonical form, and hands each robot its part in
    its own frame: the very paths the robots' own computations return, without n of them.
    """

    def __init__(self, size: int = SHARED_PLANS) -> None:
        self._plans: OrderedDict[tuple[bytes, Params], Plan] = OrderedDict()
        self._size = size
        self.planned = 0  # how many plans were actually made (the rest were shared)

    def plan_of(self, form: SharedForm, params: Params) -> Plan:
        """The plan of the configuration `form` (made at most once while remembered)."""
        key = (form.key(), params)
        made = self._plans.get(key)
        if made is None:
            made = plan(form.points, params)
            self.planned += 1
            self._plans[key] = made
            if len(self._plans) > self._size:
                self._plans.popitem(last=False)
        return made

    def path(self, form: SharedForm, made: Plan, robot: int, flip: bool) -> Path:
        """Robot `robot`'s path in its own frame: what `algorithm.compute` returns it."""
        canon = form.for_robot(robot, flip)
        return canon.to_frame(made.moves.get(canon.observer, STAY))


class HistoryMismatchError(ValueError):
    """Committed rounds to resume from that this run would not have produced."""


def default_max_rounds(n: int, scheduler: str) -> int:
    """A round cap far above what a correct run needs under `scheduler` (see ROUNDS_PER_STEP)."""
    per_step = ROUNDS_PER_STEP.get(scheduler, 10 * max(1, n))
    return per_step * (n + STEP_SLACK)


@dataclass(frozen=True, slots=True)
class RoundReport:
    """What happened in one committed round (world frame), for callbacks such as a dashboard."""

    round: int
    active: tuple[int, ...]
    paths: dict[int, Path]
    outcome: RoundOutcome
    progress: Progress


@dataclass(frozen=True, slots=True)
class RunResult:
    """How a run ended and what it cost. Positions are (n, 2), world frame."""

    status: str
    rounds: int
    epochs: int
    moves: int
    total_distance: float
    collisions: int
    looks: int
    initial: Points
    positions: Points
    moves_by_robot: tuple[int, ...]


def run_lockstep(
    initial: Points,
    params: Params,
    scheduler: Scheduler,
    *,
    seed: int,
    max_rounds: int | None = None,
    record: RecordWriter | None = None,
    on_round: Callable[[RoundReport], None] | None = None,
    compute: ComputeFn | None = None,
    history: Sequence[RoundEntry] | None = None,
) -> RunResult:
    """Run until formed, stalled or `max_rounds` (default `default_max_rounds`).

    `seed` fixes the robots' private frames and view orders; the scheduler carries its own seed.
    `compute` defaults to the reference algorithm, run for the whole round at once (`SharedPlans`).
    `history`: resume a run from `initial` after these committed rounds (a record's, maybe none):
    they are replayed into the scheduler, the view orders and the progress, as the networked
    coordinator and world replay them after a restart, and not recorded again (nor the header);
    the run then goes on exactly as it would have without the break.
    Raises InvalidConfigurationError for an invalid start, UnsupportedInputError outside the
    supported range (agent/tolerance.py), ValueError if n disagrees with params,
    HistoryMismatchError for a history this run would not have produced.
    """
    positions = validate_configuration(initial)  # a fresh float64 copy, on the grid
    shared = SharedPlans()
    n = len(positions)
    if n != params.n:
        raise ValueError(f"the start has {n} robots but params say n={params.n}")
    check_supported(positions, params.a)
    cap = default_max_rounds(n, scheduler.name) if max_rounds is None else max_rounds
    tracker = ProgressTracker(n, params.a, cap)
    flips = [draw_flip(seed, robot) for robot in range(n)]
    look_rng = np.random.default_rng([LOOK_STREAM, seed & 0xFFFFFFFF])
    everyone = list(range(n))
    initial_copy = positions.copy()
    looks = 0
    if record is not None and history is None:
        record.header(n, params.a, seed, scheduler.name, positions, max_rounds=cap)

    round_no = 0
    if history is not None:
        positions, looks = _replay(history, positions, scheduler, tracker)
        round_no = len(history)
        if compute is not None:
            for _ in range(looks):  # each Look drew one order of the others
                look_rng.permutation(n - 1)
    while not tracker.done:
        round_no += 1
        active = scheduler.active(round_no, everyone)
        paths: dict[int, Path] = {}
        if compute is None and active:
            form = SharedForm.of(positions)
            made = shared.plan_of(form, params)
        for robot in active:
            me = positions[robot]
            if compute is None:
                path_local = shared.path(form, made, robot, flips[robot])
            else:
                order = look_rng.permutation(n - 1)
                order[order >= robot] += 1  # a shuffled order of everyone but `robot`
                path_local = compute(to_local(positions[order], me, flips[robot]), params)
            looks += 1
            if path_local:
                paths[robot] = path_to_world(path_local, (float(me[0]), float(me[1])), flips[robot])
        outcome = apply_round(positions, paths) if paths else RoundOutcome(positions.copy())
        tracker.observe(
            active,
            paths.keys(),
            positions,
            outcome.positions,
            outcome.traveled,
            len(outcome.collisions),
        )
        if record is not None:
            moves = {r: (p, outcome.traveled.get(r, 0.0)) for r, p in paths.items()}
            record.round(round_no, active, moves, outcome.positions, outcome.collisions)
        positions = np.asarray(outcome.positions, dtype=np.float64)
        if on_round is not None:
            on_round(RoundReport(round_no, tuple(active), paths, outcome, tracker.snapshot()))

    progress = tracker.snapshot()
    assert progress.status is not None
    if record is not None:
        record.result(
            progress.status,
            progress.rounds,
            positions,
            epochs=progress.epochs,
            moves=progress.moves,
            total_distance=progress.total_distance,
            collisions=progress.collisions,
        )
    return RunResult(
        status=progress.status,
        rounds=progress.rounds,
        epochs=progress.epochs,
        moves=progress.moves,
        total_distance=progress.total_distance,
        collisions=progress.collisions,
        looks=looks,
        initial=initial_copy,
        positions=positions,
        moves_by_robot=progress.moves_by_robot,
    )


def _replay(
    history: Sequence[RoundEntry], initial: Points, scheduler: Scheduler, tracker: ProgressTracker
) -> tuple[Points, int]:
    """Advance `scheduler` and `tracker` over the committed rounds `history` from `initial`, as
    the uninterrupted run did (every robot live); the positions after them and the Looks taken.

    Raises HistoryMismatchError where a round is not what this run would have done there.
    """
    everyone = list(range(len(initial)))
    positions, looks = initial, 0
    for round_no, entry in enumerate(history, start=1):
        if entry.round != round_no:
            raise HistoryMismatchError(f"round {entry.round} comes where round {round_no} should")
        if tracker.done:
            raise HistoryMismatchError(f"round {round_no} follows the end of the run "
                                       f"({tracker.status} after round {round_no - 1})")
        timed_out = entry.extra.get("timed_out")
        if timed_out:
            raise HistoryMismatchError(f"round {round_no}: robots {timed_out} timed out, which "
                                       "never happens in lock step")
        active = scheduler.active(round_no, everyone)
        if list(entry.active) != active:
            raise HistoryMismatchError(f"round {round_no} activated robots {list(entry.active)} "
                                       f"where this {scheduler.name} schedule activates {active}")
        after = np.asarray(entry.positions, dtype=np.float64)
        traveled = {m.robot: m.traveled for m in entry.moves}  # by robot, as the round summed it
        tracker.observe(active, traveled.keys(), positions, after, traveled,
                        len(entry.collisions))
        positions, looks = after, looks + len(active)
    return positions, looks


__all__ = [
    "ComputeFn",
    "HistoryMismatchError",
    "RoundReport",
    "RunResult",
    "SharedPlans",
    "default_max_rounds",
    "run_lockstep",
]
