"""The paper's algorithm as a pure function of one snapshot in the robot's own frame."""

from __future__ import annotations

from agent.params import Params
from agent.path import STAY, Path, Points


def compute(view: Points, params: Params) -> Path:
    """The path the observer (at the origin) wants, given the others' positions `view` (n-1, 2)."""
    # placeholder until the algorithm lands (being written now); returns "stay"
    del view, params
    return STAY
