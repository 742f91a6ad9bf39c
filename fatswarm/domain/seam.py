"""The algorithm seam: what fatswarm asks of an algorithm, and the parameters that configure it.

An algorithm is any object with the attributes and methods of `Algorithm`. fatswarm finds it by
name (entry point group `fatswarm.algorithms`) or by `module:attribute`
(fatswarm/domain/registry.py); the world asks it whether the goal is reached, every robot asks it
where to go. Nothing else in fatswarm knows which algorithm runs. docs/algorithms.md shows how to
write one.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import traceback
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final, Protocol, TypeVar, cast, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.assumptions import Assumptions
from fatswarm.domain.lights import Glance, LightsError, Lit, colour_index, palette
from fatswarm.domain.path import Path, Points, StraightMoves
from fatswarm.domain.robot_model import Frames, ModelError

ParamValue = bool | int | float | str  # what a parameter can hold: it travels on the wire
MAX_PARAMS = 32  # parameters an algorithm may declare (bounds what a peer can make us parse)
MAX_TEXT = 200  # characters of a text parameter or an algorithm name

P = TypeVar("P")

Views = NDArray[np.float64]
"""(k, m, 2): k robots' views at once, row i robot i's own view (m, 2) in its own private frame,
its rows in the order its Look gives them: what the round hook `compute_views` is given."""


class AlgorithmError(ValueError):
    """An algorithm that cannot be found or loaded, or an object that is not an algorithm."""


class AlgorithmFailure(RuntimeError):
    """The algorithm's own code raised where fatswarm cannot go on without it (its goal)."""

    @staticmethod
    def of(what: str, exc: BaseException) -> AlgorithmFailure:
        """`what raised Type: message (at file.py:line)`, pointing at the algorithm's line."""
        frames = traceback.extract_tb(exc.__traceback__)
        last = frames[-1] if frames else None
        where = f" (at {os.path.basename(last.filename)}:{last.lineno})" if last else ""
        failure = AlgorithmFailure(f"{what} raised {type(exc).__name__}: {exc}{where}")
        failure.__cause__ = exc
        return failure


MAX_FAILURE = 200  # characters of a failed compute's one line (`failure_text`), wire and record


def failure_text(exc: BaseException) -> str:
    """A compute that raised, in one line: `Type: message` (its first line, at most MAX_FAILURE
    characters): what the move message and the round line's `failed` carry."""
    message = str(exc).strip().splitlines()
    text = f"{type(exc).__name__}: {message[0]}" if message else type(exc).__name__
    return text if len(text) <= MAX_FAILURE else text[: MAX_FAILURE - 3] + "..."


def failure_kind(text: str) -> str:
    """What a failure is, apart from the robot and round it hit (its numbers masked): logs say
    each kind once ("ViewError: the view holds # robots, expected n-# = #")."""
    return _NUMBER.sub("#", text)


_NUMBER = re.compile(r"\d+(?:\.\d+)?(?:e[-+]?\d+)?")


class AlgorithmParamsError(ValueError):
    """A parameter the algorithm does not have, or a value it refuses (the message says which)."""


@dataclass(frozen=True, slots=True)
class ParamSpec:
    """One parameter: its name, its default (whose type is the parameter's type) and a line of
    help for `--help` and docs."""

    name: str
    default: ParamValue
    help: str

    @property
    def kind(self) -> type:
        """bool, int, float or str: the type of the default."""
        return type(self.default)

    def parse(self, text: str) -> ParamValue:
        """The value that `--param NAME=TEXT` gives; raises AlgorithmParamsError."""
        kind = self.kind
        value: ParamValue = text
        try:
            if kind is bool:
                lowered = text.strip().lower()
                if lowered not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError(text)
                value = lowered in ("true", "1", "yes")
            elif kind is int:
                value = int(text)
            elif kind is float:
                value = float(text)
        except ValueError:
            raise AlgorithmParamsError(
                f"parameter {self.name} takes a {kind.__name__}, got {text!r}"
            ) from None
        return self.coerce(value)

    def coerce(self, value: object) -> ParamValue:
        """`value` as this parameter's type (an int is a fine float); raises AlgorithmParamsError.

        Used on values from flags, records and the wire: a float must be finite, a text short.
        """
        kind = self.kind
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if type(value) is not kind:
            raise AlgorithmParamsError(
                f"parameter {self.name} takes a {kind.__name__}, got {value!r}"
            )
        if isinstance(value, float) and not math.isfinite(value):
            raise AlgorithmParamsError(f"parameter {self.name} must be finite, got {value!r}")
        if isinstance(value, str) and len(value) > MAX_TEXT:
            raise AlgorithmParamsError(
                f"parameter {self.name} is longer than {MAX_TEXT} characters"
            )
        assert isinstance(value, (bool, int, float, str))
        return value


