"""Start configurations: random kinds are valid and need (or not) expansion; --init files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fatswarm.agent.geometry import sec
from fatswarm.deploy.scenarios.starts import (
    KINDS,
    InitFileError,
    degenerate_starts,
    load_init,
    overlapping_pair,
    random_start,
    target_radius,
)

SIZES = [1, 2, 3, 4, 5, 8, 13, 40]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("n", SIZES)
def test_random_starts_are_valid(kind: str, n: int) -> None:
    for seed in range(3):
        pts = random_start(n, seed, kind)
        assert pts.shape == (n, 2) and pts.dtype == np.float64
        assert np.all(np.isfinite(pts)) and overlapping_pair(pts) is None


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("a", [3.2, 4.0, 7.0])
def test_clustered_and_dense_need_expansion_others_do_not(kind: str, a: float) -> None:
    needs_expansion = kind in ("clustered", "dense")
    for n in (2, 3, 6, 17):
        for seed in range(3):
            radius = sec(random_start(n, seed, kind, a)).radius
            assert (radius < target_radius(n, a)) == needs_expansion, (n, seed, radius)


def test_dense_starts_have_touching_robots() -> None:
    pts = random_start(12, 0, "dense")
    dist = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
    assert np.sum(np.isclose(dist, 2.0)) >= 2 * 11


def test_loose_starts_keep_robots_a_apart() -> None:
    pts = random_start(10, 1, "loose", 6.0)
    dist = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(dist, np.inf)
    assert dist.min() >= 6.0


def test_same_seed_same_start_and_generator_accepted() -> None:
    np.testing.assert_array_equal(random_start(9, 4), random_start(9, 4))
    assert not np.array_equal(random_start(9, 4), random_start(9, 5))
    rng = np.random.default_rng(1)
    assert random_start(5, rng, "spread").shape == (5, 2)


def test_unknown_kind_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown start kind"):
        random_start(4, 0, "heap")


def test_target_radius_uses_a_star() -> None:
    assert target_radius(6, 3.2) == pytest.approx(4.0)  # a* = 4: hexagon side 4
    assert target_radius(4, 6.0) == pytest.approx(6.0 / np.sqrt(2.0))


def test_degenerate_starts_are_valid_and_cover_the_issue_list() -> None:
    starts = degenerate_starts()
    for name, (pts, a) in starts.items():
        assert overlapping_pair(pts) is None, name
        assert a > 3
    assert {len(p) for p, _ in starts.values()} >= {2, 3, 4}
    assert {"all-on-L", "symmetric-robot-at-o", "symmetric-no-robot-at-o"} <= set(starts)
    assert {"touching-rosette", "small-uniform", "large-uneven-circle"} <= set(starts)


def test_symmetric_start_with_robot_at_o_has_it_at_the_north_point() -> None:
    pts, _ = degenerate_starts()["symmetric-robot-at-o"]
    circle = sec(pts)
    north = np.array([circle.center[0], circle.center[1] + circle.radius])
    assert np.min(np.linalg.norm(pts - north, axis=1)) < 1e-9


def write(tmp_path: Path, content: object) -> str:
    path = tmp_path / "init.json"
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    return str(path)


def test_load_init_reads_positions_and_optional_a(tmp_path: Path) -> None:
    pts, a = load_init(write(tmp_path, {"positions": [[0, 0], [2, 0]], "a": 5}))
    np.testing.assert_array_equal(pts, [[0.0, 0.0], [2.0, 0.0]])
    assert a == 5.0
    assert load_init(write(tmp_path, {"positions": [[1, 1]]}))[1] is None


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("{", "is not JSON"),
        ([[0, 0]], "must hold"),
        ({"positions": []}, "non-empty list"),
        ({"positions": [[0, 0], [1]]}, "position 1 must be"),
        ({"positions": [[0, 0], [1, "2"]]}, "finite numbers"),
        ({"positions": [[0, 0], [1e400, 0]]}, "finite numbers"),
        ({"positions": [[0, 0], [5, 5], [1, 1]]}, "robots 0 and 2 overlap"),
        ({"positions": [[0, 0]], "a": "big"}, "'a' must be a number"),
        ({"positions": [[0, 0]], "a": "4"}, "'a' must be a number, got '4'"),
        ({"positions": [[0, 0]], "a": True}, "'a' must be a number, got true"),
        ({"positions": [[0, 0]], "a": None}, r"'a' must be a number, got null \(leave 'a' out"),
    ],
)
def test_bad_init_file_gives_one_line_error(tmp_path: Path, content: object, message: str) -> None:
    with pytest.raises(InitFileError, match=message) as info:
        load_init(write(tmp_path, content))
    assert "\n" not in str(info.value)


def test_missing_init_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(InitFileError, match="cannot read init file"):
        load_init(str(tmp_path / "absent.json"))


def test_an_init_file_pair_just_below_the_overlap_bound_is_refused_with_its_real_distance(
    tmp_path: Path,
) -> None:
    # one float step closer than 2 - 1e-7 used to read "centres 2 apart, need >= 2"
    from fatswarm.domain.tolerance import OVERLAP_DISTANCE

    gap = float(np.nextafter(OVERLAP_DISTANCE, 0.0))
    with pytest.raises(InitFileError) as info:
        load_init(write(tmp_path, {"positions": [[0.0, 0.0], [gap, 0.0]]}))
    assert "centres 1.9999998999999997 apart, need >= 2 - 1e-07 = 1.9999999" in str(info.value)
    pts, _ = load_init(write(tmp_path, {"positions": [[0.0, 0.0], [OVERLAP_DISTANCE, 0.0]]}))
    assert len(pts) == 2  # exactly at the bound: touching, allowed
