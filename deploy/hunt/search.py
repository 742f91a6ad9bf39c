"""The pure parts of `fatswarm hunt`: drawing a candidate run from the hunt's seed, running it in
lock step and classifying how it failed, and shrinking a failure to a small case that a scripted
schedule replays exactly. No printing, no processes: `deploy/hunt/pool.py` runs these in workers.

The engine is a seeded random search with a greedy delta-debugging shrinker; docs/hunt.md says
why it is not Hypothesis.
"""

from __future__ import annotations

import os
import shlex
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any, Final

import numpy as np

from fatswarm.deploy.sweep.grid import ParamText, SweepInputError
from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.seam import Configured

HUNT_STREAM: Final = 0x4B17  # keeps the hunt's draws apart from every other seeded stream
SEED_MASK: Final = 0xFFFFFFFF
SEED_BOUND: Final = 2**31  # candidate seeds are drawn below this (any run seed works)
PAPER: Final = "uniform-circle"  # the algorithm whose SEC promise is checked (docs/algorithm.md G9)

# Failure kinds, in the order a summary lists them.
COLLISION: Final = "collision"  # physics stopped a robot at contact
INVARIANT: Final = "invariant"  # overlap, or a robot left the SEC when the algorithm promises not
STALLED: Final = "stalled"  # every robot stays, the goal does not hold
MAX_ROUNDS: Final = "max_rounds"  # the round cap came first
ERROR: Final = "error"  # the run raised (the algorithm's goal, say), not a refusal of its input
KINDS: Final = (COLLISION, INVARIANT, STALLED, MAX_ROUNDS, ERROR)

# The models whose rounds are semi-synchronous: every active robot looks at the same
# configuration and moves before the next round. The scripted scheduler replays such rounds. The
# paper's SEC promise (G9) is made for these only; a weaker model added to
# coordinator.schedule.NAMES (asynchronous, say) is hunted, but not held to it, unless named here.
SSYNC_ROUNDS: Final = frozenset({"fsync", "ssync", "centralized", "scripted"})

DEFAULT_SHRINK_RUNS: Final = 200  # runs one failure's shrinking may take
SEED_TRIES: Final = (0, 1, 2, 3)  # simpler run seeds the shrinker tries
DECIMAL_TRIES: Final = (0, 1, 2, 3, 4, 6)  # decimals the shrinker rounds coordinates to
MAX_DECIMALS: Final = 17  # repr of a double never needs more
# Shrinking a failure that shows in round k runs each proposal to FACTOR k + SLACK rounds only.
HORIZON_FACTOR: Final = 2
HORIZON_SLACK: Final = 10
ROUND_DROP_LIMIT: Final = 48  # scripts this long or shorter also have single rounds dropped
SEC_RADIUS_SLACK: Final = 1e-8  # world-grid rounding (2^-30) of an end point, with room


class HuntInputError(SweepInputError):
    """A hunt argument that cannot be used (the message says what to fix)."""


# -- what a hunt looks for --------------------------------------------------------------------


def hunt_models() -> tuple[str, ...]:
    """The schedulers (models) a hunt draws from: those of `coordinator.schedule.NAMES` that need
    no file, read there through the sweep's one reading of it (a new model is one more value)."""
    from fatswarm.deploy.sweep.grid import sweep_schedulers

    return sweep_schedulers()


def start_families() -> tuple[str, ...]:
    """Random start kinds (`deploy/scenarios/starts.py`), then the adversarial families
    (`deploy/scenarios/adversarial.py`)."""
    from fatswarm.deploy.scenarios.adversarial import FAMILIES
    from fatswarm.deploy.scenarios.starts import KINDS as RANDOM_KINDS

    return (*RANDOM_KINDS, *FAMILIES)


def family_sizes(family: str, sizes: Sequence[int]) -> tuple[int, ...]:
    """The n of `sizes` that `family` builds."""
    from fatswarm.deploy.scenarios.adversarial import FAMILIES, family_range

    if family in FAMILIES:
        lo, hi = family_range(family)
        return tuple(n for n in sizes if lo <= n <= hi)
    return tuple(n for n in sizes if n >= 1)


