"""The pure parts of `fatswarm hunt`: drawing a candidate run from the hunt's seed, running it in
lock step and classifying how it failed (replaying a failure's case and shrinking it is
`deploy/hunt/shrink.py`). No printing, no processes: `deploy/hunt/pool.py` runs these in workers.

The engine is a seeded random search with a greedy delta-debugging shrinker; docs/hunt.md says
why it is not Hypothesis.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from fatswarm.agent.geometry import sec, target_radius
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.config import DEFAULT_A, input_errors
from fatswarm.deploy.scenarios.adversarial import (
    DEFAULT_FAMILIES,
    FAMILIES,
    adversarial_start,
    family_range,
)
from fatswarm.deploy.scenarios.starts import KINDS as RANDOM_KINDS
from fatswarm.deploy.scenarios.starts import overlapping_pair, random_start
from fatswarm.deploy.sweep.grid import ParamText, SweepInputError, sweep_schedulers
from fatswarm.domain import tolerance
from fatswarm.domain.figures import first_failure
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import PAPER_MODEL, Bodies, RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.domain.words import counted, unit
from fatswarm.world.physics import (
    InvalidConfigurationError,
    PhysicsInvariantError,
    validate_configuration,
)

if TYPE_CHECKING:
    from fatswarm.deploy.engine.lockstep import RoundReport
    from fatswarm.world.setup import WorldSetup

HUNT_STREAM: Final = 0x4B17  # keeps the hunt's draws apart from every other seeded stream
SEED_MASK: Final = 0xFFFFFFFF
SEED_BOUND: Final = 2**31  # candidate seeds are drawn below this (any run seed works)
PAPER: Final = "uniform-circle"  # the algorithm whose SEC promise is checked (docs/algorithm.md G9)

# Failure kinds, in the order a summary lists them.
COLLISION: Final = "collision"  # physics stopped a robot at contact
INVARIANT: Final = "invariant"  # overlap, or a robot left the SEC when the algorithm promises not
COMPUTE: Final = "compute"  # the algorithm's compute raised (the robot stayed): its round line's
# `failed`, whatever the run then did (a stall of failing robots is one of these, not a stall)
STALLED: Final = "stalled"  # every robot stays, the goal does not hold
MAX_ROUNDS: Final = "max_rounds"  # the round cap came first
ERROR: Final = "error"  # the run raised (the algorithm's goal, say), not a refusal of its input
KINDS: Final = (COLLISION, INVARIANT, COMPUTE, STALLED, MAX_ROUNDS, ERROR)

# The models whose rounds are semi-synchronous: every active robot looks at the same
# configuration and moves before the next round. The scripted scheduler replays such rounds. The
# paper's SEC promise (G9) is made for these only; a weaker model added to
# coordinator.schedule.NAMES (asynchronous, say) is hunted, but not held to it, unless named here.
SSYNC_ROUNDS: Final = frozenset({"fsync", "ssync", "centralized", "scripted"})

SEC_RADIUS_SLACK: Final = 1e-8  # world-grid rounding (2^-30) of an end point, with room


class HuntInputError(SweepInputError):
    """A hunt argument that cannot be used (the message says what to fix)."""


# -- what a hunt looks for --------------------------------------------------------------------


def hunt_models() -> tuple[str, ...]:
    """The schedulers (models) a hunt draws from: those of `coordinator.schedule.NAMES` that need
    no file, read there through the sweep's one reading of it (a new model is one more value)."""
    return sweep_schedulers()


def start_families() -> tuple[str, ...]:
    """Random start kinds (`deploy/scenarios/starts.py`), then the adversarial families
    (`deploy/scenarios/adversarial.py`)."""
    return (*RANDOM_KINDS, *FAMILIES)


def default_families() -> tuple[str, ...]:
    """The families a hunt draws from when none is named: every random kind and the adversarial
    families drawn by default (the newer `rows` and `stacked-rows` are named with --starts)."""
    return (*RANDOM_KINDS, *DEFAULT_FAMILIES)


