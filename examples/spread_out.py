"""Spread out: an algorithm of your own in one file (docs/algorithms.md walks through it).

Run it with `fatswarm run --algorithm examples/spread_out.py:ALGORITHM --param spacing=5`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.path import STAY, Line, Path
from fatswarm.domain.seam import AlgorithmParamsError, ParamSpec, ParamValue

Points = NDArray[np.float64]  # (k, 2)
CONTACT: Final = 2.0  # unit discs touch when their centres are 2 apart
MIN_STEP: Final = 1e-3  # a shorter move is not worth making: the robot stays


@dataclass(frozen=True, slots=True)
class SpreadParams:
    """Wanted distance between every two centres, and the longest move of one activation."""

    n: int
    spacing: float
    step: float

    def __post_init__(self) -> None:
        if not self.spacing > CONTACT + 2.0 * MIN_STEP:
            raise AlgorithmParamsError(
                f"spacing must be > {CONTACT + 2.0 * MIN_STEP:g}, got {self.spacing:g}"
            )
        if not self.step > MIN_STEP:
            raise AlgorithmParamsError(f"step must be > {MIN_STEP:g}, got {self.step:g}")


class SpreadOut:
    """Move away from the crowd until every neighbour is at least `spacing` away.

    A robot with neighbours closer than `spacing` (its crowd) moves straight away from the crowd's
    centre of gravity (itself included) by min(`step`, half the gap to the nearest robot ahead, i.e.
    with a positive component along its motion). No collision under any scheduler: a pair in which
    each sees the other ahead closes by at most step_i + step_j <= d - 2; a robot moving away from
    the other never brings it closer, so then only the other's step <= (d - 2) / 2 counts. Capping
    by robots ahead only lets touching robots separate. The crowd is only the robots closer than
    `spacing`: with a wider sensing radius (the first version, radius 6) farther robots could turn
    two close robots toward each other, and they ended touching and blocked (stalled runs).
    Terminates on small starts (checked by simulation, not proved).
    """

    name: str = "spread-out"
    summary: str = "move away from the local crowd until every pair of robots is >= spacing apart"
    parameters: tuple[ParamSpec, ...] = (
        ParamSpec("spacing", 4.0, "least distance wanted between every two centres (> 2)"),
        ParamSpec("step", 1.0, "the longest move of one activation"),
    )

    def make_params(self, n: int, values: Mapping[str, ParamValue]) -> SpreadParams:
        spacing, step = values.get("spacing", 4.0), values.get("step", 1.0)
        assert isinstance(spacing, float) and isinstance(step, float)  # the seam typed them
        return SpreadParams(n, spacing, step)

    def compute(self, view: Points, params: SpreadParams) -> Path:
        """A Line away from the crowd's centre of gravity, or STAY; `view` is (n-1, 2)."""
        if len(view) == 0:
            return STAY
        dist = np.hypot(view[:, 0], view[:, 1])
        if float(dist.min()) >= params.spacing:
            return STAY
        crowd = view[dist < params.spacing]
        k = len(crowd) + 1  # the robot itself, at the origin
        # fsum: the same bits for every order of the view, and exactly mirrored under x -> -x
        cx = math.fsum(crowd[:, 0].tolist()) / k
        cy = math.fsum(crowd[:, 1].tolist()) / k
        norm = math.hypot(cx, cy)
        if norm == 0.0:  # the crowd is balanced about the robot: no direction (others move)
            return STAY
        ux, uy = -cx / norm, -cy / norm
        ahead = view[:, 0] * ux + view[:, 1] * uy > 0.0
        gap = float(dist[ahead].min()) - CONTACT if ahead.any() else math.inf
        step = min(params.step, gap / 2.0)
        if not step > MIN_STEP:  # blocked by a robot ahead (it moves on first)
            return STAY
        return Path((Line((ux * step, uy * step)),))

    def goal(self, positions: Points, params: SpreadParams) -> bool:
        """Every pair of centres is at least `spacing` apart; (n, 2) world positions."""
        pts = np.asarray(positions, dtype=np.float64)
        diff = pts[np.newaxis, :, :] - pts[:, np.newaxis, :]
        dist = np.hypot(diff[:, :, 0], diff[:, :, 1])
        np.fill_diagonal(dist, np.inf)
        return bool((dist >= params.spacing).all())

    def figures(self, positions: Points, params: SpreadParams) -> dict[str, float]:
        """`closest pair`: the smallest distance between two centres (the goal wants >= spacing)."""
        pts = np.asarray(positions, dtype=np.float64)
        if len(pts) < 2:
            return {}
        diff = pts[np.newaxis, :, :] - pts[:, np.newaxis, :]
        dist = np.hypot(diff[:, :, 0], diff[:, :, 1])
        np.fill_diagonal(dist, np.inf)
        return {"closest pair": float(dist.min())}


ALGORITHM: Final = SpreadOut()