@runtime_checkable
class Algorithm(Protocol[P]):
    """What fatswarm needs of an algorithm. `P` is the algorithm's own parameter object.

    - `name`: the name a run is recorded under (letters, digits, '-', '_', '.').
    - `summary`: one line for `fatswarm algorithms` and `--help`.
    - `parameters`: what `--param NAME=VALUE` may set, with defaults.
    - `make_params(n, values)`: the parameter object for n robots (None for an algorithm that
      declares it does not know n: `Assumptions.knows_n`) and the complete, typed values
      (defaults filled in); raises AlgorithmParamsError for a value it refuses.
    - `compute(view, params)`: the path of the robot that sees `view`, (k, 2) positions of the
      others it sees (k = n - 1 under the paper's model) relative to itself in its private frame
      (docs/model.md; order arbitrary). Pure: no state survives a call. Must not depend on the
      order of `view`.
    - `goal(positions, params)`: the world's test, on (n, 2) world positions, that the run's goal
      holds. A run is `formed` when the goal holds and every robot, activated since the last
      change, asked to stay; `stalled` when all stay but the goal does not hold.

    A luminous algorithm declares `colours` (a tuple of names, the first every robot's at the
    start) and `compute_lit(view, glance, params) -> Lit` (fatswarm/domain/lights.py), which
    fatswarm calls instead of `compute`. `assumptions` (fatswarm/domain/assumptions.py) says what
    the algorithm's paper assumes on every axis of the model, the schedulers and the moves; a run
    outside them goes ahead and says so. An algorithm without it may declare `frames` alone, a
    tuple of `Frames` names (default: the paper's, `("y-axis",)`), and assumes nothing else.

    Optional hooks, looked up by name: `check_start(positions, params)` refuses a start the
    algorithm does not support (raise AlgorithmParamsError or a ValueError subclass);
    `figures(positions, params) -> Mapping[str, float]` for the dashboard;
    `round_planner(params)`, an object whose `paths(positions, robots, flips)` gives the very
    paths `compute` would give each of `robots` in its own frame, made at once (a fast lock step);
    `compute_views(views, params)`, the round hook: the paths of k robots of a round in one call,
    each from its own view only (`Views`, (k, m, 2), row i robot i's view in its own frame),
    k Paths, or a `StraightMoves` (fatswarm/domain/path.py: k straight lines or stays as arrays,
    the fast form), each bit for bit the one `compute(views[i], params)` returns (the
    lock step uses it where every view is alike: docs/algorithms.md, "The round hook"). Pure, as
    `compute`: no state survives a call, and path i may depend on row i alone.
    """

    name: str
    summary: str
    parameters: tuple[ParamSpec, ...]

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> P: ...

    def compute(self, view: Points, params: P) -> Path: ...

    def goal(self, positions: Points, params: P) -> bool: ...


def resolve_values(
    algorithm: Algorithm[Any], given: Mapping[str, object] | None = None
) -> dict[str, ParamValue]:
    """Every parameter of `algorithm`: `given` (typed or as text from a flag) over the defaults.

    Raises AlgorithmParamsError naming an unknown parameter and the ones there are.
    """
    specs = {spec.name: spec for spec in algorithm.parameters}
    values: dict[str, ParamValue] = {name: spec.default for name, spec in specs.items()}
    for name, value in (given or {}).items():
        spec = specs.get(name)
        if spec is None:
            known = ", ".join(specs) or "none"
            raise AlgorithmParamsError(
                f"algorithm {algorithm.name} has no parameter {name!r} (it has: {known})"
            )
        values[name] = spec.parse(value) if isinstance(value, str) else spec.coerce(value)
    return values


def parse_assignments(texts: list[str] | tuple[str, ...]) -> dict[str, str]:
    """`["a=5", "tol=1e-3"]` as a mapping; raises AlgorithmParamsError for a text without '='."""
    out: dict[str, str] = {}
    for text in texts:
        name, sep, value = text.partition("=")
        if not sep or not name.strip():
            raise AlgorithmParamsError(f"--param takes NAME=VALUE, got {text!r}")
        out[name.strip()] = value.strip()
    return out


