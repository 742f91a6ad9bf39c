"""One run's configuration, frozen: what the CLI, the Python API and the parts are built from.

`RunConfig` holds what a user asks for (flags or keyword arguments); `resolve()` checks it and
builds the run (`RunSetup`): its settings (`world.setup.WorldSetup`, the one type the record's
header is written from and read back to: the start on the grid, the round cap, the adversary, the
model, how it was made), the algorithm configured for n robots and the scheduler. Every refusal is
one of `input_errors()`, with a message saying what to fix.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Final

import numpy as np

from fatswarm.domain.adversary import ASYNC_NAMES
from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import AXES, PAPER_MODEL, Bodies, Lights, ModelError, RobotModel
from fatswarm.domain.seam import AlgorithmError, AlgorithmParamsError, Configured, parse_assignments
from fatswarm.domain.tolerance import UnsupportedInputError, check_supported
from fatswarm.domain.version import __version__

if TYPE_CHECKING:
    from fatswarm.coordinator.schedule import Scheduler
    from fatswarm.world.record import RunRecord
    from fatswarm.world.setup import WorldSetup

DEFAULT_N: Final = 8
DEFAULT_A: Final = 4.0
DEFAULT_SCHEDULER: Final = "ssync"  # the paper's model
DEFAULT_START: Final = "clustered"  # needs SEC expansion, so every phase of the algorithm runs
DEFAULT_MOVE_TIMEOUT_S: Final = 5.0


class RunInputError(ValueError):
    """A combination of settings a run cannot use."""


@dataclass(frozen=True, slots=True, eq=False)
class RunConfig:
    """What a run is asked to be. Unset fields take the documented defaults on `resolve()`.

    The start is `positions` (an (n, 2) array), else the JSON file `init`, else a random start of
    kind `start` drawn from `seed`. `params` are the algorithm's (values or their text).
    """

    n: int | None = None
    algorithm: str = "uniform-circle"
    params: Mapping[str, object] = field(default_factory=dict)
    seed: int = 0
    start: str = DEFAULT_START
    init: str | None = None
    positions: Points | None = None
    scheduler: str = DEFAULT_SCHEDULER
    schedule: str | None = None
    fairness: int | None = None
    max_rounds: int | None = None
    non_rigid: float | None = None  # the adversary's delta: moves may stop after it (None: rigid)
    crash: int | None = None  # f robots the adversary crashes for good (None: none)
    model: RobotModel = PAPER_MODEL  # sight, obstruction, lights, frames (docs/model.md)
    record_views: bool = False  # each record line names what each looker saw
    move_timeout_s: float = DEFAULT_MOVE_TIMEOUT_S
    pace_s: float = 0.0
    command: tuple[str, ...] = ()

    @staticmethod
    def from_args(args: argparse.Namespace, seed: int) -> RunConfig:
        """The configuration `fatswarm run`'s flags ask for (`-a` is `--param a=`)."""
        params: dict[str, object] = dict(parse_assignments(list(getattr(args, "param", []) or [])))
        if getattr(args, "a", None) is not None:
            if "a" in params:
                raise RunInputError("give the side once: -a or --param a=..., not both")
            params["a"] = float(args.a)
        return RunConfig(
            n=args.n,
            algorithm=getattr(args, "algorithm", "uniform-circle"),
            params=params,
            seed=seed,
            start=args.start,
            init=args.init,
            scheduler=args.scheduler,
            schedule=args.schedule,
            fairness=args.fairness,
            max_rounds=args.max_rounds,
            non_rigid=getattr(args, "non_rigid", None),
            crash=getattr(args, "crash", None),
            model=model_from_args(args),
            record_views=bool(getattr(args, "record_views", False)),
            move_timeout_s=float(getattr(args, "move_timeout", DEFAULT_MOVE_TIMEOUT_S)),
            pace_s=float(getattr(args, "pace", None) or 0.0),
            command=tuple(getattr(args, "_argv", None) or sys.argv),
        )

    def resolve(self, *, networked: bool = False, swarm: str = "lockstep") -> RunSetup:
        """Check everything and build the run: its settings (`WorldSetup`, what the header says)
        and what they build; raises one of `input_errors()`. `networked`: the header keeps the
        move timeout; `swarm`: the swarm the world serves (a networked run's is the launcher's)."""
        # an agent imports this module (through deploy.flags), never the schedulers
        from fatswarm.coordinator.schedule import default_fairness, make_scheduler

        # the whole lock-step engine: the CLI imports this module to build its parser
        from fatswarm.deploy.engine.lockstep import default_max_rounds, run_reach

        # the world's records and physics: an agent imports this module, never them
        from fatswarm.world.setup import WorldSetup

        if self.scheduler != "scripted" and self.schedule is not None:
            raise RunInputError("--schedule only goes with --scheduler scripted")
        if self.max_rounds is not None and self.max_rounds < 1:
            raise RunInputError(f"--max-rounds must be at least 1, got {self.max_rounds}")
        check_fairness(self.fairness, self.scheduler)
        check_non_rigid(self.non_rigid)
        setting, initial = resolve_start(
            self.init,
            self.n,
            None,
            self.seed,
            self.start,
            self.algorithm,
            params=self.params,
            positions=self.positions,
            bodies_are_points=self.model.bodies is Bodies.POINTS,
        )
        n = setting.n
        scheduler = make_scheduler(self.scheduler, n, self.seed, self.schedule, self.fairness)
        reach = run_reach(setting, initial) if self.scheduler in ASYNC_NAMES else 0.0
        max_rounds = self.max_rounds or default_max_rounds(n, self.scheduler, reach, self.non_rigid)
        check_crash(self.crash, n)
        check_lights(self.model, setting)
        settings = WorldSetup(
            swarm,
            n,
            self.seed,
            self.scheduler,
            initial,
            max_rounds,
            algorithm=self.algorithm,
            params=dict(setting.values),
            non_rigid=self.non_rigid,
            crash=self.crash,
            robot_model=self.model,
            record_views=self.record_views,
            version=__version__,
            start=self.start if self.positions is None and self.init is None else None,
            init=_absolute(self.init),
            fairness=(
                int(self.fairness or default_fairness(n))
                if self.scheduler in FAIR_SCHEDULERS
                else None
            ),
            schedule=_absolute(self.schedule),
            move_timeout=float(self.move_timeout_s) if networked else None,
            command=self.command or None,
        )
        return RunSetup(settings, setting, scheduler)


