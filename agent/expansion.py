"""SECExpansion (docs/algorithm.md, G2-G5): while the SEC is smaller than the target circle, leaders
elected among the robots on it move radially outward."""

from __future__ import annotations

import numpy as np

from fatswarm.agent.geometry import Circle, is_free, mirror_matched
from fatswarm.agent.planning import Ctx, Step, first_ranked, without
from fatswarm.domain.path import Line, Path, Points

EXPANSION_OVERSHOOT = 1e-9
"""Expansion aims at 2r(1 + this) so that rounding cannot leave r_c just below r (G2)."""


def sec_expansion(ctx: Ctx, r: float) -> Step | None:
    """SECExpansion with leader election on the SEC robots (G3, G4) and radial moves (G5); None
    if no leader can move (stuck)."""
    pts, c = ctx.pts, ctx.circle
    cx, cy = c.center
    dist = np.hypot(pts[:, 0] - cx, pts[:, 1] - cy)
    on_sec = (dist >= c.radius - ctx.tol_at).nonzero()[0]
    sec_pts = pts[on_sec]
    matched = mirror_matched(sec_pts, cx, ctx.tol_at)
    on_l = np.abs(sec_pts[:, 0] - cx) <= ctx.tol_at
    if not matched.all():  # case 1: the unmatched SEC robot with maximum Y
        cand = (~matched).nonzero()[0]
        keys = (-sec_pts[cand, 1], -np.abs(sec_pts[cand, 0] - cx))
        leaders = [int(on_sec[cand[first_ranked(keys, ctx.tol_eq)]])]
        kind = "exp-case1"
    elif (~on_l).any():  # case 2 (a or b): the top mirror pair off L
        cand = (~on_l).nonzero()[0]
        top = int(cand[np.argmax(sec_pts[cand, 1])])
        mx, my = 2.0 * cx - sec_pts[top, 0], sec_pts[top, 1]
        partner = int(np.argmin(np.hypot(sec_pts[:, 0] - mx, sec_pts[:, 1] - my)))
        leaders = sorted({int(on_sec[top]), int(on_sec[partner])})
        kind = "exp-case2"
    else:  # G4: every SEC robot is on L; the north one leads
        leaders = [int(on_sec[np.argmax(sec_pts[:, 1])])]
        kind = "exp-case2b-north"
    moves: dict[int, Path] = {}
    for leader in leaders:
        path = _radial_move(pts, leader, c, 2.0 * r * (1.0 + EXPANSION_OVERSHOOT))
        if path is not None:
            moves[leader] = path
    if not moves:
        return None
    return kind, moves


def _radial_move(pts: Points, leader: int, circle: Circle, reach: float) -> Path | None:
    """Move `leader` outward along the ray from the SEC centre until its farthest robot is `reach`
    away (G5). Distances to every robot inside the SEC only grow along this ray: collision free.
    """
    p = pts[leader]
    u = p - np.asarray(circle.center)
    norm = float(np.hypot(u[0], u[1]))
    if norm == 0.0:
        return None
    u = u / norm
    others = without(pts, leader)
    d = p - others
    b = d @ u
    t = -b + np.sqrt(np.maximum(b * b - np.einsum("ij,ij->i", d, d) + reach * reach, 0.0))
    step = float(t.min())
    if step <= 0.0:
        return None
    end = (float(p[0] + step * u[0]), float(p[1] + step * u[1]))
    path = Path((Line(end),))
    start = (float(p[0]), float(p[1]))
    return path if is_free(start, path, others) else None
