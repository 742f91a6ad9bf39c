"""The dashboard never shows a formation reached through collisions as a plain FORMED."""

from __future__ import annotations

import numpy as np

from fatswarm.deploy.view.dashboard import Frame, outcome_text
from fatswarm.domain.outcome import Status

SQUARE = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]])


def formed(collisions: int) -> Frame:
    return Frame(
        round=12,
        n=4,
        a=4.0,
        scheduler="ssync",
        positions=SQUARE,
        status=Status.FORMED,
        collisions_total=collisions,
    )


def test_a_formation_without_collisions_is_shown_as_formed() -> None:
    assert outcome_text(formed(0)) == (
        "FORMED: uniform-circle goal reached by 4 robots after 12 rounds, 0 collisions"
    )


def test_a_formation_through_collisions_says_it_is_not_collision_free() -> None:
    assert outcome_text(formed(2)) == (
        "FORMED WITH 2 COLLISIONS: uniform-circle goal reached by 4 robots after 12 rounds, "
        "not collision-free"
    )
    assert outcome_text(formed(1)).startswith("FORMED WITH 1 COLLISION:")