def family_sizes(family: str, sizes: Sequence[int]) -> tuple[int, ...]:
    """The n of `sizes` that `family` builds."""
    if family in FAMILIES:
        lo, hi = family_range(family)
        return tuple(n for n in sizes if lo <= n <= hi)
    return tuple(n for n in sizes if n >= 1)


@dataclass(frozen=True, slots=True)
class Hunt:
    """What every run of a hunt shares: the algorithm, its parameters and the adversary; and what
    its candidates are drawn from."""

    algorithm: str = DEFAULT_ALGORITHM  # a registered name, module:attribute or file.py:attribute
    params: ParamText = ()  # canonical `--param` texts; the others take their defaults
    families: tuple[str, ...] = ()  # start families to draw from
    sizes: tuple[int, ...] = ()  # n to draw from (each family keeps the n it builds)
    models: tuple[str, ...] = ()  # schedulers to draw from
    non_rigid: float | None = None  # the adversary's delta (None: rigid moves)
    crash: int | None = None  # robots the adversary crashes (None: none)
    max_rounds: int | None = None  # None: the scheduler's default cap for each n
    robot_models: tuple[RobotModel, ...] = (PAPER_MODEL,)  # robot models to draw from
    record_views: bool = False  # a saved failure's records name what each looker saw

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
        # the whole lock-step engine: the CLI imports this module (through deploy.hunt.command)
        # to build its parser
        from fatswarm.deploy.engine.lockstep import default_max_rounds

        if self.max_rounds is not None:
            return self.max_rounds
        return default_max_rounds(n, model, non_rigid=self.non_rigid)


@dataclass(frozen=True, slots=True)
class Candidate:
    """One drawn run: the `index`-th of the hunt, its start family, n, model (scheduler), run
    seed and robot model."""

    index: int
    family: str
    n: int
    model: str
    seed: int
    robot_model: RobotModel = PAPER_MODEL


def draw_candidate(hunt: Hunt, hunt_seed: int, index: int) -> Candidate:
    """The `index`-th candidate of the hunt seeded `hunt_seed`: a function of both alone, so the
    hunt is reproducible whichever worker runs which candidate. The robot model is drawn last,
    and only from more than one: a hunt of the paper's model draws what it always drew."""
    choices = hunt.choices()
    if not choices or not hunt.models:
        raise HuntInputError("no start family builds any n of the range asked for; widen -n")
    rng = np.random.default_rng([HUNT_STREAM, hunt_seed & SEED_MASK, index])
    family, sizes = choices[int(rng.integers(len(choices)))]
    n = sizes[int(rng.integers(len(sizes)))]
    model = hunt.models[int(rng.integers(len(hunt.models)))]
    seed = int(rng.integers(SEED_BOUND))
    robot_models = hunt.robot_models
    robot_model = (
        robot_models[int(rng.integers(len(robot_models)))]
        if len(robot_models) > 1
        else robot_models[0]
    )
    return Candidate(index, family, n, model, seed, robot_model)


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
    adversary's draws), the round cap, the model it was found under (for its cap) and its robot
    model. A run under a model without semi-synchronous rounds (async) has no script (`rounds`
    None): it is replayed under that model and the same seed."""

    positions: tuple[tuple[float, float], ...]
    rounds: tuple[tuple[int, ...], ...] | None  # None: under `model` itself (not scriptable)
    after: str
    seed: int
    max_rounds: int
    model: str
    robot_model: RobotModel = PAPER_MODEL  # sight, obstruction, lights, frames

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
    return load_algorithm(ref)


def configure(hunt: Hunt, n: int) -> Configured:
    """The hunt's algorithm configured for n robots; raises AlgorithmParamsError."""
    return Configured.of(_algorithm(hunt.algorithm), n, dict(hunt.params))


