"""Gathering by the centre of gravity: the baseline other LCM simulators ship, behind the seam.

Each robot moves straight toward the centre of gravity of all n centres by at most half the gap to
its nearest neighbour; it stays once that step is within `tolerance`, and the run ends.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.agent.params import check_count, check_tolerance
from fatswarm.agent.row_sums import fsum_rows, nearest_norms
from fatswarm.domain.assumptions import Assumptions
from fatswarm.domain.path import STAY, Line, Path, Points, StraightMoves
from fatswarm.domain.robot_model import Bodies, Visibility
from fatswarm.domain.scratch import scratch
from fatswarm.domain.seam import AlgorithmParamsError, ParamSpec, ParamValue, Views
from fatswarm.domain.tolerance import CONTACT

Values = NDArray[np.float64]  # (k,)
DEFAULT_TOLERANCE: Final = 1e-3
GOAL_BLOCK: Final = 512  # rows of the pairwise distance matrix `goal` holds at once (memory bound)
EACH_UP_TO: Final = 96
"""`compute_views` takes each robot's sums and step in Python up to this many view rows in all
(k * m): fewer calls than the arrays' way for a small swarm's round."""
ROUNDING_REL: Final = 1e-12  # G from world positions vs a robot's view: a few ulps of the span
_NOWHERE: Final = (0.0, 0.0)  # a staying robot's row of `_each`'s ends (read by nobody)


@dataclass(frozen=True, slots=True)
class GatheringParams:
    """n robots (None: not known, as the world gives it, `Gathering.assumptions`); a robot stays
    when its step would be at most `tolerance` (> 0, finite)."""

    n: int | None
    tolerance: float = DEFAULT_TOLERANCE

    def __post_init__(self) -> None:
        check_count(self.n)
        check_tolerance(self.tolerance, zero_ok=False)


def _steps(to_centre: Points, nearest: Values) -> Values:
    """Each robot's step: min(|G|, (d_min - 2) / 2), from (k, 2) vectors to G and (k,) d_min."""
    return np.asarray(
        np.minimum(np.hypot(to_centre[:, 0], to_centre[:, 1]), (nearest - CONTACT) / 2.0)
    )


def _nearest(positions: Points) -> Values:
    """(n,) distance from each centre to its nearest other one, `GOAL_BLOCK` rows at a time."""
    n = len(positions)
    out = np.empty(n, dtype=np.float64)
    for lo in range(0, n, GOAL_BLOCK):
        rows = positions[lo : lo + GOAL_BLOCK]
        diff = positions[np.newaxis, :, :] - rows[:, np.newaxis, :]
        dist = np.hypot(diff[:, :, 0], diff[:, :, 1])
        dist[np.arange(len(rows)), np.arange(lo, lo + len(rows))] = np.inf
        out[lo : lo + len(rows)] = dist.min(axis=1)
    return out


def centre_of_gravity(positions: Points) -> tuple[float, float]:
    """The mean of (k, 2) centres, each coordinate summed exactly (`math.fsum`) then divided."""
    k = len(positions)
    return (math.fsum(positions[:, 0].tolist()) / k, math.fsum(positions[:, 1].tolist()) / k)