def assumptions_of(algorithm: object) -> Assumptions:
    """What `algorithm` declares it assumes: its `assumptions` (default: any value of every axis
    but frames, the paper's), with its `frames` if it declares them too (as an algorithm did
    before it could declare more; a subclass may narrow its parent's frames so); raises
    AlgorithmError for a declaration that is not one."""
    declared = getattr(algorithm, "assumptions", None)
    if declared is None:
        declared = NO_ASSUMPTIONS
    if not isinstance(declared, Assumptions):
        raise AlgorithmError(
            f"algorithm {getattr(algorithm, 'name', '?')}: assumptions must be an Assumptions "
            f"(fatswarm.domain.assumptions), got {type(declared).__name__}"
        )
    if getattr(algorithm, "frames", None) is None:
        return declared
    return dataclasses.replace(declared, frames=_frames(algorithm))


def assumed_frames(algorithm: object) -> tuple[Frames, ...]:
    """The frames `algorithm` declares it assumes (default the paper's; every one for any);
    raises AlgorithmError."""
    return assumptions_of(algorithm).frames or tuple(Frames)


def _frames(algorithm: object) -> tuple[Frames, ...]:
    """The frames an algorithm without `assumptions` declares (default the paper's)."""
    declared = getattr(algorithm, "frames", (Frames.Y_AXIS,))
    try:
        if not isinstance(declared, tuple) or not declared:
            raise ModelError(f"got {declared!r}")
        return tuple(Frames(name) for name in declared)
    except (ModelError, ValueError):
        choices = ", ".join(f.value for f in Frames)
        raise AlgorithmError(
            f"algorithm {getattr(algorithm, 'name', '?')}: frames must be a non-empty tuple of "
            f"{choices}, got {declared!r}"
        ) from None


def checked(compute: Callable[[Points], Path]) -> Callable[[Points], Path]:
    """`compute`, refusing (TypeError) anything but a Path: an algorithm's bug is said plainly."""

    def run(view: Points) -> Path:
        path = compute(view)
        if not isinstance(path, Path):
            raise TypeError(f"compute returned {type(path).__name__}, not a Path")
        return path

    return run


NO_ASSUMPTIONS: Final = Assumptions()  # an algorithm's that declares none: the paper's frames


class RoundPlanner(Protocol):
    """An algorithm's optional fast path for a lock step: every robot of a round at once."""

    def paths(
        self, positions: Points, robots: Sequence[int], flips: Sequence[bool]
    ) -> Mapping[int, Path]:
        """Each of `robots`' path in its own frame (X mirrored where `flips[robot]`), from the
        world positions (n, 2): the very paths its `compute` would return for its view."""
        ...


def _hook_of_its_compute(algorithm: object, name: str) -> Any:
    """The hook `name` of `algorithm` (a shortcut for many robots' Computes at once), or None if
    it has none or the hook is inherited from above the class that defines its `compute`: a
    subclass that changes `compute` and keeps its parent's hook would have the parent's moves."""
    hook = getattr(algorithm, name, None)
    if hook is None or name in getattr(algorithm, "__dict__", {}):  # none, or the object's own
        return hook
    mro = type(algorithm).__mro__
    compute_owner = next((c for c in mro if "compute" in vars(c) or "compute_lit" in vars(c)), None)
    hook_owner = next((c for c in mro if name in vars(c)), None)
    if compute_owner is None or hook_owner is None:
        return hook
    return hook if issubclass(hook_owner, compute_owner) else None