def candidate_start(hunt: Hunt, candidate: Candidate) -> Points:
    """The (n, 2) start of a candidate: a random kind drawn at the algorithm's scale `a` (as
    `fatswarm run --start` draws it), or an adversarial family's start."""
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
        s = tolerance.scale(circle.radius)
        tol_at, tol_eq = tolerance.EPS_AT_REL * s, tolerance.EPS_EQ_REL * s
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


def invariants(
    hunt: Hunt, setting: Configured, model: str, robot_model: RobotModel = PAPER_MODEL
) -> list[InvariantCheck]:
    """The checks a run is held to besides physics: the SEC promise for the paper's algorithm,
    with rigid moves under a semi-synchronous model and the paper's robot model (a cut move may
    stop a detour outside the SEC, which G9 checks only at the path's end; the paper promises
    nothing to robots that see less, or share no Y axis)."""
    paper_run = hunt.non_rigid is None and robot_model.is_paper
    if setting.name == PAPER and paper_run and model in SSYNC_ROUNDS:
        return [sec_invariant(setting)]
    return []


def overlap(positions: Points) -> str | None:
    """A pair of discs that overlap (physics guarantees none; checked all the same)."""
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
    robot_model: RobotModel = PAPER_MODEL,
    settings: WorldSetup | None = None,
) -> Outcome:
    """Run one start under `scheduler` and `robot_model` in lock step and classify it.

    The first collision or broken invariant (overlap, the SEC promise) is the failure, at its
    round (a collision first within one round: an invariant after a stopped move means
    nothing); with `stop_early` the run stops there. Otherwise a stalled run or one past its cap
    is the failure; a run formed with no collision is none. A start or parameters the algorithm
    or the supported range refuse is `refused`, not a failure; once running, an overlap physics
    raises is an INVARIANT failure, anything else the run raises an ERROR failure. `record`: a
    journal to write the run to (`world.record.RecordWriter`; with the hunt's `record_views`, what
    each looker saw). `settings`: the run's settings whole (a saved case's replay: its header says
    how it was made), in place of the hunt's adversary and `robot_model`.
    """
    # the whole lock-step engine: the CLI imports this module (through deploy.hunt.command)
    # to build its parser
    from fatswarm.deploy.engine.lockstep import run_lockstep

    try:  # the input first: refused here, it is no failure
        setting = configure(hunt, len(positions))
        points = robot_model.bodies is Bodies.POINTS
        setting.check_start(validate_configuration(positions, bodies_are_points=points))
    except input_errors() as exc:
        return Outcome(None, refused=f"{type(exc).__name__}: {exc}")
    watch = _RoundWatch(
        invariants(hunt, setting, model, robot_model), positions, stop_early, points, unit(model)
    )
    try:
        result = run_lockstep(
            positions,
            setting,
            scheduler,
            seed=seed,
            max_rounds=max_rounds,
            on_round=watch.on_round,
            algorithm_ref=hunt.algorithm,
            non_rigid=hunt.non_rigid,
            crash=hunt.crash,
            record=record,
            robot_model=robot_model,
            record_views=hunt.record_views and record is not None,
            settings=settings,
        )
    except _Found as stop:
        return Outcome(stop.failure, tuple(watch.active), rounds=len(watch.active))
    except (InvalidConfigurationError, PhysicsInvariantError) as exc:  # physics saw an overlap
        return watch.raised(INVARIANT, f"{watch.word} {len(watch.active) + 1}: {exc}")
    except Exception as exc:  # a finding: the algorithm raised where the run cannot go on
        return watch.raised(ERROR, f"{type(exc).__name__}: {exc}")
    return watch.ended(result.status, result.rounds)


