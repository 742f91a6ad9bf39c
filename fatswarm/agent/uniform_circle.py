"""The paper's algorithm behind the seam: uniform circle formation by transparent fat robots.

Its one parameter is the least side `a` of the polygon (the paper's a > 3). The goal is the
uniform circle (`geometry.is_formed`); the plan is shared by all the robots of a round in lock step
(`SharedPlans`), since every robot plans on the same canonical bits (agent/canonical.py).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping, Sequence
from typing import Final

from fatswarm.agent import algorithm, geometry
from fatswarm.agent.canonical import SharedForm
from fatswarm.agent.params import Params, ParamsError
from fatswarm.domain.assumptions import PAPER_ASSUMPTIONS, Assumptions
from fatswarm.domain.path import STAY, Path, Points
from fatswarm.domain.seam import ParamSpec, ParamValue
from fatswarm.domain.tolerance import check_supported

DEFAULT_A: Final = 4.0
SHARED_PLANS: Final = 8  # canonical forms remembered: a round has one; ssync revisits a few


class SharedPlans:
    """The paper's algorithm for all the robots of a round at once, exactly as each computes it.

    Every robot's own `algorithm.compute` puts its view in canonical form (the same bits for all)
    and plans there. This makes the canonical form once a round (`SharedForm`), the plan once per
    distinct canonical form, and hands each robot its part in its own frame: the very paths the
    robots' own computations return, without n of them.
    """

    def __init__(self, params: Params, size: int = SHARED_PLANS) -> None:
        self.params = params
        self._plans: OrderedDict[bytes, algorithm.Plan] = OrderedDict()
        self._size = size
        self.planned = 0  # how many plans were actually made (the rest were shared)

    def plan_of(self, form: SharedForm) -> algorithm.Plan:
        """The plan of the configuration `form` (made at most once while remembered)."""
        key = form.key()
        made = self._plans.get(key)
        if made is None:
            made = algorithm.plan(form.points, self.params)
            self.planned += 1
            self._plans[key] = made
            if len(self._plans) > self._size:
                self._plans.popitem(last=False)
        return made

    def paths(
        self, positions: Points, robots: Sequence[int], flips: Sequence[bool]
    ) -> dict[int, Path]:
        """Each of `robots`' path in its own frame (flipped per `flips[robot]`)."""
        if not len(robots):
            return {}
        form = SharedForm.of(positions)
        out = dict.fromkeys(robots, STAY)  # a robot the plan does not move stays, in any frame
        for observer, path in self.plan_of(form).moves.items():
            for robot in form.robots_at(observer):
                if robot in out and form.observer(robot, flips[robot]) == observer:
                    out[robot] = form.for_robot(robot, flips[robot]).to_frame(path)
        return out


class UniformCircle:
    """Mondal & Gan Chaudhuri's algorithm; docs/algorithm.md holds each rule the paper left open."""

    name = "uniform-circle"
    summary = "the paper's uniform circle formation by transparent fat robots (side >= a)"
    parameters: tuple[ParamSpec, ...] = (
        ParamSpec("a", DEFAULT_A, "least side of the polygon the robots form (the paper: a > 3)"),
    )
    # the paper's section 2: transparent unit discs seeing all, Y agreed, SSYNC, rigid, n given
    assumptions: Assumptions = PAPER_ASSUMPTIONS

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> Params:
        if n is None:
            raise ParamsError("the paper's algorithm is given n (it declares knows_n)")
        a = values.get("a", DEFAULT_A)
        assert isinstance(a, (int, float)) and not isinstance(a, bool)
        return Params(n, float(a))  # raises ParamsError, an AlgorithmParamsError

    def compute(self, view: Points, params: Params) -> Path:
        return algorithm.compute(view, params)

    def goal(self, positions: Points, params: Params) -> bool:
        return geometry.is_formed(positions, params.a)

    def check_start(self, positions: Points, params: Params) -> None:
        """The supported range (fatswarm/domain/tolerance.py): spans and circles small enough for
        the grid."""
        check_supported(positions, params.a)

    def figures(self, positions: Points, params: Params) -> dict[str, float]:
        return {"target radius": geometry.target_radius(params.n, params.a)}

    def round_planner(self, params: Params) -> SharedPlans:
        return SharedPlans(params)


ALGORITHM: Final = UniformCircle()

__all__ = ["ALGORITHM", "DEFAULT_A", "SharedPlans", "UniformCircle"]
