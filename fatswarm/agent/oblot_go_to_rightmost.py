"""oblot-sim's `GoToRightMost`, ported: every robot moves straight to the position of largest x in
its own frame, its own included (docs/ports.md, "oblot-go-to-rightmost").
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

import numpy as np

from fatswarm.agent.oblot_common import (
    STAY,
    TOLERANCE_SPEC,
    OblotParams,
    gathered,
    go_to,
    make_oblot_params,
    peer_assumptions,
    spread,
)
from fatswarm.domain.assumptions import Assumptions
from fatswarm.domain.path import Path, Points
from fatswarm.domain.robot_model import Frames
from fatswarm.domain.seam import ParamSpec, ParamValue

# "Rightmost" is the robot's own x: the robots gather only if they agree on the x axis, as the
# peer's default frames do (one shared transformation, `Main.java:47-53`): both-axes.
# Until `both-axes` exists in this branch the declaration below is the nearest existing word,
# y-axis, which is NOT enough (a mirrored robot's rightmost is the others' leftmost).


class OblotGoToRightMost:
    """Rule: take the position with the largest x in the robot's frame, the robot itself (the
    origin) included, and move straight there (`algorithms/GoToRightMost.java:15`).

    Ties: the peer keeps the first maximum in robot-id order (Java's stream `max`), which an
    anonymous robot cannot name. Ours, the smallest order-free rule: the robot stays if nobody has
    a larger x than itself; otherwise, of the robots of largest x, the one of smallest y.
    """

    name: str = "oblot-go-to-rightmost"
    summary: str = (
        "oblot-sim's GoToRightMost: move to the robot of largest x (needs frames that agree on x)"
    )
    parameters: tuple[ParamSpec, ...] = (TOLERANCE_SPEC,)
    assumptions: Assumptions = peer_assumptions((Frames.BOTH_AXES,))

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> OblotParams:
        return make_oblot_params(n, values)

    def compute(self, view: Points, params: OblotParams) -> Path:
        """A Line to the rightmost robot, or STAY if that is this one."""
        if len(view) == 0:
            return STAY
        xs = view[:, 0]
        top = float(xs.max())
        if not top > 0.0:  # the robot itself (x = 0) is as far right as anyone
            return STAY
        tied = view[xs == top]
        k = int(np.argmin(tied[:, 1]))
        return go_to((top, float(tied[k, 1])), params)

    def goal(self, positions: Points, params: OblotParams) -> bool:
        """Every robot at one point (within GOAL_REL of the largest coordinate)."""
        return gathered(positions)

    def figures(self, positions: Points, params: OblotParams) -> dict[str, float]:
        return spread(positions)


ALGORITHM: Final = OblotGoToRightMost()

__all__ = ["ALGORITHM", "OblotGoToRightMost"]
