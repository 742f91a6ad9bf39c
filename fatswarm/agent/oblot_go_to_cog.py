"""oblot-sim's `GoToCoG`, ported: every robot moves straight to the centre of gravity of all the
positions it sees, its own included (docs/ports.md, "oblot-go-to-cog").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Final

import numpy as np

from fatswarm.agent.oblot_common import (
    TOLERANCE_SPEC,
    OblotParams,
    gathered,
    go_to,
    goes_to,
    make_oblot_params,
    peer_assumptions,
    spread,
)
from fatswarm.agent.row_sums import fsum_rows
from fatswarm.domain.assumptions import Assumptions
from fatswarm.domain.path import Path, Points, StraightMoves
from fatswarm.domain.scratch import scratch
from fatswarm.domain.seam import ParamSpec, ParamValue, Views

# The peer's robots see every robot (`Simulator/Simulation.java:101`), one row per robot
# (multiplicity), as points; the centre of gravity needs no agreement on axes (any frame).


EACH_UP_TO: Final = 48
"""`compute_views` takes each robot's sums in Python up to this many view rows in all (k * m):
fewer calls than the arrays' way for a small swarm's round."""


class OblotGoToCoG:
    """Rule 1: sum every position, the robot's own (the origin) included, and divide by n
    (`algorithms/GoToCoG.java:13-17`). Rule 2: move straight there (`:17`).

    The peer sums in robot-id order; a fatswarm robot's view has no order, so the sum is exact
    (`math.fsum`) and the same for every order of the rows: it differs from the peer's by rounding.
    """

    name: str = "oblot-go-to-cog"
    summary: str = (
        "oblot-sim's GoToCoG: move to the centre of gravity of all n points (points, multiplicity)"
    )
    parameters: tuple[ParamSpec, ...] = (TOLERANCE_SPEC,)
    assumptions: Assumptions = peer_assumptions(None)

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> OblotParams:
        return make_oblot_params(n, values)

    def compute(self, view: Points, params: OblotParams) -> Path:
        """A Line to the centre of gravity of the view and the origin, or STAY there."""
        n = len(view) + 1  # the robot itself, at the origin, adds nothing to the sums
        gx = math.fsum(view[:, 0].tolist()) / n if len(view) else 0.0
        gy = math.fsum(view[:, 1].tolist()) / n if len(view) else 0.0
        return go_to((gx, gy), params)

    def compute_views(self, views: Views, params: OblotParams) -> StraightMoves:
        """`compute` of every view of `views` (k, m, 2) at once, the very bits (the round hook:
        fatswarm/domain/seam.py): the sums by `fsum_rows` (`math.fsum`'s bits), then `go_to`'s
        own operations per robot (CPython's `math.hypot`). A target that is not a finite point
        raises `go_to`'s error (each robot's own compute then says it alone)."""
        k, m = views.shape[0], views.shape[1]
        if m == 0:  # the target is the origin: within any tolerance (>= 0)
            return StraightMoves(np.zeros((k, 2)), np.zeros(k, dtype=np.bool_))
        if k * m <= EACH_UP_TO:
            return _each(views, params)
        coords = scratch("oblot-go-to-cog", (2, k, m))  # every x, then every y: rows contiguous
        # (+ 0.0: -0.0 as 0.0, which changes no sum and spares fsum_rows a comparison)
        np.add(views.transpose(2, 0, 1), 0.0, out=coords)
        centre = fsum_rows(coords.reshape(2 * k, m)) / (m + 1)  # every x, then every y
        listed = centre.tolist()  # (the robot itself, at the origin, adds nothing to the sums)
        distance = list(map(math.hypot, listed[:k], listed[k:]))
        if not math.isfinite(sum(distance)):  # hypot is finite where both coordinates are
            for gx, gy in zip(listed[:k], listed[k:], strict=True):
                if not (math.isfinite(gx) and math.isfinite(gy)):
                    go_to((gx, gy), params)  # raises
        goes = np.array(distance) > params.tolerance  # not <= tolerance: the distance is finite
        return StraightMoves(np.where(goes, centre.reshape(2, k), 0.0).T, goes)

    def goal(self, positions: Points, params: OblotParams) -> bool:
        """Every robot at one point (within GOAL_REL of the largest coordinate)."""
        return gathered(positions)

    def figures(self, positions: Points, params: OblotParams) -> dict[str, float]:
        return spread(positions)


def _each(views: Views, params: OblotParams) -> StraightMoves:
    """`compute` of every view of `views` (k, m, 2), m >= 1, robot by robot (a small round): its
    sums by `math.fsum`, then `go_to`'s test (`goes_to`, which raises its error)."""
    n = views.shape[1] + 1  # the robot itself, at the origin, adds nothing to the sums
    fsum = math.fsum
    ends: list[float] = []
    goes: list[bool] = []
    for row_x, row_y in zip(views[:, :, 0].tolist(), views[:, :, 1].tolist(), strict=True):
        end = (fsum(row_x) / n, fsum(row_y) / n)
        go = goes_to(end, params)
        goes.append(go)
        ends += end if go else _NOWHERE
    return StraightMoves(
        np.array(ends, dtype=np.float64).reshape(len(goes), 2), np.array(goes, dtype=np.bool_)
    )


_NOWHERE: Final = (0.0, 0.0)  # a staying robot's row of `_each`'s ends (read by nobody)
ALGORITHM: Final = OblotGoToCoG()

__all__ = ["ALGORITHM", "OblotGoToCoG"]
