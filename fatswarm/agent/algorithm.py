"""The paper's algorithm as a pure function of one snapshot in the robot's own frame.

`compute(view, params)` is what an agent runs in its Compute phase. It builds the *plan* of the
whole configuration (one mover, or one mirror pair: docs/algorithm.md, G11) and returns the
observer's own part of it. The plan is made on the canonical form of the view (agent/canonical.py),
the same bits in every robot whatever its position, flip or view order, so every robot that looks
at the same configuration makes the very same plan. No state survives a call: there is no module
or instance state here. The phases are agent/expansion.py (SECExpansion) and agent/formation.py
(FormUCircle).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fatswarm.agent.canonical import Canonical, canonical
from fatswarm.agent.expansion import sec_expansion
from fatswarm.agent.formation import form_u_circle
from fatswarm.agent.geometry import is_uniform_circle, sec, target_radius
from fatswarm.agent.params import Params
from fatswarm.agent.planning import Ctx, orientation_of
from fatswarm.domain.path import STAY, Path, Points
from fatswarm.domain.tolerance import EPS_AT_REL, EPS_EQ_REL, MAX_COORD, scale, snap

VIEW_LIMIT = 4.0 * MAX_COORD
"""Relative coordinates a view may hold: twice the span of supported world coordinates, and room."""


class ViewError(ValueError):
    """The snapshot does not fit the parameters (wrong shape, count or non-finite values)."""


@dataclass(frozen=True, slots=True)
class Plan:
    """What the configuration asks for: `moves` maps robot index -> path in the given frame."""

    phase: str  # "done" | "expansion" | "formation" | "stuck"
    kind: str  # "done", "exp-case1|2|2b-north", "fill", "detour", "note-swap", "stuck"
    moves: dict[int, Path] = field(default_factory=dict)


def compute(view: Points, params: Params) -> Path:
    """The observer's path: `view` (n-1, 2) holds the others relative to it, in its own frame.

    The view is put on the grid and in canonical form (agent/canonical.py), the plan is made there,
    on the same bits in every robot, and the observer's part is mapped back to its own frame.
    """
    canon = canonical_view(view, params)
    return canon.to_frame(plan(canon.points, params).moves.get(canon.observer, STAY))


def canonical_view(view: Points, params: Params) -> Canonical:
    """The observer (at the origin) and its view, on the grid and in canonical form."""
    return canonical(_with_observer(view, params), 0)


def _with_observer(view: Points, params: Params) -> Points:
    arr = np.asarray(view, dtype=np.float64)
    if arr.size == 0:
        arr = arr.reshape(0, 2)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ViewError(f"the view must be an (n-1, 2) array, got shape {arr.shape}")
    if len(arr) != params.n - 1:
        raise ViewError(f"the view holds {len(arr)} robots, expected n-1 = {params.n - 1}")
    if len(arr):
        size = np.abs(arr)
        if not float(size.flat[size.argmax()]) <= VIEW_LIMIT:  # NaN fails the comparison too
            if not np.isfinite(arr).all():
                raise ViewError("the view holds non-finite coordinates")
            raise ViewError(f"the view reaches beyond +-{VIEW_LIMIT:g}, outside the grid's range")
    out = np.empty((len(arr) + 1, 2), dtype=np.float64)
    out[0] = 0.0  # the observer, on the grid already
    snap(arr, out=out[1:])
    return out


def plan(points: Points, params: Params) -> Plan:
    """The plan of the configuration `points` (n, 2): which robots move, and how, in that frame.

    `compute` calls it on the canonical form, so that every robot makes the very same plan.
    """
    n = len(points)
    if n <= 1:
        return Plan("done", "done")
    circle = sec(points)
    if is_uniform_circle(points, params.a, circle):  # G10: a regular n-gon is final, aligned or not
        return Plan("done", "done")
    s = scale(circle.radius)
    tol_at, tol_eq = EPS_AT_REL * s, EPS_EQ_REL * s
    r = target_radius(n, params.a)
    if circle.radius < r - tol_eq:  # G2
        phase, step = "expansion", sec_expansion(points, circle, tol_at, tol_eq, r)
    else:  # only FormUCircle needs the agreed side
        orientation = orientation_of(points, circle.center[0], tol_at, tol_eq)
        ctx = Ctx(points, circle, tol_at, tol_eq, r, orientation)
        phase, step = "formation", form_u_circle(ctx, n)
    if step is None:
        return Plan("stuck", "stuck")
    kind, moves = step
    return Plan(phase, kind, moves)
