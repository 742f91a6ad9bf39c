"""The dashboard's targets counter counts corners of one regular n-gon on the SEC, however it is
turned: a formed run shows n / n (an n = 2 run showed 0 / 2 when formed)."""

from __future__ import annotations

import numpy as np

import fatswarm
from fatswarm.deploy.view.panels import polygon_filled


def test_a_turned_regular_polygon_fills_every_corner_and_a_gap_does_not() -> None:
    t = np.linspace(0.0, 2 * np.pi, 7, endpoint=False) + 0.3
    ring = np.c_[5 * np.cos(t), 5 * np.sin(t)]
    assert polygon_filled(ring, (0.0, 0.0), 5.0, 7, 1e-6) == 7
    assert polygon_filled(ring[:5], (0.0, 0.0), 5.0, 6, 1e-6) == 1  # 5 of a 7-gon: no 6-gon
    off = ring.copy()
    off[2] *= 0.9  # inside the circle: not on a corner
    assert polygon_filled(off, (0.0, 0.0), 5.0, 7, 1e-6) == 6


def test_a_formed_run_of_two_fills_both_targets() -> None:
    result = fatswarm.run(2, seed=1, scheduler="fsync")
    pts = result.positions
    center = tuple(pts.mean(axis=0))
    rc = float(np.hypot(*(pts[0] - pts[1]))) / 2
    assert str(result.status) == "formed"
    assert polygon_filled(pts, (float(center[0]), float(center[1])), rc, 2, 1e-6) == 2