@dataclass(frozen=True, slots=True)
class Hunt:
    """What every run of a hunt shares: the algorithm, its parameters and the adversary."""

    algorithm: str = DEFAULT_ALGORITHM  # a registered name, module:attribute or file.py:attribute
    params: ParamText = ()  # canonical `--param` texts; the others take their defaults
    families: tuple[str, ...] = ()  # start families to draw from
    sizes: tuple[int, ...] = ()  # n to draw from (each family keeps the n it builds)
    models: tuple[str, ...] = ()  # schedulers to draw from
    non_rigid: float | None = None  # the adversary's delta (None: rigid moves)
    crash: int | None = None  # robots the adversary crashes (None: none)
    max_rounds: int | None = None  # None: the scheduler's default cap for each n

    def choices(self) -> list[tuple[str, tuple[int, ...]]]:
        """(family, the n it may be drawn with) for every family that has one: sizes the family
        builds, above the crash count (a crash needs a survivor)."""
        least = (self.crash or 0) + 1
        out = []
        for family in self.families:
            usable = tuple(n for n in family_sizes(family, self.sizes) if n >= max(least, 2))
            if usable:
                out.append((family, usable))
        return out

    def cap(self, n: int, model: str) -> int:
        """The round cap of a run of n robots drawn under `model`."""
        from fatswarm.deploy.engine.lockstep import default_max_rounds

        return self.max_rounds if self.max_rounds is not None else default_max_rounds(n, model)


@dataclass(frozen=True, slots=True)
class Candidate:
    """One drawn run: the `index`-th of the hunt, its start family, n, model and run seed."""

    index: int
    family: str
    n: int
    model: str
    seed: int


def draw_candidate(hunt: Hunt, hunt_seed: int, index: int) -> Candidate:
    """The `index`-th candidate of the hunt seeded `hunt_seed`: a function of both alone, so the
    hunt is reproducible whichever worker runs which candidate."""
    choices = hunt.choices()
    if not choices or not hunt.models:
        raise HuntInputError("no start family builds any n of the range asked for; widen -n")
    rng = np.random.default_rng([HUNT_STREAM, hunt_seed & SEED_MASK, index])
    family, sizes = choices[int(rng.integers(len(choices)))]
    n = sizes[int(rng.integers(len(sizes)))]
    model = hunt.models[int(rng.integers(len(hunt.models)))]
    return Candidate(index, family, n, model, int(rng.integers(SEED_BOUND)))


# -- one run and its failure -------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Failure:
    """How a run failed: its kind (KINDS), the round it showed in (the last for a stall or the
    cap; 0 before any round) and what happened, in words."""

    kind: str
    round: int
    detail: str


@dataclass(frozen=True, slots=True)
class Case:
    """A run replayed exactly: the start, the active sets of the first rounds (`after` the
    script: "fsync" or "repeat"), the run seed (the private frames, view orders and the
    adversary's draws), the round cap, and the model it was found under (for its cap). A run
    under a model without semi-synchronous rounds (async) has no script (`rounds` None): it is
    replayed under that model and the same seed."""

    positions: tuple[tuple[float, float], ...]
    rounds: tuple[tuple[int, ...], ...] | None  # None: under `model` itself (not scriptable)
    after: str
    seed: int
    max_rounds: int
    model: str

    @property
    def n(self) -> int:
        return len(self.positions)

    def points(self) -> Points:
        return np.array(self.positions, dtype=np.float64).reshape(-1, 2)


@dataclass(frozen=True, slots=True)
class Outcome:
    """A run's failure (None: it formed cleanly), its rounds' active sets as far as it ran (a
    run stops at its first collision or broken invariant), and whether its input was refused."""

    failure: Failure | None
    active: tuple[tuple[int, ...], ...] = ()
    refused: str = ""  # the refusal of the start or parameters (then no failure)
    status: str = ""  # the run's status, when it ran to its end
    rounds: int = 0


