"""A variant of the paper's algorithm for asynchronous robots: the same plan, but every move is
cut to at most `step` robot radii, so a robot never travels far on a snapshot that has gone stale.

Under the async models the paper's algorithm collides (docs/results.md): a robot follows a long
path planned on a snapshot taken before others moved, or one that showed a robot in mid-move as if
it stood still. Cutting each move is a rule a robot can apply on its own (it is the non-rigid
adversary's cut, chosen by the robot itself), and the paper's algorithm already forms under
non-rigid moves, so it keeps its structure: every Look plans afresh from where things are.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

from fatswarm.agent import uniform_circle
from fatswarm.agent.params import Params
from fatswarm.domain.assumptions import PAPER_ASSUMPTIONS, Assumptions
from fatswarm.domain.path import Path, Points, truncate
from fatswarm.domain.seam import AlgorithmParamsError, ParamSpec, ParamValue

DEFAULT_STEP: Final = 1.0


@dataclass(frozen=True, slots=True)
class SteppedParams:
    """The paper's parameters and the longest move."""

    paper: Params
    step: float

    @property
    def n(self) -> int:
        return self.paper.n


class SteppedPlans:
    """The paper's shared round plan (`uniform_circle.SharedPlans`), every path cut to `step`."""

    def __init__(self, params: SteppedParams) -> None:
        self.step = params.step
        self.shared = uniform_circle.SharedPlans(params.paper)

    def paths(
        self, positions: Points, robots: Sequence[int], flips: Sequence[bool]
    ) -> dict[int, Path]:
        return {
            robot: cut(path, self.step)
            for robot, path in self.shared.paths(positions, robots, flips).items()
        }


def cut(path: Path, step: float) -> Path:
    """`path` (from the robot, at the origin of its frame) cut to its first `step` of length."""
    return truncate((0.0, 0.0), path, step) if path else path


class SteppedUniformCircle:
    """`uniform-circle` with every move cut to at most `step`: for asynchronous robots."""

    name = "uniform-circle-stepped"
    summary = "the paper's algorithm with every move cut to at most `step` (for async robots)"
    parameters: tuple[ParamSpec, ...] = (
        *uniform_circle.UniformCircle.parameters,
        ParamSpec("step", DEFAULT_STEP, "longest move, in robot radii (> 0)"),
    )
    # the paper's model, but for any scheduler (async its aim)
    assumptions: Assumptions = dataclasses.replace(PAPER_ASSUMPTIONS, schedulers=None)

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> SteppedParams:
        step = values.get("step", DEFAULT_STEP)
        if isinstance(step, bool) or not isinstance(step, (int, float)) or not 0 < step < 1e6:
            raise AlgorithmParamsError(f"step must be a distance > 0, got {step!r}")
        paper = uniform_circle.ALGORITHM.make_params(
            n, {k: v for k, v in values.items() if k != "step"}
        )
        return SteppedParams(paper, float(step))

    def compute(self, view: Points, params: SteppedParams) -> Path:
        return cut(uniform_circle.ALGORITHM.compute(view, params.paper), params.step)

    def goal(self, positions: Points, params: SteppedParams) -> bool:
        return uniform_circle.ALGORITHM.goal(positions, params.paper)

    def check_start(self, positions: Points, params: SteppedParams) -> None:
        uniform_circle.ALGORITHM.check_start(positions, params.paper)

    def figures(self, positions: Points, params: SteppedParams) -> dict[str, float]:
        return uniform_circle.ALGORITHM.figures(positions, params.paper)

    def round_planner(self, params: SteppedParams) -> SteppedPlans:
        return SteppedPlans(params)


ALGORITHM: Final = SteppedUniformCircle()

__all__ = ["ALGORITHM", "DEFAULT_STEP", "SteppedParams", "SteppedPlans", "SteppedUniformCircle"]