@dataclass(frozen=True, slots=True, eq=False)
class Configured:
    """An algorithm with its parameters for a run of n robots: what the world and agents hold."""

    algorithm: Algorithm[Any]
    n: int
    values: Mapping[str, ParamValue]
    params: Any  # the algorithm's own parameter object
    colours: tuple[str, ...] = ()  # its palette (fatswarm/domain/lights.py); () if not luminous
    assumptions: Assumptions = NO_ASSUMPTIONS  # what it assumes (default: the paper's frames)

    @staticmethod
    def of(
        algorithm: Algorithm[Any], n: int, given: Mapping[str, object] | None = None
    ) -> Configured:
        """Resolve, check and build the parameters; raises AlgorithmParamsError, or
        AlgorithmError for a palette or frames declaration fatswarm cannot use."""
        values = resolve_values(algorithm, given)
        try:
            colours = palette(algorithm)
        except LightsError as exc:
            raise AlgorithmError(str(exc)) from None
        assumptions = assumptions_of(algorithm)
        params = algorithm.make_params(n if assumptions.knows_n else None, values)
        return Configured(algorithm, n, values, params, colours, assumptions)

    @property
    def frames(self) -> tuple[Frames, ...]:
        """The frames the algorithm assumes (every one if any)."""
        return self.assumptions.frames or tuple(Frames)

    @property
    def luminous(self) -> bool:
        """Whether the algorithm has lights (declares colours)."""
        return bool(self.colours)

    def decide(self, view: Points, glance: Glance | None = None) -> tuple[Path, int | None]:
        """One robot's Compute in its private frame: its path and, for a luminous algorithm, the
        index of the colour it shows next (None otherwise). Raises TypeError or LightsError for
        an answer that is not a Path (a Lit, in a palette colour)."""
        if not self.colours:
            path = self.algorithm.compute(view, self.params)
            colour = None
        else:
            luminous: Any = self.algorithm  # checked by the registry: it has compute_lit
            lit = luminous.compute_lit(view, glance, self.params)
            if not isinstance(lit, Lit):
                raise TypeError(f"compute_lit returned {type(lit).__name__}, not a Lit")
            path, colour = lit.path, colour_index(self.colours, lit.colour, "compute_lit")
        if not isinstance(path, Path):
            raise TypeError(f"compute returned {type(path).__name__}, not a Path")
        return path, colour

    @property
    def name(self) -> str:
        return self.algorithm.name

    def compute(self, view: Points) -> Path:
        """The algorithm's path for one robot's view (its private frame)."""
        return self.algorithm.compute(view, self.params)

    def goal(self, positions: Points) -> bool:
        """Whether the goal holds for (n, 2) world positions; raises AlgorithmFailure if the
        algorithm's goal raises (nobody can then say whether the run is over)."""
        try:
            return bool(self.algorithm.goal(positions, self.params))
        except Exception as exc:
            raise AlgorithmFailure.of(f"the goal of algorithm {self.name}", exc) from exc

    def check_start(self, positions: Points) -> None:
        """The algorithm's own refusal of a start it does not support, if it has one."""
        hook = getattr(self.algorithm, "check_start", None)
        if hook is not None:
            hook(positions, self.params)

    def views_compute(self) -> Callable[[Views], Sequence[Path] | StraightMoves] | None:
        """The algorithm's round hook for these parameters (`compute_views`), if it has one and
        is not luminous (a luminous algorithm's Compute goes per robot)."""
        hook = _hook_of_its_compute(self.algorithm, "compute_views")
        if hook is None or self.colours:
            return None
        params = self.params
        return lambda views: cast(Sequence[Path] | StraightMoves, hook(views, params))

    def round_planner(self) -> RoundPlanner | None:
        """The algorithm's round planner for these parameters, if it has the hook."""
        hook = _hook_of_its_compute(self.algorithm, "round_planner")
        return None if hook is None else cast(RoundPlanner, hook(self.params))

    def figures(self, positions: Points) -> dict[str, float]:
        """The algorithm's finite figures for the dashboard (none if it has no hook); raises
        AlgorithmFailure if the hook raises or gives something that is not a map of numbers."""
        hook = getattr(self.algorithm, "figures", None)
        if hook is None:
            return {}
        try:
            given = {str(k): float(v) for k, v in hook(positions, self.params).items()}
        except Exception as exc:
            raise AlgorithmFailure.of(f"the figures of algorithm {self.name}", exc) from exc
        return {k: v for k, v in given.items() if math.isfinite(v)}

    def describe(self) -> str:
        """`name a=4 ...`: the algorithm and its parameters, for summaries."""
        shown = " ".join(
            f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in self.values.items()
        )
        return f"{self.name} {shown}".strip()


__all__ = [
    "MAX_FAILURE",
    "MAX_PARAMS",
    "Algorithm",
    "AlgorithmError",
    "AlgorithmFailure",
    "AlgorithmParamsError",
    "Configured",
    "ParamSpec",
    "ParamValue",
    "Points",
    "RoundPlanner",
    "Views",
    "assumed_frames",
    "assumptions_of",
    "checked",
    "failure_kind",
    "failure_text",
    "parse_assignments",
    "resolve_values",
]
