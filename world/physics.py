"""Disc physics of one round: movers start together at unit speed; continuous collision detection.

API CONTRACT (stub; the physics helper replaces the bodies, keeps the signatures).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from agent.path import Path, Points


class InvalidConfigurationError(ValueError):
    """A configuration no run may start from (overlap, NaN, infinity, wrong shape)."""


@dataclass(frozen=True, slots=True)
class Collision:
    """Robot `robot` was stopped at time `t` (= arc length travelled) by contact with `other`."""

    robot: int
    other: int
    t: float
    point: tuple[float, float]


@dataclass(frozen=True, slots=True)
class RoundOutcome:
    """Positions after the round, arc length each mover covered, and contacts that stopped movers."""

    positions: Points
    traveled: dict[int, float] = field(default_factory=dict)
    collisions: list[Collision] = field(default_factory=list)


def validate_configuration(positions: Points) -> Points:
    """Return positions as an (n, 2) float64 array or raise InvalidConfigurationError."""
    raise NotImplementedError


def apply_round(positions: Points, paths: Mapping[int, Path]) -> RoundOutcome:
    """Move every robot of `paths` along its path (world frame) at once, stopping at contact."""
    raise NotImplementedError


__all__ = ["np"]