class Gathering:
    """Go to the centre of gravity, never further than half the gap to the nearest neighbour.

    No collision under the round schedulers (fsync, ssync, centralized, scripted; rigid or not,
    with exact views): the robots that move in a round all Looked at the same positions, robot k
    stays within step_k <= (d_kj - 2) / 2 of its start for every j, so at every instant
    |p_i - p_j| >= d_ij - step_i - step_j >= d_ij - (d_ij - 2) = 2. Not under async: a robot may
    move on a view in which another has not started the step it already chose, and the bound no
    longer holds ((0, 0) and (2.5, 0), async, seed 1; docs/algorithms.md, "gathering").
    The cap also means a robot touching a neighbour never moves again: the swarm can end as
    touching clumps rather than one (the goal is "nobody would move", not "one cluster").
    """

    name: str = "gathering"
    summary: str = "move toward the centre of gravity by at most half the gap to the nearest robot"
    parameters: tuple[ParamSpec, ...] = (
        ParamSpec(
            "tolerance",
            DEFAULT_TOLERANCE,
            "a robot stays when its step would be at most this (> 0)",
        ),
    )
    # the centre of gravity and the nearest gap are the same in any frame: no agreement needed;
    # the centre is of the robots seen (all: transparent, unlimited), n is never used (the view's
    # size); the step cap keeps discs of radius 1 apart for any partial move (docs/algorithms.md)
    assumptions: Assumptions = Assumptions(
        visibility=(Visibility.TRANSPARENT,),
        sight=(None,),
        frames=None,
        noise=(0.0,),
        bodies=(Bodies.FAT,),
        knows_n=False,
    )

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> GatheringParams:
        tol = values.get("tolerance", DEFAULT_TOLERANCE)
        if isinstance(tol, bool) or not isinstance(tol, (int, float)):
            raise AlgorithmParamsError(f"tolerance must be a number, got {tol!r}")
        return GatheringParams(n, float(tol))

    def compute(self, view: Points, params: GatheringParams) -> Path:
        """A Line toward G by the capped step, or STAY; `view` is (n-1, 2), the robot at the origin.

        fsum, hypot and min give the same bits for any order of the rows and, up to sign, under
        x -> -x, so the path depends on neither.
        """
        if len(view) == 0:
            return STAY
        n = len(view) + 1  # the robot itself, at the origin, adds nothing to the sums
        gx = math.fsum(view[:, 0].tolist()) / n
        gy = math.fsum(view[:, 1].tolist()) / n
        d_min = float(np.hypot(view[:, 0], view[:, 1]).min())
        return _toward(gx, gy, (d_min - CONTACT) / 2.0, params.tolerance)

    def compute_views(self, views: Views, params: GatheringParams) -> StraightMoves:
        """`compute` of every view of `views` (k, m, 2) at once, the very bits (the round hook:
        fatswarm/domain/seam.py): the sums by `fsum_rows` (`math.fsum`'s bits), the nearest gap
        by `nearest_norms` (the same `np.hypot` per element), then `_toward`'s own operations
        per robot (`_towards`: CPython's `math.hypot`, whose last bit np.hypot's may differ
        from); up to EACH_UP_TO view rows in all, robot by robot (`_each`)."""
        k, m = views.shape[0], views.shape[1]
        if m == 0:
            return StraightMoves(np.zeros((k, 2)), np.zeros(k, dtype=np.bool_))
        if k * m <= EACH_UP_TO:
            return _each(views, params.tolerance)
        coords = scratch("gathering", (2, k, m))  # every x, then every y: rows contiguous
        # (+ 0.0: -0.0 as 0.0, which changes no sum nor norm and spares fsum_rows a comparison)
        np.add(views.transpose(2, 0, 1), 0.0, out=coords)
        sums = fsum_rows(coords.reshape(2 * k, m))  # every x sum, then every y sum
        nearest = nearest_norms(coords[0], coords[1])
        return _towards(sums, m + 1, nearest, params.tolerance)  # the robot itself adds nothing

    def goal(self, positions: Points, params: GatheringParams) -> bool:
        """No robot would move: every robot's step, from world positions, is <= tolerance.

        Up to rounding (ROUNDING_REL of the swarm's span): a robot sums its own view, this sums
        positions relative to robot 0 (exact on the grid). Lenient is safe: `formed` also needs
        every robot to have stayed.
        """
        pts = np.asarray(positions, dtype=np.float64)
        if len(pts) <= 1:
            return True
        pts = pts - pts[0]
        gx, gy = centre_of_gravity(pts)
        to_g = np.array([gx, gy]) - pts
        slack = ROUNDING_REL * max(1.0, float(np.abs(pts).max()))
        return bool((_steps(to_g, _nearest(pts)) <= params.tolerance + slack).all())

    def figures(self, positions: Points, params: GatheringParams) -> dict[str, float]:
        """`spread`: the largest distance of a centre from the centre of gravity."""
        pts = np.asarray(positions, dtype=np.float64)
        if len(pts) == 0:
            return {"spread": 0.0}
        gx, gy = centre_of_gravity(pts)
        return {"spread": float(np.hypot(pts[:, 0] - gx, pts[:, 1] - gy).max())}