class _Found(Exception):
    """Raised from the round callback to stop a run at its first collision or broken invariant:
    what follows cannot change the failure's kind."""

    def __init__(self, failure: Failure) -> None:
        super().__init__(failure.detail)
        self.failure = failure


@lru_cache(maxsize=8)
def _algorithm(ref: str) -> Any:
    from fatswarm.domain.registry import load_algorithm

    return load_algorithm(ref)


def configure(hunt: Hunt, n: int) -> Configured:
    """The hunt's algorithm configured for n robots; raises AlgorithmParamsError."""
    return Configured.of(_algorithm(hunt.algorithm), n, dict(hunt.params))


def candidate_start(hunt: Hunt, candidate: Candidate) -> Points:
    """The (n, 2) start of a candidate: a random kind drawn at the algorithm's scale `a` (as
    `fatswarm run --start` draws it), or an adversarial family's start."""
    from fatswarm.deploy.engine.config import DEFAULT_A
    from fatswarm.deploy.scenarios.adversarial import FAMILIES, adversarial_start
    from fatswarm.deploy.scenarios.starts import random_start

    if candidate.family in FAMILIES:
        return adversarial_start(candidate.family, candidate.n, candidate.seed)
    scale = configure(hunt, candidate.n).values.get("a", DEFAULT_A)
    assert isinstance(scale, (int, float))
    return random_start(candidate.n, candidate.seed, candidate.family, float(scale))


InvariantCheck = Callable[[Points, Points], str | None]


def sec_invariant(setting: Configured) -> InvariantCheck:
    """The paper's algorithm's promise about the smallest enclosing circle, as a check of one
    round (positions before, after): once the SEC's radius r_c is at least the target radius r
    (FormUCircle), a move is made only if the SEC after it equals the current one within EPS_AT
    and its radius stays >= r - EPS_EQ (docs/algorithm.md G9, for every subset SSYNC activates).
    So no robot ends a round farther than r_c + 2 EPS_AT from the current centre, and the swarm
    never falls back to expansion. Expansion rounds (r_c < r) move leaders out of the SEC on
    purpose and are not checked. The slack adds the world grid's rounding of end points."""
    from fatswarm.agent.geometry import sec, target_radius
    from fatswarm.domain.tolerance import EPS_AT_REL, EPS_EQ_REL, scale

    a = setting.values.get("a")
    assert isinstance(a, float)
    r = target_radius(setting.n, a)

    def check(before: Points, after: Points) -> str | None:
        if len(before) < 2:
            return None
        # relative to one robot, as the robots see it: exact on the grid, and `sec` of absolute
        # coordinates near 1e6 can miss a point (a triangle of side 4 at (4.4e5, 9.7e5) gave
        # radius 2 where 4/sqrt(3) is right)
        origin = before[0].copy()
        before, after = before - origin, after - origin
        circle = sec(before)
        if circle.radius < r:  # expansion (or within rounding of its threshold)
            return None
        s = scale(circle.radius)
        tol_at, tol_eq = EPS_AT_REL * s, EPS_EQ_REL * s
        cx, cy = circle.center
        dist = np.hypot(after[:, 0] - cx, after[:, 1] - cy)
        worst = int(np.argmax(dist))
        if dist[worst] > circle.radius + 2.0 * tol_at + SEC_RADIUS_SLACK:
            return (
                f"robot {worst} left the SEC in FormUCircle: {dist[worst]:.9g} from its "
                f"centre, radius {circle.radius:.9g} (G9 keeps it within 2 EPS_AT)"
            )
        new = sec(after)
        if new.radius < r - tol_eq - SEC_RADIUS_SLACK:
            return (
                f"the SEC shrank to radius {new.radius:.9g} below r = {r:.9g} in FormUCircle "
                "(G9: the swarm must not fall back to expansion)"
            )
        return None

    return check


