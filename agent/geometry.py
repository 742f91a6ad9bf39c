"""Plane geometry the paper uses: smallest enclosing circle, free paths, symmetry, targets."""

from __future__ import annotations

import numpy as np

from agent.path import Points


def is_uniform_circle(positions: Points, a: float) -> bool:
    """True when the centres form a regular n-gon with side >= a (within tolerance)."""
    # placeholder until geometry lands
    del positions, a
    return False


__all__ = ["is_uniform_circle", "np"]