def _toward(gx: float, gy: float, gap: float, tolerance: float) -> Path:
    """A Line toward G = (gx, gy) by at most `gap` (half the room to the nearest neighbour), or
    STAY when that step is not above `tolerance` (also a touching or overlapping neighbour)."""
    end = _toward_end(gx, gy, gap, tolerance)
    return STAY if end is None else Path((Line(end),))


def _toward_end(gx: float, gy: float, gap: float, tolerance: float) -> tuple[float, float] | None:
    """Where `_toward`'s Line ends, or None where it stays."""
    to_g = math.hypot(gx, gy)
    step = min(to_g, gap)
    if not step > tolerance:
        return None
    if step >= to_g:
        return (gx, gy)
    f = step / to_g
    return (gx * f, gy * f)


def _each(views: Views, tolerance: float) -> StraightMoves:
    """`compute` of every view of `views` (k, m, 2), m >= 1, robot by robot (a small round, in
    fewer calls than as arrays): its sums by `math.fsum`, its nearest gap by `nearest_norms`,
    then `_toward_end`."""
    n = views.shape[1] + 1  # the robot itself, at the origin, adds nothing to the sums
    xs, ys = views[:, :, 0], views[:, :, 1]
    nearest = nearest_norms(xs, ys).tolist()
    fsum = math.fsum
    ends: list[float] = []
    goes: list[bool] = []
    for row_x, row_y, d_min in zip(xs.tolist(), ys.tolist(), nearest, strict=True):
        end = _toward_end(fsum(row_x) / n, fsum(row_y) / n, (d_min - CONTACT) / 2.0, tolerance)
        goes.append(end is not None)
        ends += _NOWHERE if end is None else end
    return StraightMoves(
        np.array(ends, dtype=np.float64).reshape(len(goes), 2), np.array(goes, dtype=np.bool_)
    )


def _towards(sums: Values, n: int, nearest: Values, tolerance: float) -> StraightMoves:
    """`compute`'s last steps for k robots at once, the very bits: G from `sums` (2k,) (every x
    sum, then every y sum of the views) over `n` robots, the gap from each view's `nearest` (k,)
    norm, then `_toward`: |G| by `math.hypot` per robot (CPython's, as `_toward`), the rest its
    operations on arrays (Python's min(a, b) is b only where b < a; a row that goes all the way
    is scaled by 1.0, which leaves every float as it is; a row that stays by 0.0, read by
    nobody)."""
    k = len(nearest)
    centre = sums / n  # (2k,)
    listed = centre.tolist()
    to_g = np.fromiter(map(math.hypot, listed[:k], listed[k:]), dtype=np.float64, count=k)
    gaps = nearest - CONTACT
    gaps /= 2.0
    short = gaps < to_g  # a step short of G (min(to_g, gap) is gap exactly there)
    step = np.where(short, gaps, to_g)
    goes = step > tolerance
    short &= goes  # scaled by step / |G| (> step > tolerance there)
    scale = np.divide(step, to_g, out=goes.astype(np.float64), where=short)
    ends = centre.reshape(2, k)
    ends *= scale
    return StraightMoves(ends.T, goes)


ALGORITHM: Final = Gathering()

__all__ = ["ALGORITHM", "DEFAULT_TOLERANCE", "Gathering", "GatheringParams", "centre_of_gravity"]