def invariants(hunt: Hunt, setting: Configured, model: str) -> list[InvariantCheck]:
    """The checks a run is held to besides physics: the SEC promise for the paper's algorithm,
    with rigid moves under a semi-synchronous model (the paper's; a cut move may stop a detour
    outside the SEC, which G9 checks only at the path's end)."""
    if setting.name == PAPER and hunt.non_rigid is None and model in SSYNC_ROUNDS:
        return [sec_invariant(setting)]
    return []


def overlap(positions: Points) -> str | None:
    """A pair of discs that overlap (physics guarantees none; checked all the same)."""
    from fatswarm.deploy.scenarios.starts import overlapping_pair

    pair = overlapping_pair(positions)
    if pair is None:
        return None
    i, j, dist = pair
    return f"robots {i} and {j} overlap: centres {dist:.12g} apart"


def run_case(
    hunt: Hunt,
    positions: Points,
    scheduler: Any,
    model: str,
    *,
    seed: int,
    max_rounds: int,
    stop_early: bool = True,
    record: Any = None,
    header_extra: dict[str, Any] | None = None,
) -> Outcome:
    """Run one start under `scheduler` in lock step and classify it.

    The first collision or broken invariant (overlap, the SEC promise) is the failure, at its
    round (a collision first within one round: an invariant after a stopped move means
    nothing); with `stop_early` the run stops there. Otherwise a stalled run or one past its cap
    is the failure; a run formed with no collision is none. A start or parameters the algorithm
    or the supported range refuse is `refused`, not a failure; once running, an overlap physics
    raises is an INVARIANT failure, anything else the run raises an ERROR failure. `record`: a
    journal to write the run to (`world.record.RecordWriter`), with `header_extra` in its header.
    """
    from fatswarm.deploy.engine.config import input_errors
    from fatswarm.deploy.engine.lockstep import RoundReport, run_lockstep
    from fatswarm.domain.outcome import Status
    from fatswarm.world.physics import (
        InvalidConfigurationError,
        PhysicsInvariantError,
        validate_configuration,
    )

    active: list[tuple[int, ...]] = []
    found: list[Failure] = []
    try:  # the input first: refused here, it is no failure
        setting = configure(hunt, len(positions))
        setting.check_start(validate_configuration(positions))
    except input_errors() as exc:
        return Outcome(None, refused=f"{type(exc).__name__}: {exc}")
    checks = invariants(hunt, setting, model)
    before = [np.array(positions, dtype=np.float64)]

    def on_round(report: RoundReport) -> None:
        active.append(tuple(report.active))
        after = report.outcome.positions
        failure = None
        if report.outcome.collisions:
            hit = report.outcome.collisions[0]
            failure = Failure(
                COLLISION,
                report.round,
                f"robot {hit.robot} stopped at contact with robot {hit.other} "
                f"in round {report.round}",
            )
        else:
            broken = overlap(after)
            for check in checks if broken is None else ():
                broken = check(before[0], after)
                if broken is not None:
                    break
            if broken is not None:
                failure = Failure(INVARIANT, report.round, f"round {report.round}: {broken}")
        before[0] = np.array(after, dtype=np.float64)
        if failure is not None and not found:
            found.append(failure)
            if stop_early:
                raise _Found(failure)

    try:
        result = run_lockstep(
            positions,
            setting,
            scheduler,
            seed=seed,
            max_rounds=max_rounds,
            on_round=on_round,
            algorithm_ref=hunt.algorithm,
            non_rigid=hunt.non_rigid,
            crash=hunt.crash,
            record=record,
            header_extra=header_extra,
        )
    except _Found as stop:
        return Outcome(stop.failure, tuple(active), rounds=len(active))
    except (InvalidConfigurationError, PhysicsInvariantError) as exc:  # physics saw an overlap
        return Outcome(
            Failure(INVARIANT, len(active) + 1, f"round {len(active) + 1}: {exc}"),
            tuple(active),
            rounds=len(active),
        )
    except Exception as exc:  # a finding: the algorithm raised where the run cannot go on
        return Outcome(
            Failure(ERROR, len(active) + 1, f"{type(exc).__name__}: {exc}"),
            tuple(active),
            rounds=len(active),
        )
    if found:
        return Outcome(found[0], tuple(active), status=result.status, rounds=result.rounds)
    failure = None
    if result.status == Status.STALLED:
        failure = Failure(
            STALLED,
            result.rounds,
            f"stalled after {result.rounds} rounds: every robot stays, the goal does not hold",
        )
    elif result.status == Status.MAX_ROUNDS:
        failure = Failure(
            MAX_ROUNDS, result.rounds, f"still running at the round cap ({result.rounds} rounds)"
        )
    return Outcome(failure, tuple(active), status=result.status, rounds=result.rounds)