class _RoundWatch:
    """The round callback of `run_case`: the active sets so far, and the first collision or broken
    invariant (raising `_Found` there with `stop_early`)."""

    def __init__(
        self,
        checks: list[InvariantCheck],
        positions: Points,
        stop_early: bool,
        points: bool = False,
        word: str = "round",
    ) -> None:
        self.checks = checks
        self.word = word  # what the run counts: "cycle" under an async model (`words.unit`)
        self.points = points  # point robots: sharing a point is no overlap
        self.stop_early = stop_early
        self.active: list[tuple[int, ...]] = []
        self.found: list[Failure] = []
        self.before = np.array(positions, dtype=np.float64)

    def on_round(self, report: RoundReport) -> None:
        self.active.append(tuple(report.entry.active))
        after = report.entry.positions
        failure = self._failure(report, after)
        self.before = np.array(after, dtype=np.float64)
        if failure is not None and not self.found:
            self.found.append(failure)
            if self.stop_early:
                raise _Found(failure)

    def _failure(self, report: RoundReport, after: Points) -> Failure | None:
        if report.entry.collisions:
            hit = report.entry.collisions[0]
            return Failure(
                COLLISION,
                report.entry.round,
                f"robot {hit.robot} stopped at contact with robot {hit.other} "
                f"in {self.word} {report.entry.round}",
            )
        broken = None if self.points else overlap(after)
        for check in self.checks if broken is None else ():
            broken = check(self.before, after)
            if broken is not None:
                break
        if broken is not None:
            at = f"{self.word} {report.entry.round}"
            return Failure(INVARIANT, report.entry.round, f"{at}: {broken}")
        first = first_failure(report.entry.round, report.entry.extra)
        if first is not None:
            return Failure(COMPUTE, report.entry.round, f"the algorithm failed: {first}")
        return None

    def ended(self, status: str, rounds: int) -> Outcome:
        """The outcome of a run that ended with `status` after `rounds`: its first failure seen,
        else a stall or the cap."""
        failure = self.found[0] if self.found else _ended_failure(status, rounds, self.word)
        return Outcome(failure, tuple(self.active), status=status, rounds=rounds)

    def raised(self, kind: str, detail: str) -> Outcome:
        """The outcome of a run that raised after the rounds seen: a `kind` failure in the next."""
        rounds = len(self.active)
        return Outcome(Failure(kind, rounds + 1, detail), tuple(self.active), rounds=rounds)


def _ended_failure(status: str, rounds: int, word: str = "round") -> Failure | None:
    """The failure of a run that ended with `status` after `rounds` (None: it formed), in the
    unit the run counts (`word`: "cycle" under an async model)."""
    done = counted(rounds, word)
    if status == Status.STALLED:
        return Failure(
            STALLED, rounds, f"stalled after {done}: every robot stays, the goal does not hold"
        )
    if status == Status.MAX_ROUNDS:
        return Failure(MAX_ROUNDS, rounds, f"still running at the {word} cap ({done})")
    return None


def run_candidate(hunt: Hunt, candidate: Candidate) -> tuple[Outcome, Case | None]:
    """Run a drawn candidate under its models; with a failure, also the Case that replays it: its
    start and its rounds' active sets as a script (then fsync), its seed, its cap and its robot
    model."""
    try:
        positions = candidate_start(hunt, candidate)
        scheduler = make_scheduler(candidate.model, candidate.n, candidate.seed)
    except input_errors() as exc:
        return Outcome(None, refused=f"{type(exc).__name__}: {exc}"), None
    cap = hunt.cap(candidate.n, candidate.model)
    outcome = run_case(
        hunt,
        positions,
        scheduler,
        candidate.model,
        seed=candidate.seed,
        max_rounds=cap,
        robot_model=candidate.robot_model,
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
        candidate.robot_model,
    )
    return outcome, case


def scriptable(model: str) -> bool:
    """Whether a run under `model` is replayed exactly by a script of its rounds' active sets."""
    return model in SSYNC_ROUNDS


__all__ = [
    "COLLISION",
    "COMPUTE",
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
    "candidate_start",
    "configure",
    "default_families",
    "draw_candidate",
    "hunt_models",
    "invariants",
    "overlap",
    "run_candidate",
    "run_case",
    "sec_invariant",
    "start_families",
]
