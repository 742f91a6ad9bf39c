"""What the four ports of oblot-sim's algorithms share: the peer's tolerance, its refusals, the view
with the robot itself put back in, and the parameters and goals (docs/ports.md).

The peer (github:werner291/oblot-sim at db477c8) gives an algorithm every position, its own
included, at the origin of its frame; fatswarm's view leaves the robot out. Each port adds it back
as the first row of `with_self`, which is the only row a port may tell apart from the others.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Final

import numpy as np

from fatswarm.agent.geometry import Circle, sec
from fatswarm.agent.params import check_count, check_tolerance
from fatswarm.domain.assumptions import Assumptions, Movement
from fatswarm.domain.path import STAY, Line, Path, Points
from fatswarm.domain.robot_model import Bodies, Frames, Visibility
from fatswarm.domain.seam import AlgorithmParamsError, ParamSpec, ParamValue

# The model oblot-sim gives its algorithms (docs/ports.md, "Assumptions"): every robot seen
# (`Simulator/Simulation.java:101`), as points, one row per robot (multiplicity), n not given (the
# view's length), exact positions, FSYNC and SSYNC, rigid or not; frames are each algorithm's own.
PEER_MODEL: Final = Assumptions(
    visibility=(Visibility.TRANSPARENT,),
    sight=(None,),
    frames=None,
    noise=(0.0,),
    bodies=(Bodies.POINTS,),
    multiplicity=True,
    knows_n=False,
    schedulers=("fsync", "ssync"),
    movement=(Movement.RIGID, Movement.NON_RIGID),
)


def peer_assumptions(frames: tuple[Frames, ...] | None) -> Assumptions:
    """PEER_MODEL with what one algorithm needs of the peer's frames (None: any)."""
    return replace(PEER_MODEL, frames=frames)


PEER_EPSILON: Final = 1e-13
"""The peer's one tolerance (`Util/Config.java:30`): absolute for points, angles and the count
inside the circle; relative for "on the circle" (`Util/Circle.java:48`)."""

GOAL_REL: Final = 1e-9
"""The goals' tolerance, relative to max(1, the largest coordinate): the peer has no goal; this is
the one its recorded runs were cut at (tests/data/oblot/README.md), applied to world positions."""

TOLERANCE_SPEC: Final = ParamSpec(
    "tolerance",
    0.0,
    "a robot stays when its target is within this distance of it; 0 is the peer's rule (it moves "
    "unless the target is exactly where it stands)",
)


class OblotRuleError(ValueError):
    """A configuration the peer's algorithm refuses or cannot handle (the peer throws there too);
    the message names the rule and the peer's file and line."""


@dataclass(frozen=True, slots=True)
class OblotParams:
    """n (None when the world does not give it: the ports take n from the view, as the peer
    does) and the `tolerance` below which a target counts as where the robot stands (>= 0)."""

    n: int | None
    tolerance: float = 0.0

    def __post_init__(self) -> None:
        check_count(self.n)
        check_tolerance(self.tolerance, zero_ok=True)


def make_oblot_params(n: int | None, values: Mapping[str, ParamValue]) -> OblotParams:
    """The ports' parameters from `--param` values (defaults filled in)."""
    tol = values.get("tolerance", 0.0)
    if isinstance(tol, bool) or not isinstance(tol, (int, float)):
        raise AlgorithmParamsError(f"tolerance must be a number, got {tol!r}")
    return OblotParams(n, float(tol))


def with_self(view: Points) -> Points:
    """(k + 1, 2): the robot itself at the origin (row 0), then the view's rows."""
    pts = np.zeros((len(view) + 1, 2), dtype=np.float64)
    if len(view):
        pts[1:] = np.asarray(view, dtype=np.float64)
    return pts


def circle_of(points: Points) -> Circle:
    """The smallest enclosing circle (`fatswarm.agent.geometry.sec`) of `points` taken in sorted
    order, so that its rounding does not depend on the order of the view's rows."""
    pts = np.asarray(points, dtype=np.float64)
    return sec(pts[np.lexsort((pts[:, 1], pts[:, 0]))])


def go_to(target: tuple[float, float], params: OblotParams) -> Path:
    """A straight move to `target` (the peer's `LinearPath`), or STAY when it is within
    `tolerance` of the origin (exactly the origin under the peer's rule, tolerance 0)."""
    x, y = target
    return Path((Line((x, y)),)) if goes_to(target, params) else STAY


def goes_to(target: tuple[float, float], params: OblotParams) -> bool:
    """Whether `go_to` moves to `target` (False: STAY); raises its OblotRuleError where the
    target is not a finite point."""
    x, y = target
    if not (math.isfinite(x) and math.isfinite(y)):
        raise OblotRuleError(f"the target ({x}, {y}) is not a finite point")
    return not math.hypot(x, y) <= params.tolerance


def same_point(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """The peer's point equality: each coordinate within PEER_EPSILON (`Vector.java:261,268`)."""
    return abs(a[0] - b[0]) < PEER_EPSILON and abs(a[1] - b[1]) < PEER_EPSILON


def gathered(positions: Points) -> bool:
    """Every robot within GOAL_REL * max(1, largest coordinate) of the first one."""
    pts = np.asarray(positions, dtype=np.float64)
    if len(pts) <= 1:
        return True
    spread = float(np.hypot(pts[:, 0] - pts[0, 0], pts[:, 1] - pts[0, 1]).max())
    return spread <= GOAL_REL * max(1.0, float(np.abs(pts).max()))


def spread(positions: Points) -> dict[str, float]:
    """`spread`: the largest distance of a robot from the centre of gravity."""
    pts = np.asarray(positions, dtype=np.float64)
    if len(pts) == 0:
        return {"spread": 0.0}
    gx = math.fsum(pts[:, 0].tolist()) / len(pts)
    gy = math.fsum(pts[:, 1].tolist()) / len(pts)
    return {"spread": float(np.hypot(pts[:, 0] - gx, pts[:, 1] - gy).max())}


__all__ = [
    "GOAL_REL",
    "PEER_EPSILON",
    "STAY",
    "TOLERANCE_SPEC",
    "Circle",
    "OblotParams",
    "OblotRuleError",
    "circle_of",
    "gathered",
    "go_to",
    "goes_to",
    "make_oblot_params",
    "same_point",
    "spread",
    "with_self",
]
