"""Point robots that meet: each goes straight to the centre of gravity of the robots it sees and
itself (each robot counted, so it needs multiplicity detection). For tests of `--bodies points`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Final

import numpy as np

from fatswarm.domain.assumptions import Assumptions
from fatswarm.domain.path import STAY, Line, Path, Points
from fatswarm.domain.robot_model import Bodies, Visibility
from fatswarm.domain.seam import ParamSpec, ParamValue

TOLERANCE: Final = 1e-6  # a robot this close to the centre of gravity stays


class Meet:
    name = "meet-points"
    summary = "point robots go to the centre of gravity of all (they meet there)"
    parameters: tuple[ParamSpec, ...] = ()
    assumptions = Assumptions(
        visibility=(Visibility.TRANSPARENT,),
        sight=(None,),
        frames=None,
        noise=(0.0,),
        bodies=(Bodies.POINTS,),
        multiplicity=True,
        knows_n=False,
    )

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> None:
        assert n is None  # it declares it does not know n
        return None

    def compute(self, view: Points, params: None) -> Path:
        k = len(view) + 1  # itself, at the origin, adds nothing to the sums
        gx = math.fsum(view[:, 0].tolist()) / k
        gy = math.fsum(view[:, 1].tolist()) / k
        if math.hypot(gx, gy) <= TOLERANCE:
            return STAY
        return Path((Line((gx, gy)),))

    def goal(self, positions: Points, params: None) -> bool:
        pts = np.asarray(positions, dtype=np.float64)
        return bool(np.ptp(pts[:, 0]) <= TOLERANCE and np.ptp(pts[:, 1]) <= TOLERANCE)


ALGORITHM = Meet()


class MeetOnce(Meet):
    """`meet-points` without multiplicity detection: it sees each occupied point once (the
    centre of gravity of the points it sees, itself among them)."""

    name = "meet-points-once"
    assumptions = Assumptions(
        visibility=(Visibility.TRANSPARENT,),
        sight=(None,),
        frames=None,
        noise=(0.0,),
        bodies=(Bodies.POINTS,),
        multiplicity=False,
        knows_n=False,
    )


ONCE = MeetOnce()
