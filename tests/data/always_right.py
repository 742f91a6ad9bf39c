"""A planted failure for `fatswarm hunt`: every robot always moves +x by `step` in its own frame.

Each robot's X axis is flipped at random (from the run's seed), so "right" is either way in the
world: two robots facing each other collide, and a swarm that never collides never stays, so it
runs past its round cap. Its goal never holds. tests/unit/test_hunt.py hunts it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Final

from fatswarm.domain.path import Line, Path, Points
from fatswarm.domain.seam import AlgorithmParamsError, ParamSpec, ParamValue

DEFAULT_STEP: Final = 3.0


class AlwaysRight:
    """Move `step` to the right of the private frame, whatever the robot sees."""

    name = "always-right"
    summary = "a planted failure: every robot moves +x by `step` in its own frame, always"
    parameters: tuple[ParamSpec, ...] = (
        ParamSpec("step", DEFAULT_STEP, "how far every robot moves right each time (> 0)"),
    )

    def make_params(self, n: int, values: Mapping[str, ParamValue]) -> float:
        step = values.get("step", DEFAULT_STEP)
        if (
            isinstance(step, bool)
            or not isinstance(step, (int, float))
            or not (math.isfinite(step) and step > 0.0)
        ):
            raise AlgorithmParamsError(f"step must be finite and > 0, got {step!r}")
        return float(step)

    def compute(self, view: Points, params: float) -> Path:
        """+x by `params`, in the robot's own frame (X may be flipped in the world)."""
        return Path((Line((params, 0.0)),))

    def goal(self, positions: Points, params: float) -> bool:
        """Never: the run ends only by a stall (it never stays) or at its round cap."""
        return False


ALGORITHM: Final = AlwaysRight()