def run_candidate(hunt: Hunt, candidate: Candidate) -> tuple[Outcome, Case | None]:
    """Run a drawn candidate under its model; with a failure, also the Case that replays it: its
    start and its rounds' active sets as a script (then fsync), its seed and its cap."""
    from fatswarm.coordinator.schedule import make_scheduler
    from fatswarm.deploy.engine.config import input_errors

    try:
        positions = candidate_start(hunt, candidate)
        scheduler = make_scheduler(candidate.model, candidate.n, candidate.seed)
    except input_errors() as exc:
        return Outcome(None, refused=f"{type(exc).__name__}: {exc}"), None
    cap = hunt.cap(candidate.n, candidate.model)
    outcome = run_case(
        hunt, positions, scheduler, candidate.model, seed=candidate.seed, max_rounds=cap
    )
    if outcome.failure is None:
        return outcome, None
    rounds = (
        (outcome.active or (tuple(range(candidate.n)),)) if scriptable(candidate.model) else None
    )
    case = Case(
        tuple((float(x), float(y)) for x, y in positions),
        rounds,
        "fsync",
        candidate.seed,
        cap,
        candidate.model,
    )
    return outcome, case


def scriptable(model: str) -> bool:
    """Whether a run under `model` is replayed exactly by a script of its rounds' active sets."""
    return model in SSYNC_ROUNDS


def replay(
    hunt: Hunt,
    case: Case,
    *,
    stop_early: bool = True,
    record: Any = None,
    max_rounds: int | None = None,
) -> Outcome:
    """Run a Case under its scripted schedule (or its own model, when it has no script), up to
    its cap or the lower `max_rounds`."""
    from fatswarm.coordinator.schedule import Scripted, make_scheduler

    if case.rounds is None:
        scheduler: Any = make_scheduler(case.model, case.n, case.seed)
        model = case.model
    else:
        scheduler, model = Scripted(case.rounds, case.after), "scripted"
    cap = case.max_rounds if max_rounds is None else min(max_rounds, case.max_rounds)
    return run_case(
        hunt,
        case.points(),
        scheduler,
        model,
        seed=case.seed,
        max_rounds=cap,
        stop_early=stop_early,
        record=record,
    )


# -- shrinking ---------------------------------------------------------------------------------


@dataclass(slots=True)
class Shrunk:
    """A shrinking's result: the smallest case found that fails with the same kind, its failure,
    the runs it took, and whether the unshrunk case replayed at all under its script."""

    case: Case
    failure: Failure
    runs: int
    reproduced: bool
    steps: list[str] = field(default_factory=list)  # the shrink steps taken, in order


def decimals(value: float) -> int:
    """The fewest decimals that write `value` exactly (17 for most grid values)."""
    for places in range(MAX_DECIMALS):
        if round(value, places) == value:
            return places
    return MAX_DECIMALS


def case_decimals(case: Case) -> int:
    """The most decimals any coordinate of the case needs."""
    return max((decimals(v) for p in case.positions for v in p), default=0)


def _cap_for(hunt: Hunt, case: Case, n: int) -> int:
    """A shrunk case's cap: the hunt's `--max-rounds`, or the default of its model for its n
    (so a case past its cap is past the cap that model would give its n robots)."""
    return hunt.cap(n, case.model)


