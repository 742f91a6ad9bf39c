"""A test algorithm with lights and limited sight: robots spread until no two centres are closer
than `gap`. A robot near a neighbour steps away from the nearest one, unless it sees a robot
showing `moving` (then it waits, showing `waiting`); it shows `moving` while it steps.

Not a research algorithm: it exercises the lights (its own colour and the others'), limited sight
and obstruction end to end (tests/integration, docs/model.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from fatswarm.domain.lights import Glance, Lit
from fatswarm.domain.path import Line, Path, Points
from fatswarm.domain.seam import ParamSpec, ParamValue


@dataclass(frozen=True, slots=True)
class SpreadParams:
    n: int
    gap: float
    step: float


class LitSpread:
    name = "lit-spread"
    summary = "spread until centres are gap apart; wait while a seen neighbour moves (test)"
    parameters = (
        ParamSpec("gap", 3.0, "the least distance between centres wanted"),
        ParamSpec("step", 0.4, "how far a robot steps away from its nearest neighbour"),
    )
    colours = ("still", "moving", "waiting")
    frames = ("y-axis", "chirality", "disoriented")

    def make_params(self, n: int, values: Mapping[str, ParamValue]) -> SpreadParams:
        return SpreadParams(n, float(values["gap"]), float(values["step"]))

    def compute(self, view: Points, params: SpreadParams) -> Path:
        return self.compute_lit(view, Glance("still", None), params).path

    def compute_lit(self, view: Points, glance: Glance | None, params: SpreadParams) -> Lit:
        if not len(view):
            return Lit(Path(), "still")
        dist = np.hypot(view[:, 0], view[:, 1])
        near = dist < params.gap - 1e-9
        if not near.any():
            return Lit(Path(), "still")
        others = glance.others if glance is not None else None
        if others is not None and any(
            c == "moving" for c, k in zip(others, near, strict=True) if k
        ):
            return Lit(Path(), "waiting")
        # away from the nearest ones together: the same whatever the order of the view or frame
        nearest = view[dist <= dist.min() + 1e-9].sum(axis=0)
        norm = float(np.hypot(*nearest))
        if norm < 1e-6:  # nearest ones all around it: no way out by this rule
            return Lit(Path(), "waiting")
        away = -nearest / norm * params.step
        return Lit(Path((Line((float(away[0]), float(away[1]))),)), "moving")

    def goal(self, positions: Points, params: SpreadParams) -> bool:
        if len(positions) < 2:
            return True
        d = np.hypot(*(positions[:, None, :] - positions[None, :, :]).transpose(2, 0, 1))
        np.fill_diagonal(d, np.inf)
        return bool(d.min() >= params.gap - 1e-9)


ALGORITHM = LitSpread()