@dataclass(frozen=True, slots=True)
class RunSetup:
    """A run ready to go: its settings (`WorldSetup`: what the record's header says, through its
    one codec) and what they build, the algorithm configured for n robots and the scheduler.
    `resumed`: the record whose committed rounds go on (--resume)."""

    settings: WorldSetup
    params: Configured  # the algorithm and its parameters for n robots
    scheduler: Scheduler
    resumed: RunRecord | None = None

    @property
    def seed(self) -> int:
        return self.settings.seed

    @property
    def initial(self) -> Points:
        """The (n, 2) start."""
        return self.settings.initial

    @property
    def max_rounds(self) -> int:
        """The round cap (ended cycles under an async model)."""
        assert self.settings.max_rounds is not None  # `resolve` and --resume always set it
        return self.settings.max_rounds

    @property
    def algorithm_ref(self) -> str:
        """How every process loads the algorithm: a name or module:attribute."""
        return self.settings.algorithm

    @property
    def non_rigid(self) -> float | None:
        return self.settings.non_rigid

    @property
    def crash(self) -> int | None:
        return self.settings.crash

    @property
    def robot_model(self) -> RobotModel:
        return self.settings.robot_model

    @property
    def record_views(self) -> bool:
        return self.settings.record_views

    @property
    def outside(self) -> str:
        """The line saying how the run is outside its algorithm's assumptions ('' if within)."""
        return self.settings.outside(self.params)


def _absolute(path: str | None) -> str | None:
    """A file setting as the header keeps it: absolute (the run repeats from any directory)."""
    return None if path is None else os.path.abspath(path)


def model_from_args(args: argparse.Namespace) -> RobotModel:
    """The robot model that the flags of its axes (`AXES`: `--visibility`, `--sight`...) ask for
    (unset ones: the paper's); raises ModelError."""
    given = {a.name: getattr(args, a.name, None) for a in AXES}
    return RobotModel.of(**{k: v for k, v in given.items() if v is not None})


def check_lights(model: RobotModel, setting: Configured) -> None:
    """Refuse `--lights` other than the default for an algorithm without lights (RunInputError)."""
    if model.lights is not Lights.FULL and not setting.luminous:
        raise RunInputError(
            f"--lights {model.lights} needs an algorithm with lights; {setting.name} has none"
        )


FAIR_SCHEDULERS: Final = ("ssync", "centralized")  # the schedulers a fairness bound K bounds
WHY_NO_FAIRNESS: Final = {
    "fsync": "activates every robot in every round",
    "scripted": "activates whom its schedule file says",
    "async": "has no rounds (its adversary is fair by construction: the header's fairness_time)",
    "async-slowest": "has no rounds (its adversary is fair by construction: the header's "
    "fairness_time)",
}


def check_fairness(fairness: int | None, scheduler: str) -> None:
    """Refuse a fairness bound for a scheduler that would ignore it (RunInputError)."""
    if fairness is not None and scheduler not in FAIR_SCHEDULERS:
        why = WHY_NO_FAIRNESS.get(scheduler, "takes no fairness bound")
        raise RunInputError(
            f"--fairness only goes with --scheduler ssync or centralized; {scheduler} {why}: "
            "drop --fairness"
        )


def check_non_rigid(delta: float | None) -> None:
    """Refuse a non-rigid delta that is not a finite number > 0 (RunInputError)."""
    if delta is not None and not (math.isfinite(delta) and delta > 0):
        raise RunInputError(
            f"--non-rigid must be a finite distance > 0 (robot radii), got {delta:g}"
        )