def drop_robots(hunt: Hunt, case: Case, robots: Sequence[int]) -> Case | None:
    """The case without `robots`: the others renumbered in order, the script's sets likewise
    (rounds left empty are dropped); None if too few robots would remain."""
    gone = set(robots)
    keep = [i for i in range(case.n) if i not in gone]
    if len(keep) < max(2, (hunt.crash or 0) + 1):
        return None
    number = {old: new for new, old in enumerate(keep)}
    rounds = (
        None
        if case.rounds is None
        else tuple(
            sets
            for sets in (tuple(number[r] for r in rnd if r in number) for rnd in case.rounds)
            if sets
        )
        or (tuple(range(len(keep))),)
    )
    return replace(
        case,
        positions=tuple(case.positions[i] for i in keep),
        rounds=rounds,
        max_rounds=_cap_for(hunt, case, len(keep)),
    )


def _fewer_robots(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    """Drop halves, quarters... then single robots (delta debugging's complements)."""
    size = case.n // 2
    while size >= 1:
        for lo in range(0, case.n, size):
            smaller = drop_robots(hunt, case, range(lo, min(lo + size, case.n)))
            if smaller is not None:
                yield f"dropped robots {lo}..{min(lo + size, case.n) - 1}", smaller
        size //= 2


def _shorter_schedule(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    """fsync from the start; then the script cut to its first 1, 2, 4... rounds (then fsync);
    then, for a short script, single rounds dropped or made fsync rounds."""
    del hunt
    if case.rounds is None:
        return
    everyone = tuple(range(case.n))
    if case.rounds != (everyone,) or case.after != "fsync":
        yield "fsync from round 1", replace(case, rounds=(everyone,), after="fsync")
    length = len(case.rounds)
    keep = 1
    while keep < length:
        yield (
            f"first {keep} rounds, then fsync",
            replace(case, rounds=case.rounds[:keep], after="fsync"),
        )
        keep *= 2
    if 1 < length <= ROUND_DROP_LIMIT:
        for k in range(length):
            yield (
                f"dropped round {k + 1}",
                replace(case, rounds=case.rounds[:k] + case.rounds[k + 1 :]),
            )
        for k in range(length):
            if case.rounds[k] != everyone:
                yield (
                    f"round {k + 1} all active",
                    replace(case, rounds=(*case.rounds[:k], everyone, *case.rounds[k + 1 :])),
                )


def _simpler_seed(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    del hunt
    for seed in SEED_TRIES:
        if seed < case.seed:
            yield f"seed {seed}", replace(case, seed=seed)


def _simpler_coordinates(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    """The swarm moved by a whole vector towards the origin; every coordinate rounded to fewer
    decimals; then each coordinate alone."""
    del hunt
    pts = case.points()
    shift = np.round(pts.mean(axis=0)) + 0.0  # + 0.0: no -0.0
    if shift.any():
        moved = pts - shift
        yield f"moved by {(0.0 - shift).tolist()}", replace(case, positions=_pairs(moved))
    most = case_decimals(case)
    for places in DECIMAL_TRIES:
        if places < most:
            yield (
                f"coordinates to {places} decimals",
                replace(case, positions=_pairs(np.round(pts, places))),
            )
    for i in range(case.n):
        for axis in (0, 1):
            value = float(pts[i, axis])
            for places in DECIMAL_TRIES:
                if places < decimals(value):
                    changed = pts.copy()
                    changed[i, axis] = round(value, places)
                    yield (
                        f"robot {i} {'xy'[axis]} to {places} decimals",
                        replace(case, positions=_pairs(changed)),
                    )
                    break


def _pairs(points: Points) -> tuple[tuple[float, float], ...]:
    return tuple((float(x) + 0.0, float(y) + 0.0) for x, y in points)  # + 0.0: no -0.0


SHRINK_STEPS: Final = (_fewer_robots, _shorter_schedule, _simpler_seed, _simpler_coordinates)


def _valid(case: Case) -> bool:
    from fatswarm.deploy.scenarios.starts import overlapping_pair

    pts = case.points()
    return bool(np.isfinite(pts).all()) and overlapping_pair(pts) is None


def shrink(hunt: Hunt, case: Case, kind: str, *, budget: int = DEFAULT_SHRINK_RUNS) -> Shrunk:
    """The smallest case found that fails with the same `kind`: greedily, fewer robots, a shorter
    script (then fsync), a smaller seed, simpler coordinates, again until a whole pass finds
    nothing or `budget` runs are spent. Deterministic: no draw, the same steps in the same order.

    The case is first replayed under its script: if that does not fail with `kind` (a model a
    script cannot replay), it is returned as it is with `reproduced` False.
    """
    first = replay(hunt, case)
    runs = 1
    if first.failure is None or first.failure.kind != kind:
        failure = first.failure or Failure(kind, 0, "not reproduced by a scripted replay")
        return Shrunk(case, failure, runs, reproduced=False)
    best, failure = _cut_after(case, first), first.failure
    taken: list[str] = []
    improved = True
    while improved and runs < budget:
        improved = False
        for step in SHRINK_STEPS:
            progress = True
            while progress and runs < budget:
                progress = False
                for what, proposal in step(hunt, best):
                    if runs >= budget:
                        break
                    if not _valid(proposal):
                        continue
                    runs += 1
                    outcome = replay(hunt, proposal, max_rounds=_horizon(failure))
                    if outcome.failure is not None and outcome.failure.kind == kind:
                        best, failure = _cut_after(proposal, outcome), outcome.failure
                        taken.append(what)
                        progress = improved = True
                        break
    return Shrunk(best, failure, runs, reproduced=True, steps=taken)


def _horizon(failure: Failure) -> int | None:
    """How far a proposal is run while shrinking a failure that shows in a round (a collision,
    an invariant, an error): a little past where the best case so far fails. A proposal failing
    later is passed over (a smaller shrink, never a wrong one: a run's rounds before its cap do
    not depend on the cap); it saves running every proposal that does not fail to its cap."""
    if failure.kind in (COLLISION, INVARIANT, ERROR):
        return HORIZON_FACTOR * failure.round + HORIZON_SLACK
    return None


def _cut_after(case: Case, outcome: Outcome) -> Case:
    """A case failing by a collision or an invariant needs no script past its failing round."""
    assert outcome.failure is not None
    if (
        case.rounds is not None
        and outcome.failure.kind in (COLLISION, INVARIANT)
        and (0 < outcome.failure.round < len(case.rounds))
    ):
        return replace(case, rounds=case.rounds[: outcome.failure.round])
    return case


# -- the files of a failure ---------------------------------------------------------------------


def start_data(hunt: Hunt, case: Case) -> dict[str, Any]:
    """The `--init` file of a case: `{"positions": [[x, y], ...]}`, with the side `a` when the
    algorithm has one (what `world.starts.load_init` reads)."""
    data: dict[str, Any] = {"positions": [[x, y] for x, y in case.positions]}
    a = configure(hunt, case.n).values.get("a")
    if a is not None:
        data["a"] = a
    return data


def schedule_data(case: Case) -> dict[str, Any] | None:
    """The `--schedule` file of a case (what `coordinator.schedule.load_script` reads); None for
    a case replayed under its own model."""
    if case.rounds is None:
        return None
    return {"rounds": [list(r) for r in case.rounds], "after": case.after}


def replay_argv(
    hunt: Hunt, case: Case, folder: str = ".", record: str = "replay.jsonl"
) -> list[str]:
    """`fatswarm run --lockstep` repeating the case from the files in `folder`: the same seed
    (it fixes the private frames too), cap and adversary. A file algorithm is named absolutely."""

    def inside(name: str) -> str:
        return name if folder == "." else os.path.join(folder, name)

    argv = ["fatswarm", "run", "--lockstep", "--init", inside("start.json")]
    if case.rounds is None:
        argv += ["--scheduler", case.model]
    else:
        argv += ["--scheduler", "scripted", "--schedule", inside("schedule.json")]
    argv += ["--seed", str(case.seed), "--max-rounds", str(case.max_rounds)]
    if hunt.algorithm != DEFAULT_ALGORITHM:
        argv += ["--algorithm", absolute_ref(hunt.algorithm)]
    for name, text in hunt.params:
        argv += ["--param", f"{name}={text}"]
    if hunt.non_rigid is not None:
        argv += ["--non-rigid", repr(hunt.non_rigid)]
    if hunt.crash is not None:
        argv += ["--crash", str(hunt.crash)]
    return [*argv, "--no-dashboard", "--record", inside(record), "--force"]


def absolute_ref(ref: str) -> str:
    """`path/file.py:attribute` with an absolute path (the command runs from any directory)."""
    path, sep, attr = ref.rpartition(":")
    if sep and path.endswith(".py"):
        return f"{os.path.abspath(path)}:{attr}"
    return ref


def replay_command(hunt: Hunt, case: Case) -> str:
    """The shell line that replays a saved case from inside its folder."""
    return shlex.join(replay_argv(hunt, case))


def summary_data(
    hunt: Hunt,
    hunt_seed: int,
    candidate: Candidate,
    found: Failure,
    shrunk: Shrunk,
    original: Case,
    replayed: Failure | None,
) -> dict[str, Any]:
    """summary.json: what failed, where the hunt drew it, how it was shrunk and how to replay."""
    from fatswarm import __version__

    return {
        "kind": shrunk.failure.kind,
        "detail": shrunk.failure.detail,
        "round": shrunk.failure.round,
        "replayed": None
        if replayed is None
        else {"kind": replayed.kind, "detail": replayed.detail},
        "reproduced": shrunk.reproduced,
        "found": {
            "index": candidate.index,
            "family": candidate.family,
            "n": candidate.n,
            "scheduler": candidate.model,
            "seed": candidate.seed,
            "kind": found.kind,
            "detail": found.detail,
            "round": found.round,
            "script_rounds": _length(original),
            "decimals": case_decimals(original),
        },
        "shrunk": {
            "n": shrunk.case.n,
            "script_rounds": _length(shrunk.case),
            "after": shrunk.case.after,
            "seed": shrunk.case.seed,
            "max_rounds": shrunk.case.max_rounds,
            "decimals": case_decimals(shrunk.case),
            "runs": shrunk.runs,
            "steps": shrunk.steps,
        },
        "hunt": {
            "seed": hunt_seed,
            "algorithm": hunt.algorithm,
            "params": dict(hunt.params),
            "non_rigid": hunt.non_rigid,
            "crash": hunt.crash,
        },
        "command": replay_command(hunt, shrunk.case),
        "fatswarm_version": __version__,
    }


def _length(case: Case) -> int | None:
    return None if case.rounds is None else len(case.rounds)


def folder_name(candidate: Candidate, kind: str) -> str:
    """A failure's subfolder: the candidate's index (the hunt's order) and the kind."""
    return f"{candidate.index:06d}-{kind}"


def kind_counts(kinds: Mapping[str, int]) -> str:
    """`collision 3  stalled 1`, kinds in KINDS order, the ones never seen left out."""
    return "  ".join(f"{kind} {kinds[kind]}" for kind in KINDS if kinds.get(kind))


__all__ = [
    "COLLISION",
    "ERROR",
    "INVARIANT",
    "KINDS",
    "MAX_ROUNDS",
    "SSYNC_ROUNDS",
    "STALLED",
    "Candidate",
    "Case",
    "Failure",
    "Hunt",
    "HuntInputError",
    "Outcome",
    "Shrunk",
    "absolute_ref",
    "candidate_start",
    "case_decimals",
    "configure",
    "decimals",
    "draw_candidate",
    "drop_robots",
    "folder_name",
    "hunt_models",
    "invariants",
    "kind_counts",
    "overlap",
    "replay",
    "replay_argv",
    "replay_command",
    "run_candidate",
    "run_case",
    "schedule_data",
    "sec_invariant",
    "shrink",
    "start_data",
    "start_families",
    "summary_data",
]
