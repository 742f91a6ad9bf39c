"""Geometry: exact smallest enclosing circle, free paths, vacancy, targets, uniform circles."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.agent.geometry import (
    Circle,
    arc_distances,
    is_free,
    is_uniform_circle,
    is_vacant,
    mirror_matched,
    path_x_range,
    sec,
    target_points,
    target_radius,
    targets_on,
)
from fatswarm.domain.path import Arc, Line, Path
from fatswarm.domain.tolerance import CONTACT


def brute_force_sec(pts: np.ndarray) -> float:
    """Oracle: the smallest circle through 2 or 3 of the points that encloses them all."""
    best = math.inf
    n = len(pts)
    if n == 1:
        return 0.0
    cands: list[tuple[float, float, float]] = []
    for i, j in itertools.combinations(range(n), 2):
        c = (pts[i] + pts[j]) / 2
        cands.append((c[0], c[1], float(np.hypot(*(pts[i] - c)))))
    for i, j, k in itertools.combinations(range(n), 3):
        (ax, ay), (bx, by), (cx, cy) = pts[i], pts[j], pts[k]
        d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
        if abs(d) < 1e-12:
            continue
        a2, b2, c2 = ax**2 + ay**2, bx**2 + by**2, cx**2 + cy**2
        ux = (a2 * (by - cy) + b2 * (cy - ay) + c2 * (ay - by)) / d
        uy = (a2 * (cx - bx) + b2 * (ax - cx) + c2 * (bx - ax)) / d
        cands.append((ux, uy, float(np.hypot(ax - ux, ay - uy))))
    for ux, uy, r in cands:
        if np.all(np.hypot(pts[:, 0] - ux, pts[:, 1] - uy) <= r * (1 + 1e-9) + 1e-12):
            best = min(best, r)
    return best


coords = st.floats(min_value=-50, max_value=50, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(coords, coords), min_size=1, max_size=9))
def test_sec_matches_brute_force_oracle(raw: list[tuple[float, float]]) -> None:
    pts = np.array(raw, dtype=np.float64)
    c = sec(pts)
    assert c.radius == pytest.approx(brute_force_sec(pts), rel=1e-9, abs=1e-9)
    d = np.hypot(pts[:, 0] - c.center[0], pts[:, 1] - c.center[1])
    assert np.all(d <= c.radius * (1 + 1e-9) + 1e-12)


def test_sec_of_a_nearly_right_triangle_encloses_its_right_angle() -> None:
    # its circumcircle and the diametral circle of the long side round to one radius: the SEC
    # once kept the diametral one, with (0, 0) 9e-9 outside
    pts = np.array([(0.0, 0.0), (1.0, 0.0), (1e-7, 11.0)])
    c = sec(pts)
    d = np.hypot(pts[:, 0] - c.center[0], pts[:, 1] - c.center[1])
    assert np.all(d <= c.radius * (1 + 1e-12))


def test_sec_of_collinear_points_is_the_extreme_pair() -> None:
    pts = np.array([[0.0, -3.0], [0.0, 1.0], [0.0, 5.0], [0.0, -1.0]])
    c = sec(pts)
    assert c.center == pytest.approx((0.0, 1.0))
    assert c.radius == pytest.approx(4.0)


def test_sec_of_cocircular_points_is_their_circle() -> None:
    ang = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    pts = np.stack([3 + 7 * np.cos(ang), -2 + 7 * np.sin(ang)], axis=1)
    c = sec(pts)
    assert c.center == pytest.approx((3.0, -2.0), abs=1e-12)
    assert c.radius == pytest.approx(7.0, rel=1e-12)


def test_sec_with_near_duplicate_points_is_stable() -> None:
    pts = np.array([[0.0, 0.0], [1e-13, 0.0], [10.0, 0.0], [10.0, 1e-13], [5.0, 5.0]])
    assert sec(pts).radius == pytest.approx(brute_force_sec(pts), rel=1e-9)


def test_sec_of_one_point_has_radius_zero() -> None:
    assert sec(np.array([[2.0, 3.0]])) == Circle((2.0, 3.0), 0.0)


def test_sec_refuses_a_wrong_shape() -> None:
    with pytest.raises(ValueError, match="n, 2"):
        sec(np.zeros((0, 2)))


def test_target_radius_uses_side_at_least_four() -> None:
    # G1: a* = max(a, 4)
    assert target_radius(8, 3.1) == pytest.approx(4 / (2 * math.sin(math.pi / 8)))
    assert target_radius(6, 10.5) == pytest.approx(10.5)
    assert target_radius(1, 4.0) == 0.0


def test_targets_start_at_o_in_case_i_and_half_a_step_away_in_case_ii() -> None:
    c = Circle((1.0, 2.0), 5.0)
    t_i = targets_on(c, 4, robot_at_o=True)
    assert any(np.allclose(t, (1.0, 7.0)) for t in t_i)
    t_ii = targets_on(c, 4, robot_at_o=False)
    h = 5 / math.sqrt(2)
    assert sorted(map(tuple, np.round(t_ii - (1.0, 2.0), 9))) == sorted(
        (round(sx * h, 9), round(sy * h, 9)) for sx in (1, -1) for sy in (1, -1)
    )


def test_target_points_are_mirror_symmetric_about_l() -> None:
    pts = np.array([[0.0, 5.0], [4.0, 3.0], [-1.0, -5.0], [2.0, 0.0], [-3.0, 1.0]])
    t = target_points(pts)
    c = sec(pts)
    assert mirror_matched(t, c.center[0], 1e-9).all()


def test_capsule_catches_a_robot_just_beyond_the_destination() -> None:
    # G6, E13: the paper's rectangle says free, the end disc would overlap
    path = Path((Line((5.0, 0.0)),))
    assert not is_free((0.0, 0.0), path, np.array([[6.5, 0.0]]))


def test_touching_neighbours_behind_or_beside_do_not_block() -> None:
    path = Path((Line((5.0, 0.0)),))
    assert is_free((0.0, 0.0), path, np.array([[-2.0, 0.0]]))
    assert is_free((0.0, 0.0), path, np.array([[2.0, 2.0]]))


def test_a_robot_grazing_the_segment_blocks_it() -> None:
    path = Path((Line((5.0, 0.0)),))
    assert not is_free((0.0, 0.0), path, np.array([[0.3, 1.98]]))  # E19


def test_arc_distance_to_a_point_beside_the_sweep_uses_the_ends() -> None:
    # quarter arc from (2,0) to (0,2) about the origin; the point (-2,0) is off the sweep
    d = arc_distances((2.0, 0.0), Arc((0.0, 0.0), math.pi / 2), np.array([[-2.0, 0.0], [0.0, 3.0]]))
    assert d[0] == pytest.approx(math.hypot(2, 2))
    assert d[1] == pytest.approx(1.0)


def test_vacant_point_needs_every_other_centre_two_away() -> None:
    assert is_vacant((0.0, 0.0), np.array([[2.0, 0.0]]))
    assert not is_vacant((0.0, 0.0), np.array([[1.999, 0.0]]))


def test_path_x_range_includes_arc_extremes() -> None:
    lo, hi = path_x_range((0.0, 1.0), Path((Arc((0.0, 0.0), math.pi),)))
    assert lo == pytest.approx(-1.0, abs=1e-12)
    assert hi == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("n", [3, 4, 5, 7, 12])
def test_regular_polygon_with_long_sides_is_uniform_at_any_rotation(n: int) -> None:
    r = target_radius(n, 4.0)
    ang = 0.3 + np.arange(n) * 2 * np.pi / n
    pts = np.stack([10 + r * np.cos(ang), -4 + r * np.sin(ang)], axis=1)
    assert is_uniform_circle(pts, 4.0)
    assert not is_uniform_circle(pts * 0.9, 4.0)  # too small: side 3.6 < 4


def test_uneven_circle_is_not_uniform() -> None:
    ang = np.array([0.0, 1.0, 2.5, 4.0])
    pts = np.stack([10 * np.cos(ang), 10 * np.sin(ang)], axis=1)
    assert not is_uniform_circle(pts, 4.0)


def test_two_robots_are_uniform_when_far_enough_apart() -> None:
    assert is_uniform_circle(np.array([[2.598, 1.5], [-2.598, -1.5]]), 4.0)  # E12
    assert not is_uniform_circle(np.array([[1.0, 0.0], [-1.0, 0.0]]), 4.0)


def test_contact_is_two_radii() -> None:
    assert CONTACT == 2.0


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(st.integers(-4, 4), st.integers(-3, 3)), min_size=1, max_size=30),
    st.floats(-3, 3),
)
def test_mirror_matching_agrees_with_all_pairs(cells: list[tuple[int, int]], axis: float) -> None:
    # integer grids make many robots share a Y, exercising both the window and the dense path
    pts = np.array([(axis + 1.5 * x, 2.0 * y) for x, y in cells], dtype=np.float64)
    mx = 2 * axis - pts[:, 0]
    dense = (
        np.hypot(mx[:, None] - pts[None, :, 0], pts[:, None, 1] - pts[None, :, 1]).min(axis=1)
        <= 1e-6
    )
    assert np.array_equal(mirror_matched(pts, axis, 1e-6), dense)
