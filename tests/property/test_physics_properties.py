"""Physics invariants on random starts and paths: no overlap ever, robots stay on their paths."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fatswarm.domain.path import Arc, Line, Path, Point, Segment, path_length, point_at, transform
from fatswarm.domain.tolerance import GRID, snap
from fatswarm.world.physics import CONTACT_SLACK, PLAN_ROUNDING, apply_round, validate_configuration

OVERLAP = 2.0 - CONTACT_SLACK
SAMPLES = 400  # times per round at which the trajectories are checked for overlap

coord = st.floats(-6.0, 6.0, allow_nan=False)


@dataclass(frozen=True)
class Round:
    start: np.ndarray
    paths: dict[int, Path]


@st.composite
def segments(draw: st.DrawFn, start: Point) -> Segment:
    """A line to a point near the robot's start, or an arc about such a point."""
    dx, dy = draw(coord), draw(coord)
    if draw(st.booleans()):
        return Line((start[0] + dx, start[1] + dy))
    sweep = draw(st.floats(-2 * math.pi, 2 * math.pi, allow_nan=False))
    return Arc((start[0] + 0.6 * dx, start[1] + 0.6 * dy), sweep)


@st.composite
def rounds(draw: st.DrawFn, max_n: int = 6) -> Round:
    """Robots on distinct cells of a 4x4 grid of pitch 2.5, jittered by up to 0.25 (so touching
    is possible, overlap is not), and a path of 0 to 3 segments for some of them."""
    cells = draw(st.lists(st.integers(0, 15), min_size=1, max_size=max_n, unique=True))
    jitter = st.floats(-0.25, 0.25, allow_nan=False)
    start = np.array([[2.5 * (c % 4) + draw(jitter), 2.5 * (c // 4) + draw(jitter)] for c in cells])
    paths: dict[int, Path] = {}
    for i in range(len(cells)):
        if draw(st.booleans()):
            here = (float(start[i, 0]), float(start[i, 1]))
            count = draw(st.integers(0, 3))
            paths[i] = Path(tuple(draw(segments(here)) for _ in range(count)))
    return Round(start, paths)


def trajectory(
    start: np.ndarray, path: Path | None, traveled: float, times: np.ndarray
) -> np.ndarray:
    """Where a robot is at each time: on its path until it stopped (agent.path, not physics)."""
    here = (float(start[0]), float(start[1]))
    if path is None:
        return np.repeat(start[None, :], len(times), axis=0)
    return np.array([point_at(here, path, min(float(t), traveled)) for t in times])


def min_pair_distance(tracks: np.ndarray) -> float:
    """Smallest centre distance over all pairs and sampled times; tracks: (robots, times, 2)."""
    if len(tracks) < 2:
        return math.inf
    d = tracks[:, None] - tracks[None, :]
    dist = np.hypot(d[..., 0], d[..., 1])
    idx = np.arange(len(tracks))
    dist[idx, idx] = math.inf
    return float(dist.min())


@settings(max_examples=150, deadline=None)
@given(rounds())
def test_no_overlap_and_every_robot_stays_on_its_own_path(r: Round) -> None:
    validate_configuration(r.start)
    before = r.start.copy()
    out = apply_round(r.start, r.paths)
    assert np.array_equal(r.start, before)
    n = len(r.start)

    # Robots without a path do not move; movers end on their path at `traveled`.
    assert set(out.traveled) == set(r.paths)
    for i in range(n):
        if i not in r.paths:
            assert out.positions[i].tolist() == r.start[i].tolist()
            continue
        here = (float(r.start[i, 0]), float(r.start[i, 1]))
        length = path_length(here, r.paths[i])
        assert 0.0 <= out.traveled[i] <= length
        expected = point_at(here, r.paths[i], out.traveled[i])
        # ... up to the snap to the grid: one of the four grid points around the end.
        assert np.hypot(*(out.positions[i] - expected)) <= 1e-12 + math.sqrt(2.0) * GRID

    # No overlap after the round, nor at any sampled time during it.
    assert min_pair_distance(out.positions[:, None, :]) >= OVERLAP
    horizon = max(out.traveled.values(), default=0.0)
    times = np.union1d(np.linspace(0.0, horizon, SAMPLES), [c.t for c in out.collisions])
    tracks = np.array(
        [trajectory(r.start[i], r.paths.get(i), out.traveled.get(i, 0.0), times) for i in range(n)]
    )
    assert min_pair_distance(tracks) >= OVERLAP - 1e-12

    # A robot is stopped exactly when a contact is reported, touching the robot it met.
    stopped = {c.robot for c in out.collisions}
    assert len(stopped) == len(out.collisions)
    for i, path in r.paths.items():
        here = (float(r.start[i, 0]), float(r.start[i, 1]))
        if i not in stopped:
            # A path shorter than the rounding of the round's frame (an arc of radius 1e-16) is
            # no move there: it travels 0. Any other travels its whole length, exactly.
            length = path_length(here, path)
            assert out.traveled[i] == length or (out.traveled[i] == 0.0 and length < 1e-12)
    for c in out.collisions:
        assert c.t == out.traveled[c.robot]
        assert np.hypot(*(np.array(c.point) - out.positions[c.robot])) == 0.0
        pair = [
            trajectory(r.start[k], r.paths.get(k), out.traveled.get(k, 0.0), np.array([c.t]))[0]
            for k in (c.robot, c.other)
        ]
        assert OVERLAP <= float(np.hypot(*(pair[0] - pair[1]))) <= 2.0 + 1e-6


@settings(max_examples=150, deadline=None)
@given(
    length=st.floats(0.5, 20.0),
    heading=st.floats(-math.pi, math.pi),
    obstacles=st.lists(
        st.tuples(
            st.floats(-3.0, 25.0),
            st.one_of(
                st.sampled_from([2.0, -2.0, 2.0 - PLAN_ROUNDING, -(2.0 - PLAN_ROUNDING)]),
                st.floats(-4.0, 4.0),
            ),
        ),
        max_size=5,
    ),
)
def test_straight_mover_stops_exactly_where_an_analytic_oracle_says(
    length: float, heading: float, obstacles: list[tuple[float, float]]
) -> None:
    # Mover from the origin along the x axis (then everything rotated by `heading`); obstacles
    # given as (along, across) offsets. Oracle: the mover overlaps obstacle k iff the segment
    # passes closer than 2 - slack; it stops where it first reaches distance 2 from such a one.
    local = np.array([(0.0, 0.0), *obstacles])
    c, s = math.cos(heading), math.sin(heading)
    start = local @ np.array([[c, s], [-s, c]])
    d = start[1:, None, :] - start[None, 1:, :]
    pairwise = np.hypot(d[..., 0], d[..., 1]) + np.eye(len(obstacles)) * 9.0
    assume(np.all(pairwise >= 2.0) and np.all(np.hypot(*local[1:].T) >= 2.0))
    along, across = local[1:, 0], local[1:, 1]
    nearest = np.hypot(np.clip(along, 0.0, length) - along, across)
    assume(np.all(np.abs(nearest - OVERLAP) > 1e-8))  # knife edges may go either way

    out = apply_round(start, {0: Path((Line((length * c, length * s)),))})
    blocked = nearest < OVERLAP
    if not blocked.any():
        assert out.collisions == []
        assert math.isclose(out.traveled[0], length, rel_tol=1e-12)
        return
    entry = along[blocked] - np.sqrt(np.maximum(4.0 - across[blocked] ** 2, 0.0))
    assert math.isclose(out.traveled[0], float(np.maximum(entry, 0.0).min()), abs_tol=1e-7)
    assert [col.robot for col in out.collisions] == [0]
    assert blocked[out.collisions[0].other - 1]


@settings(max_examples=100, deadline=None)
@given(rounds(), st.sampled_from([1e5, -3e5, 6.8e5, -1.9e6]))
def test_no_overlap_far_from_the_origin(r: Round, offset: float) -> None:
    # The same rounds, shifted by an exact grid offset: the world's positions can be anywhere
    # within +-2e6, and the contact search must not lose contacts to the rounding there.
    shift = (offset, -offset)
    start = snap(r.start + np.array(shift))
    paths = {i: transform(p, shift, False) for i, p in r.paths.items()}
    out = apply_round(start, paths)
    assert min_pair_distance(out.positions[:, None, :]) >= OVERLAP
