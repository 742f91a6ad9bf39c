"""FormUCircle's early refusal of a move that changes the SEC is sound: whenever
`_moves_the_sec` says so, `_keeps_sec` refuses the move to the target, and to any end within
END_MATCH of it, so skipping the path search changes no plan.

Swarms are drawn to sit at the edge of the test: robots on the SEC and pulled inside it by a few
tol_at around the band `_moves_the_sec` looks at, targets anywhere on the circle.
"""

from __future__ import annotations

import math

import numpy as np

from fatswarm.agent.detour import END_MATCH
from fatswarm.agent.formation import SURE_SEC, _keeps_sec, _moves_the_sec
from fatswarm.agent.geometry import sec, target_radius
from fatswarm.agent.planning import Ctx, without
from fatswarm.domain.path import Line, Path
from fatswarm.domain.tolerance import EPS_AT_REL, EPS_EQ_REL, scale, snap

RNG = np.random.default_rng(9)
DEPTHS = (0.0, 0.5, 1.0, 2.0, SURE_SEC - 0.1, SURE_SEC, 2 * SURE_SEC - 0.1, 2 * SURE_SEC, 20.0)


def swarm() -> np.ndarray:
    """Robots on and just inside a circle (depths in units of tol_at), and some well inside."""
    radius = float(RNG.uniform(3.0, 60.0))
    tol = EPS_AT_REL * scale(radius)
    rim = int(RNG.integers(2, 7))
    angles = RNG.uniform(-math.pi, math.pi, rim)
    depths = RNG.choice(DEPTHS, rim) * tol
    depths[:2] = 0.0
    r = radius - depths
    pts = [np.stack([r * np.cos(angles), r * np.sin(angles)], axis=1)]
    inner = int(RNG.integers(0, 6))
    rho = radius * np.sqrt(RNG.uniform(0.0, 0.8, inner))
    phi = RNG.uniform(-math.pi, math.pi, inner)
    pts.append(np.stack([rho * np.cos(phi), rho * np.sin(phi)], axis=1))
    return snap(np.concatenate(pts) + RNG.uniform(-5.0, 5.0, 2))


def test_an_early_refusal_is_a_refusal_of_every_end_near_the_target() -> None:
    refused = 0
    for _ in range(600):
        pts = swarm()
        circle = sec(pts)
        s = scale(circle.radius)
        ctx = Ctx(pts, circle, EPS_AT_REL * s, EPS_EQ_REL * s, target_radius(3, 4.0), 1.0)
        cx, cy = circle.center
        for i in range(len(pts)):
            start = (float(pts[i, 0]), float(pts[i, 1]))
            others = without(pts, i)
            for phi in RNG.uniform(-math.pi, math.pi, 6):
                target = (cx + circle.radius * math.cos(phi), cy + circle.radius * math.sin(phi))
                if not _moves_the_sec(ctx, start, target, others):
                    continue
                refused += 1
                for dx, dy in ((0.0, 0.0), (END_MATCH, 0.0), (0.0, -END_MATCH), (1e-12, 1e-12)):
                    end = (target[0] + dx, target[1] + dy)
                    assert not _keeps_sec(ctx, {i: Path((Line(end),))}), (pts.tolist(), i, end)
    assert refused > 500  # the draw does reach the early refusal
