"""oblot-sim's `MoveAlongSEC`, ported: every robot goes to the nearest point of the smallest
enclosing circle and then half a turn along it (docs/ports.md, "oblot-move-along-sec").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Final

import numpy as np

from fatswarm.agent.oblot_common import (
    GOAL_REL,
    PEER_EPSILON,
    STAY,
    TOLERANCE_SPEC,
    OblotParams,
    circle_of,
    make_oblot_params,
    peer_assumptions,
    with_self,
)
from fatswarm.domain.assumptions import Assumptions
from fatswarm.domain.path import Arc, Line, Path, Points, Segment
from fatswarm.domain.robot_model import Frames
from fatswarm.domain.seam import ParamSpec, ParamValue

HALF_TURN: Final = math.pi
"""The arc's sweep: anticlockwise in the robot's frame (`clockwise = false`,
`algorithms/MoveAlongSEC.java:20`); the peer's world turns it the other way (docs/ports.md)."""

# The circle needs no agreement on axes; the arc's sense (anticlockwise) needs a common handedness.


class OblotMoveAlongSEC:
    """Rule 1: the smallest enclosing circle of every position, the robot's own included
    (`algorithms/MoveAlongSEC.java:17`; the peer's is Welzl's randomized algorithm,
    `Util/SmallestEnclosingCircle.java`, ours `fatswarm.agent.geometry.sec`: the same circle up to
    rounding). Rule 2: the point of the circle nearest the robot: the robot itself if it is on the
    circle within the peer's relative tolerance, else its radial projection (`:18`,
    `Util/Circle.java:47-64`). Rule 3: straight there, then half a turn about the centre, with
    `clockwise = false` (`:19-23`).

    Where the peer is silent: a robot exactly at the circle's centre has no nearest point (the
    peer divides by zero there, `Util/Circle.java:62`, and its robot goes to NaN): ours stays, the
    smallest rule. All robots at one point (radius 0): the peer's path has length 0; ours stays.
    """

    name: str = "oblot-move-along-sec"
    summary: str = (
        "oblot-sim's MoveAlongSEC: to the nearest point of the smallest enclosing circle, then "
        "half a turn along it (never stays)"
    )
    parameters: tuple[ParamSpec, ...] = (TOLERANCE_SPEC,)
    assumptions: Assumptions = peer_assumptions((Frames.BOTH_AXES, Frames.CHIRALITY))

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> OblotParams:
        return make_oblot_params(n, values)

    def compute(self, view: Points, params: OblotParams) -> Path:
        """A Line to the circle (none when on it), then an anticlockwise half turn."""
        circle = circle_of(with_self(view))
        cx, cy = circle.center
        r = circle.radius
        if not r > 0.0:
            return STAY
        here = math.hypot(cx, cy)  # the robot's distance from the centre
        segments: list[Segment] = []
        if not (r * (1.0 - PEER_EPSILON) < here < r * (1.0 + PEER_EPSILON)):
            if here == 0.0:  # at the centre: no nearest point (the peer divides by zero)
                return STAY
            f = r / here
            on_x, on_y = cx + (0.0 - cx) * f, cy + (0.0 - cy) * f
            if math.hypot(on_x, on_y) > params.tolerance:
                segments.append(Line((on_x, on_y)))
        segments.append(Arc((cx, cy), HALF_TURN))
        return Path(tuple(segments))

    def goal(self, positions: Points, params: OblotParams) -> bool:
        """Every robot on the smallest enclosing circle (within GOAL_REL * max(1, r))."""
        pts = np.asarray(positions, dtype=np.float64)
        if len(pts) <= 1:
            return True
        circle = circle_of(pts)
        cx, cy = circle.center
        off = np.abs(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) - circle.radius)
        return bool(float(off.max()) <= GOAL_REL * max(1.0, circle.radius))

    def figures(self, positions: Points, params: OblotParams) -> dict[str, float]:
        """`off circle`: the largest distance of a robot from the smallest enclosing circle."""
        pts = np.asarray(positions, dtype=np.float64)
        if len(pts) == 0:
            return {"off circle": 0.0}
        circle = circle_of(pts)
        cx, cy = circle.center
        off = np.abs(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) - circle.radius)
        return {"off circle": float(off.max())}


ALGORITHM: Final = OblotMoveAlongSEC()

__all__ = ["ALGORITHM", "HALF_TURN", "OblotMoveAlongSEC"]
