"""Disc physics: contacts stop movers at distance 2, clearance 2 passes, bad input is refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fatswarm.domain.path import Arc, Line, Path, PathFormatError, end_point, path_length, point_at
from fatswarm.domain.tolerance import GRID, OVERLAP_DISTANCE, snap
from fatswarm.world.physics import (
    CONTACT_SLACK,
    Collision,
    InvalidConfigurationError,
    InvalidRoundError,
    apply_round,
    validate_configuration,
)

TOUCH = 1e-9  # how close to exactly 2 a stopped robot must end up


def pts(*xy: tuple[float, float]) -> np.ndarray:
    return np.array(xy, dtype=np.float64)


def line(*ends: tuple[float, float]) -> Path:
    return Path(tuple(Line(e) for e in ends))


def dist(p: np.ndarray, i: int, j: int) -> float:
    return float(np.hypot(*(p[i] - p[j])))


# ---------------------------------------------------------------------------------------------
# Contacts


def test_head_on_movers_stop_touching_and_both_are_recorded() -> None:
    out = apply_round(pts((0, 0), (10, 0)), {0: line((10, 0)), 1: line((0, 0))})
    assert dist(out.positions, 0, 1) == pytest.approx(2.0, abs=TOUCH)
    assert dist(out.positions, 0, 1) >= 2.0 - CONTACT_SLACK
    assert out.positions[0] == pytest.approx([4.0, 0.0], abs=TOUCH)
    assert out.traveled[0] == pytest.approx(4.0, abs=TOUCH)
    assert out.traveled[1] == pytest.approx(4.0, abs=TOUCH)
    assert sorted((c.robot, c.other) for c in out.collisions) == [(0, 1), (1, 0)]
    for c in out.collisions:
        assert c.t == pytest.approx(4.0, abs=TOUCH)
        assert c.point == pytest.approx(tuple(out.positions[c.robot]))


def test_mover_into_still_robot_stops_at_contact_and_only_the_mover_is_recorded() -> None:
    out = apply_round(pts((0, 0), (5, 0)), {0: line((10, 0))})
    assert out.positions[0] == pytest.approx([3.0, 0.0], abs=TOUCH)
    assert out.positions[1].tolist() == [5.0, 0.0]
    assert out.traveled == {0: pytest.approx(3.0, abs=TOUCH)}
    assert out.collisions == [Collision(0, 1, out.traveled[0], tuple(out.positions[0]))]


def test_arc_mover_into_still_robot_stops_touching_it() -> None:
    # Quarter turn about the origin at radius 5, from (5, 0) towards (0, 5); a robot sits on the
    # circle at 60 degrees, so contact comes 2 * asin(1 / 5) radians before it.
    still = (5 * math.cos(math.pi / 3), 5 * math.sin(math.pi / 3))
    out = apply_round(pts((5, 0), still), {0: Path((Arc((0.0, 0.0), math.pi / 2),))})
    assert dist(out.positions, 0, 1) == pytest.approx(2.0, abs=TOUCH)
    expected_angle = math.pi / 3 - 2 * math.asin(1 / 5)
    assert out.traveled[0] == pytest.approx(5 * expected_angle, abs=1e-8)
    assert [(c.robot, c.other) for c in out.collisions] == [(0, 1)]


def test_two_arc_movers_meeting_both_stop_touching() -> None:
    # Mirror images about the y axis turning towards each other on circles about (±5.5, 0):
    # at angle θ from the x axis they are 11 - 10 cos θ apart, 2 when cos θ = 0.9.
    paths = {0: Path((Arc((-5.5, 0.0), -math.pi),)), 1: Path((Arc((5.5, 0.0), math.pi),))}
    out = apply_round(pts((-5.5, 5), (5.5, 5)), paths)
    assert dist(out.positions, 0, 1) == pytest.approx(2.0, abs=TOUCH)
    assert out.positions[0] == pytest.approx([-out.positions[1][0], out.positions[1][1]])
    assert {(c.robot, c.other) for c in out.collisions} == {(0, 1), (1, 0)}
    assert out.traveled[0] == pytest.approx(5 * (math.pi / 2 - math.acos(0.9)), abs=1e-8)


def test_grazing_tangential_pass_at_exactly_distance_two_is_not_a_collision() -> None:
    out = apply_round(pts((0, 0), (5, 2), (7, -2)), {0: line((10, 0))})
    assert out.collisions == []
    assert out.traveled[0] == 10.0
    assert out.positions[0].tolist() == [10.0, 0.0]


def test_pass_within_planner_rounding_is_free_but_within_slack_is_stopped() -> None:
    free = apply_round(pts((0, 0), (5, 2 - 1e-9)), {0: line((10, 0))})
    assert free.collisions == []
    hit = apply_round(pts((0, 0), (5, 2 - 2 * CONTACT_SLACK)), {0: line((10, 0))})
    assert [(c.robot, c.other) for c in hit.collisions] == [(0, 1)]
    assert dist(hit.positions, 0, 1) == pytest.approx(2.0, abs=TOUCH)


def test_robots_that_start_touching_and_move_apart_or_sideways_are_not_collisions() -> None:
    start = pts((0, 0), (2, 0), (0, 2))
    out = apply_round(start, {0: line((-5, 0)), 1: line((2, -5)), 2: line((0, 7))})
    assert out.collisions == []
    assert out.traveled == {0: 5.0, 1: 5.0, 2: 5.0}


def test_moving_alongside_a_touching_neighbour_and_arriving_touching_are_free() -> None:
    out = apply_round(pts((0, 0), (0, 2), (6, 2)), {0: line((6.0, 0.0))})
    assert out.collisions == []
    assert out.positions[0].tolist() == [6.0, 0.0]
    together = apply_round(pts((0, 0), (0, 2)), {0: line((9, 0)), 1: line((9, 2))})
    assert together.collisions == []
    assert dist(together.positions, 0, 1) == pytest.approx(2.0)


def test_sliding_on_an_arc_of_radius_two_around_an_obstacle_is_not_a_collision() -> None:
    obstacle = (3.7, -1.2)
    for a0 in np.linspace(0.0, 2 * math.pi, 7):
        start = (obstacle[0] + 2 * math.cos(a0), obstacle[1] + 2 * math.sin(a0))
        for sweep in (math.pi, -1.3 * math.pi):
            a1 = a0 + sweep  # then straight away from the obstacle
            away = (obstacle[0] + 7 * math.cos(a1), obstacle[1] + 7 * math.sin(a1))
            path = Path((Arc(obstacle, sweep), Line(away)))
            out = apply_round(pts(start, obstacle), {0: path})
            assert out.collisions == []
            assert out.traveled[0] == path_length(start, path)


def test_slide_approach_tangent_arc_and_leave_like_the_planner_is_free() -> None:
    # Tangent-arc-tangent detour around an obstacle at (5, 1) with clearance exactly 2.
    c = (5.0, 1.0)
    path = Path((Line((5.0, -1.0)), Arc(c, math.pi / 2), Line((7.0, 6.0))))
    out = apply_round(pts((0.0, -1.0), c), {0: path})
    assert out.collisions == []
    assert out.positions[0].tolist() == [7.0, 6.0]


def test_crossing_behind_a_mover_that_has_already_passed_is_not_a_collision() -> None:
    # Robot 1 crosses robot 0's line at x = 3 when robot 0 is at x = 8: the swept regions
    # intersect, the robots never come closer than 3.5.
    out = apply_round(pts((0, 0), (3, -8)), {0: line((20, 0)), 1: line((3, 8))})
    assert out.collisions == []
    assert out.traveled == {0: 20.0, 1: 16.0}


def test_crossing_when_timing_makes_movers_meet_stops_both() -> None:
    out = apply_round(pts((0, 0), (5, -5)), {0: line((20, 0)), 1: line((5, 5))})
    t = 5 - math.sqrt(2)  # |(t - 5, 5 - t)| = 2
    assert out.traveled[0] == pytest.approx(t, abs=TOUCH)
    assert out.traveled[1] == pytest.approx(t, abs=TOUCH)
    assert dist(out.positions, 0, 1) == pytest.approx(2.0, abs=TOUCH)
    assert len(out.collisions) == 2


def test_stopped_robot_becomes_an_obstacle_for_a_later_mover() -> None:
    # Robot 0 is stopped by robot 1 at (4, 0) at t = 4; robot 2 crosses x = 4 later and hits it.
    start = pts((0, 0), (6, 0), (4, -10))
    out = apply_round(start, {0: line((10, 0)), 2: line((4, 10))})
    assert out.positions[0] == pytest.approx([4.0, 0.0], abs=TOUCH)
    assert out.positions[2] == pytest.approx([4.0, -2.0], abs=TOUCH)
    assert [(c.robot, c.other) for c in out.collisions] == [(0, 1), (2, 0)]
    assert out.collisions[1].t == pytest.approx(8.0, abs=TOUCH)
    # Without robot 1, robot 0 is long gone when robot 2 crosses: no contact at all.
    free = apply_round(start[[0, 2]], {0: line((10, 0)), 1: line((4, 10))})
    assert free.collisions == []


def test_robot_that_finished_its_path_is_an_obstacle() -> None:
    out = apply_round(pts((0, 0), (4, -8)), {0: line((4, 0)), 1: line((4, 6))})
    assert out.positions[0].tolist() == [4.0, 0.0]
    assert out.positions[1] == pytest.approx([4.0, -2.0], abs=TOUCH)
    assert [(c.robot, c.other) for c in out.collisions] == [(1, 0)]


def test_chain_of_contacts_in_a_crowd_leaves_no_overlap() -> None:
    # Everyone heads for the centre of a ring: many contacts, all resolved without overlap.
    n = 24
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    start = np.stack([10 * np.cos(ang), 10 * np.sin(ang)], axis=1)
    paths = {i: line((0.0, 0.0)) for i in range(n)}
    out = apply_round(start, paths)
    d = np.hypot(*(out.positions[:, None] - out.positions[None]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 2 - CONTACT_SLACK
    assert sorted(c.robot for c in out.collisions) == list(range(n))
    assert all(out.traveled[i] < 10.0 for i in range(n))


# ---------------------------------------------------------------------------------------------
# Free motion


def test_traveled_equals_path_length_and_robot_ends_at_path_end_when_free() -> None:
    path = Path((Line((3.0, 0.0)), Arc((3.0, 2.0), math.pi), Line((-4.0, 4.0))))
    out = apply_round(pts((0, 0), (20, 20)), {0: path})
    assert out.collisions == []
    assert out.traveled[0] == path_length((0.0, 0.0), path)
    assert tuple(out.positions[0]) == end_point((0.0, 0.0), path)


def test_robots_without_a_path_or_with_an_empty_one_do_not_move() -> None:
    start = pts((0, 0), (5, 5), (-5, 5))
    out = apply_round(start, {1: Path(), 2: line((-5, 9))})
    assert out.positions[0].tolist() == [0.0, 0.0]
    assert out.positions[1].tolist() == [5.0, 5.0]
    assert out.traveled == {1: 0.0, 2: 4.0}
    assert apply_round(start, {}).positions.tolist() == start.tolist()


def test_apply_round_does_not_mutate_its_input() -> None:
    start = pts((0, 0), (5, 0))
    before = start.copy()
    out = apply_round(start, {0: line((10, 0))})
    assert start.tolist() == before.tolist()
    assert out.positions is not start
    out.positions[1] = [99.0, 99.0]
    assert start.tolist() == before.tolist()


def test_position_matches_point_at_for_a_stopped_multi_segment_path() -> None:
    path = Path((Line((4.0, 0.0)), Arc((4.0, 3.0), math.pi / 2), Line((12.0, 3.0))))
    out = apply_round(pts((0, 0), (8.0, 3.0)), {0: path})
    assert len(out.collisions) == 1
    expected = point_at((0.0, 0.0), path, out.traveled[0])
    assert out.positions[0] == pytest.approx(expected, abs=GRID)  # ends on the grid


def test_accepts_positions_as_lists_and_numpy_integer_robot_ids() -> None:
    out = apply_round([[0, 0], [5, 5]], {np.int64(0): line((1, 0))})  # type: ignore[arg-type,dict-item]
    assert out.traveled == {0: 1.0}


# ---------------------------------------------------------------------------------------------
# Refused input


def test_validate_configuration_returns_a_float64_copy() -> None:
    src = [[0, 0], [2, 0]]
    out = validate_configuration(src)  # type: ignore[arg-type]
    assert out.dtype == np.float64 and out.shape == (2, 2)
    arr = np.array(src, dtype=np.float64)
    assert validate_configuration(arr) is not arr


def test_validate_configuration_accepts_touching_robots() -> None:
    validate_configuration(pts((0, 0), (2, 0), (1, math.sqrt(3))))
    validate_configuration(pts((0, 0), (2 - 0.5 * CONTACT_SLACK, 0)))


@pytest.mark.parametrize(
    ("positions", "words"),
    [
        (pts((0, 0), (5, 5), (1.5, 0)), ["robots 0 and 2", "overlap", "at least 2 apart"]),
        (pts((0, 0), (2 - 2 * CONTACT_SLACK, 0)), ["robots 0 and 1", "overlap"]),
        (pts((0, 0), (math.nan, 5)), ["robot 1", "finite"]),
        (pts((0, 0), (5, 5), (math.inf, 0)), ["robot 2", "finite"]),
        (np.zeros((3, 3)), ["shape (n, 2)", "(3, 3)"]),
        (np.zeros(4), ["shape (n, 2)"]),
        (np.zeros((0, 2)), ["at least one robot"]),
        ([[0, 0], [1]], ["[x, y]"]),
        ([["a", "b"]], ["[x, y]"]),
    ],
)
def test_invalid_starts_are_refused_with_a_message_saying_what_to_fix(
    positions: object, words: list[str]
) -> None:
    with pytest.raises(InvalidConfigurationError) as info:
        validate_configuration(positions)  # type: ignore[arg-type]
    for word in words:
        assert word in str(info.value)


def test_apply_round_refuses_a_mover_overlapping_at_the_start() -> None:
    with pytest.raises(InvalidConfigurationError, match="robots 0 and 1 overlap"):
        apply_round(pts((0, 0), (1, 0)), {1: line((1, 5))})


def test_apply_round_refuses_non_finite_positions() -> None:
    with pytest.raises(InvalidConfigurationError, match="finite"):
        apply_round(pts((0, 0), (math.nan, 0)), {0: line((1, 0))})


@pytest.mark.parametrize(
    "path",
    [
        line((math.nan, 0.0)),
        line((math.inf, 0.0)),
        Path((Arc((0.0, math.nan), 1.0),)),
        Path((Arc((1.0, 0.0), math.inf),)),
        Path((Line((1.0, 0.0)),) * 1000),
        Path(("line",)),  # type: ignore[arg-type]
        Path((Line((1e308, 0.0)), Line((-1e308, 0.0)))),
    ],
)
def test_hostile_paths_are_refused_before_anything_moves(path: Path) -> None:
    with pytest.raises(PathFormatError):
        apply_round(pts((0, 0), (5, 0)), {0: path})


@pytest.mark.parametrize("robot", [-1, 2, 1.0, "0", True])
def test_unknown_robots_are_refused(robot: object) -> None:
    with pytest.raises(InvalidRoundError):
        apply_round(pts((0, 0), (5, 0)), {robot: line((1, 0))})  # type: ignore[dict-item]


def test_a_non_path_is_refused() -> None:
    with pytest.raises(InvalidRoundError, match="expected a Path"):
        apply_round(pts((0, 0), (5, 0)), {0: [Line((1.0, 0.0))]})  # type: ignore[dict-item]


def test_mirror_movers_circling_many_times_touch_repeatedly_without_being_stopped() -> None:
    # 5 - 3 cos θ apart: they touch (exactly 2) once per turn, 64 times, and never overlap.
    paths = {0: Path((Arc((0.0, 0.0), 400.0),)), 1: Path((Arc((5.0, 0.0), -400.0),))}
    out = apply_round(pts((1.5, 0), (3.5, 0)), paths)
    assert out.collisions == []
    assert out.traveled == {0: 600.0, 1: 600.0}


def test_neighbours_sliding_together_on_one_circle_while_touching_are_free() -> None:
    # Two robots 2 apart on a circle of radius 30 slide 4 turns the same way; each robot's copy
    # of the centre carries its own rounding, as paths mapped back from private frames do.
    radius = 30.0
    gap = 2 * math.asin(1 / radius)
    start = pts((radius, 0), (radius * math.cos(gap), radius * math.sin(gap)))
    paths = {
        0: Path((Arc((0.0, 0.0), 8 * math.pi),)),
        1: Path((Arc((1e-14, -1e-14), 8 * math.pi),)),
    }
    out = apply_round(start, paths)
    assert out.collisions == []
    assert dist(out.positions, 0, 1) == pytest.approx(2.0, abs=1e-9)


def test_inner_robot_turning_faster_about_the_same_centre_catches_the_outer_one() -> None:
    # Radii 5 and 4 about the origin, angular speeds 1/5 and 1/4: the angle between them falls
    # from 0.5 at 0.05 per unit time; they touch when 41 - 40 cos(angle) = 4.
    start = pts((5 * math.cos(0.5), 5 * math.sin(0.5)), (4, 0))
    out = apply_round(start, {0: Path((Arc((0.0, 0.0), 2.0),)), 1: Path((Arc((0.0, 0.0), 2.0),))})
    t = (0.5 - math.acos(37 / 40)) / 0.05
    assert out.traveled[0] == pytest.approx(t, abs=1e-8)
    assert out.traveled[1] == pytest.approx(t, abs=1e-8)
    assert dist(out.positions, 0, 1) == pytest.approx(2.0, abs=TOUCH)
    assert len(out.collisions) == 2


def test_robots_touching_side_by_side_making_the_same_turn_are_free() -> None:
    # Equal turns about centres 2 apart translate the pair along a circle: distance stays 2.
    paths = {0: Path((Arc((0.0, 0.0), 8 * math.pi),)), 1: Path((Arc((2.0, 0.0), 8 * math.pi),))}
    out = apply_round(pts((50, 0), (52, 0)), paths)
    assert out.collisions == []
    assert out.traveled[1] == pytest.approx(400 * math.pi)


@pytest.mark.parametrize("offset", [0.0, 3e5, -6.8e5, 1.9e6])
def test_two_robots_bound_for_one_point_stop_at_contact_far_from_the_origin(offset: float) -> None:
    # Found by the adversarial matrix on the old algorithm (two robots sent to one target at
    # 6.8e5): rounding there exceeded the contact search's margin, which stepped over the contact,
    # and the discs were found overlapping after the round (PhysicsInvariantError).
    start = pts((-3.2158730536466464, 0.0), (3.2158730536466464, 0.0)) + offset
    meet = (offset, 51.60560101713054 + offset)
    out = apply_round(start, {0: line(meet), 1: line(meet)})
    assert {(c.robot, c.other) for c in out.collisions} == {(0, 1), (1, 0)}
    assert dist(out.positions, 0, 1) >= 2.0 - CONTACT_SLACK
    assert out.traveled[0] == pytest.approx(35.627426, abs=1e-6)


def test_a_pair_given_at_the_overlap_bound_is_accepted_and_stays_touching_on_the_grid() -> None:
    # docs/model.md: centres 2 - 1e-7 apart touch, which is allowed; the snap to the 2^-30 grid
    # used to bring half of such pairs below the bound and refuse them ("1.9999999 apart")
    rng = np.random.default_rng(0)
    accepted = 0
    for _ in range(1000):
        centre, turn = rng.uniform(-1e4, 1e4, 2), rng.uniform(0.0, 2.0 * math.pi)
        pair = np.array(
            [centre, centre + OVERLAP_DISTANCE * np.array([math.cos(turn), math.sin(turn)])]
        )
        if math.dist(pair[0], pair[1]) < OVERLAP_DISTANCE:
            continue  # the float sum fell an ulp short: not at the bound as given
        on_grid = validate_configuration(pair)
        assert np.array_equal(snap(on_grid), on_grid)
        assert math.dist(on_grid[0], on_grid[1]) >= OVERLAP_DISTANCE
        assert np.abs(on_grid - pair).max() <= 3 * GRID  # stretched by 1 + 1.9e-9 at most
        accepted += 1
    assert accepted > 400


def test_a_touching_lattice_at_the_bound_stays_touching_on_the_grid() -> None:
    def closest(points: np.ndarray) -> float:
        gaps = np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))
        np.fill_diagonal(gaps, np.inf)
        return float(gaps.min())

    side = OVERLAP_DISTANCE + 1e-9  # above the float rounding of the lattice's coordinates
    rows = [
        (side * i + side / 2 * (j % 2), side * math.sqrt(3) / 2 * j)
        for j in range(5)
        for i in range(5)
    ]
    for offset in ((0.0, 0.0), (1234.5678, -98.7654321), (-7.3e5, 3.1e5)):
        lattice = np.array(rows) + np.array(offset)
        assert OVERLAP_DISTANCE <= closest(lattice) < OVERLAP_DISTANCE + 2e-9
        on_grid = validate_configuration(lattice)
        assert closest(on_grid) >= OVERLAP_DISTANCE
        assert np.abs(on_grid - lattice).max() < 2e-8  # stretched by 1 + 1.9e-9 at most


def test_an_overlap_refusal_shows_the_real_distance_and_the_real_bound() -> None:
    # the bound is 2 - 1e-7, not 2, and a distance just below it must not read as 2 or as it
    for gap, shown in ((1.9999998992, "1.999999899"), (1.99999989, "1.99999989"), (1.5, "1.5")):
        with pytest.raises(InvalidConfigurationError) as info:
            validate_configuration(np.array([[0.0, 0.0], [gap, 0.0]]))
        message = str(info.value)
        assert f"centres are {shown}" in message and "2 - 1e-07 = 1.9999999" in message, message