def check_crash(f: int | None, n: int) -> None:
    """Refuse a crash count f that is not 0 < f < n (RunInputError)."""
    if f is not None and not 0 < f < n:
        raise RunInputError(f"--crash must be between 1 and n - 1 = {n - 1}, got {f}")


def input_errors() -> tuple[type[Exception], ...]:
    """The exceptions `resolve_run` raises for bad input (each message says what to fix)."""
    # An agent process imports this module (through deploy.flags) and never the schedulers, the
    # starts nor physics: they load here, when a run's input is checked.
    from fatswarm.coordinator.schedule import ScheduleError
    from fatswarm.deploy.scenarios.starts import InitFileError
    from fatswarm.world.physics import InvalidConfigurationError

    return (
        AlgorithmError,
        AlgorithmParamsError,
        InitFileError,
        ScheduleError,
        InvalidConfigurationError,
        UnsupportedInputError,
        RunInputError,
        ModelError,
    )


def resolve_start(
    init: str | None,
    n: int | None,
    a: float | None,
    seed: int,
    kind: str,
    algorithm: str | None = None,
    param_texts: Sequence[str] = (),
    *,
    params: Mapping[str, object] | None = None,
    positions: Points | None = None,
    bodies_are_points: bool = False,
) -> tuple[Configured, Points]:
    """The algorithm (configured) and (n, 2) start that `--init` or `-n`/`--seed`/`--start`,
    `--algorithm`, `--param` and `-a` ask for, valid and supported by the algorithm; raises one of
    `input_errors()`. Shared by `fatswarm run` and `fatswarm world`, so both refuse the same start
    the same way. Random starts are drawn at the scale of a parameter `a`, if there is one.
    `bodies_are_points`: point robots, which may share a point (no overlap to refuse)."""
    # an agent imports this module (through deploy.flags), never physics
    from fatswarm.world.physics import validate_configuration

    chosen = load_algorithm(algorithm or DEFAULT_ALGORITHM)
    given: dict[str, object] = dict(parse_assignments(list(param_texts)))
    given.update(params or {})
    has_a = any(spec.name == "a" for spec in chosen.parameters)
    if a is not None:
        if "a" in given:
            raise RunInputError("give the side once: -a or --param a=..., not both")
        given["a"] = a
    if positions is not None:
        initial = _given_positions(positions, n)
        setting = Configured.of(chosen, len(initial), given)
    elif init is not None:
        initial, file_a = _init_positions(init, n, bodies_are_points)
        if has_a and "a" not in given and file_a is not None:
            given["a"] = file_a
        setting = Configured.of(chosen, len(initial), given)
    else:
        setting = Configured.of(chosen, DEFAULT_N if n is None else n, given)
        initial = _random_positions(setting, seed, kind)
    setting.check_start(initial)
    return setting, validate_configuration(initial, bodies_are_points=bodies_are_points)


def _given_positions(positions: Points, n: int | None) -> Points:
    """The (n, 2) start given as an array (the Python API's `positions`), checked."""
    initial = np.array(positions, dtype=np.float64)
    if initial.ndim != 2 or initial.shape[1:] != (2,) or not len(initial):
        raise RunInputError(f"positions must be an (n, 2) array, got shape {initial.shape}")
    if not np.isfinite(initial).all():
        raise RunInputError("positions must be finite numbers")
    if n is not None and n != len(initial):
        raise RunInputError(f"n={n} disagrees with the {len(initial)} positions given")
    return initial


def _init_positions(init: str, n: int | None, points: bool = False) -> tuple[Points, float | None]:
    """The (n, 2) start of the `--init` file and its side `a` (None: the file has none);
    `points`: of point robots (they may share a point)."""
    # an agent imports this module (through deploy.flags), never the starts
    from fatswarm.deploy.scenarios.starts import load_init

    initial, file_a = load_init(init, points=points)  # finite numbers, as check_supported needs
    if n is not None and n != len(initial):
        raise RunInputError(f"-n {n} disagrees with the {len(initial)} robots of {init}; drop -n")
    return initial, file_a


def _random_positions(setting: Configured, seed: int, kind: str) -> Points:
    """A random start of `kind` for the configured algorithm's n, drawn at the scale of its `a`."""
    # an agent imports this module (through deploy.flags), never the starts
    from fatswarm.deploy.scenarios.starts import random_start

    scale = setting.values.get("a", DEFAULT_A)
    assert isinstance(scale, (int, float))
    # the scale first: a random start is drawn at it (a = 1e308 would overflow it)
    check_supported(np.zeros((setting.n, 2)), float(scale))
    return random_start(setting.n, seed, kind, float(scale))


__all__ = [
    "DEFAULT_A",
    "DEFAULT_N",
    "DEFAULT_SCHEDULER",
    "DEFAULT_START",
    "RunConfig",
    "RunInputError",
    "RunSetup",
    "check_crash",
    "check_fairness",
    "check_lights",
    "check_non_rigid",
    "input_errors",
    "model_from_args",
    "resolve_start",
]
