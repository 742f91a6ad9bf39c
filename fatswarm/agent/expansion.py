"""SECExpansion (docs/algorithm.md, G2-G5): while the SEC is smaller than the target circle, leaders
elected among the robots on it move radially outward."""

from __future__ import annotations

import numpy as np

from fatswarm.agent.geometry import Circle, is_free, mirror_matched
from fatswarm.agent.planning import Step, first_ranked, without
from fatswarm.domain.path import Line, Path, Points

EXPANSION_OVERSHOOT = 1e-9
"""Expansion aims at 2r(1 + this) so that rounding cannot leave r_c just below r (G2)."""


def sec_expansion(
    pts: Points, circle: Circle, tol_at: float, tol_eq: float, r: float
) -> Step | None:
    """SECExpansion with leader election on the SEC robots (G3, G4) and radial moves (G5); None
    if no leader can move (stuck)."""
    cx, cy = circle.center
    dist = np.hypot(pts[:, 0] - cx, pts[:, 1] - cy)
    on_sec = (dist >= circle.radius - tol_at).nonzero()[0]
    sec_pts = pts.take(on_sec, axis=0)
    sec_x, sec_y = sec_pts[:, 0], sec_pts[:, 1]
    unmatched = ~mirror_matched(sec_pts, cx, tol_at)
    if unmatched[unmatched.argmax()]:  # case 1: the unmatched SEC robot with maximum Y
        cand = unmatched.nonzero()[0]
        best = first_ranked(-sec_y[cand], tol_eq, lambda: (-np.abs(sec_x[cand] - cx),))
        leaders = [int(on_sec[cand[best]])]
        kind = "exp-case1"
    else:
        off_l = np.abs(sec_x - cx) > tol_at
        if off_l[off_l.argmax()]:  # case 2 (a or b): the top mirror pair off L
            cand = off_l.nonzero()[0]
            top = int(cand[np.argmax(sec_y[cand])])
            mx, my = 2.0 * cx - sec_x[top], sec_y[top]
            partner = int(np.argmin(np.hypot(sec_x - mx, sec_y - my)))
            leaders = sorted({int(on_sec[top]), int(on_sec[partner])})
            kind = "exp-case2"
        else:  # G4: every SEC robot is on L; the north one leads
            leaders = [int(on_sec[np.argmax(sec_y)])]
            kind = "exp-case2b-north"
    moves: dict[int, Path] = {}
    for leader in leaders:
        path = _radial_move(pts, leader, circle, 2.0 * r * (1.0 + EXPANSION_OVERSHOOT))
        if path is not None:
            moves[leader] = path
    if not moves:
        return None
    return kind, moves


def _radial_move(pts: Points, leader: int, circle: Circle, reach: float) -> Path | None:
    """Move `leader` outward along the ray from the SEC centre until its farthest robot is `reach`
    away (G5). Distances to every robot inside the SEC only grow along this ray: collision free.
    """
    px, py = float(pts[leader, 0]), float(pts[leader, 1])
    ux, uy = px - circle.center[0], py - circle.center[1]
    norm = float(np.hypot(ux, uy))
    if norm == 0.0:
        return None
    ux, uy = ux / norm, uy / norm
    others = without(pts, leader)
    d = pts[leader] - others
    dx, dy = d[:, 0], d[:, 1]
    # Dot products written out (each product rounded, then the sum): `@` goes to BLAS, whose
    # kernel (fused multiply-add or not) depends on the CPU, and the plan must not.
    b = dx * ux + dy * uy
    e = b * b
    e -= dx * dx + dy * dy
    e += reach * reach
    t = np.sqrt(np.maximum(e, 0.0, out=e), out=e)
    t -= b
    step = float(t[t.argmin()])
    if step <= 0.0:
        return None
    path = Path((Line((px + step * ux, py + step * uy)),))
    return path if is_free((px, py), path, others) else None
