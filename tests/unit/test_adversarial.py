"""Adversarial starts: valid, deterministic, really near-degenerate; strategies build valid ones."""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fatswarm.agent.geometry import is_uniform_circle, sec
from fatswarm.deploy.scenarios.adversarial import (
    DEFAULT_FAMILIES,
    FAMILIES,
    FAMILY_TABLE,
    SIDES,
    adversarial_cases,
    adversarial_start,
    build_adversarial,
    family_range,
)
from fatswarm.deploy.scenarios.shapes import (
    NEAR_RANGE,
    PERTURB_RANGE,
    hex_row_height,
    min_separation,
    mirror_configuration,
    nudge_extreme,
    translate_exactly,
)
from fatswarm.domain.path import Points
from fatswarm.world.physics import CONTACT_SLACK, validate_configuration

# The strategies live beside the property tests, which import them as `strategies`; make that
# name importable here too, whether pytest runs from the checkout or not.
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "property"))
import strategies

SIZES = (2, 3, 4, 7, 12, 25)
SEEDS = range(4)
OVERLAP = 2.0 - CONTACT_SLACK


def mirror_mismatch(points: Points, axis_x: float) -> float:
    """How far the mirror image of the set (about x = axis_x) is from the set: max nearest gap."""
    image = points * [-1.0, 1.0] + [2.0 * axis_x, 0.0]
    gaps = np.hypot(image[:, None, 0] - points[None, :, 0], image[:, None, 1] - points[None, :, 1])
    return float(gaps.min(axis=1).max())


def exactly_mirrored(points: Points, axis_x: float) -> bool:
    image = points * [-1.0, 1.0] + [2.0 * axis_x, 0.0]
    key = np.lexsort((points[:, 1], points[:, 0]))
    image_key = np.lexsort((image[:, 1], image[:, 0]))
    return bool(np.array_equal(points[key], image[image_key]))


def distances(points: Points) -> Points:
    """Every pairwise centre distance, (n (n - 1) / 2,)."""
    i, j = np.triu_indices(len(points), k=1)
    out: Points = np.hypot(points[i, 0] - points[j, 0], points[i, 1] - points[j, 1])
    return out


@pytest.mark.parametrize("family", FAMILIES)
def test_every_family_builds_valid_finite_starts_for_many_n_and_seeds(family: str) -> None:
    lo, _hi = family_range(family)
    for n in (n for n in SIZES if n >= lo):
        for seed in SEEDS:
            pts = adversarial_start(family, n, seed)
            assert pts.shape == (n, 2) and pts.dtype == np.float64
            assert np.isfinite(pts).all()
            validate_configuration(pts)  # raises on any overlap


@pytest.mark.parametrize("family", FAMILIES)
def test_same_family_n_seed_gives_the_same_bits_and_other_seeds_differ(family: str) -> None:
    first = build_adversarial(family, 9, 5)
    again = build_adversarial(family, 9, 5)
    np.testing.assert_array_equal(first.positions, again.positions)
    assert first.variant == again.variant
    others = [adversarial_start(family, 9, seed) for seed in range(6, 10)]
    assert not all(np.array_equal(first.positions, o) for o in others)


def test_rim_works_from_three_to_a_hundred_robots() -> None:
    for n in (3, 4, 5, 50, 100):
        for seed in range(3):
            pts = adversarial_start("rim", n, seed)
            validate_configuration(pts)
            assert pts.shape == (n, 2)


def test_near_symmetric_mirrors_within_two_perturbations_but_never_exactly() -> None:
    # a robot on the axis moved by d is 2|d| from its own image; a pair robot |d| from its mate's
    for n in (2, 3, 6, 11, 20):
        for seed in range(6):
            built = build_adversarial("near-symmetric", n, seed)
            assert built.axis_x is not None
            assert mirror_mismatch(built.positions, built.axis_x) <= 2 * PERTURB_RANGE[1] + 1e-12
            assert not exactly_mirrored(built.positions, built.axis_x), (n, seed, built.variant)


def test_exact_symmetric_starts_are_their_own_mirror_image_bit_for_bit() -> None:
    variants: Counter[str] = Counter()
    for n in (2, 3, 8, 13, 30):
        for seed in range(8):
            built = build_adversarial("exact-symmetric", n, seed)
            assert built.axis_x is not None
            assert exactly_mirrored(built.positions, built.axis_x), (n, seed, built.variant)
            variants[built.variant] += 1
    assert {"axis-touching", "tie-axis-side", "tie-two-pairs"} <= set(variants)


def test_axis_touching_variant_has_mirror_discs_exactly_touching_across_the_axis() -> None:
    built = next(
        b
        for seed in range(40)
        if (b := build_adversarial("exact-symmetric", 6, seed)).variant == "axis-touching"
    )
    assert built.axis_x is not None
    on_line = np.abs(np.abs(built.positions[:, 0] - built.axis_x) - 1.0) == 0.0
    assert on_line.sum() == 2


def test_near_touching_starts_have_a_chain_of_contacts_within_a_micrometre() -> None:
    for n in (3, 8, 20):
        for seed in range(6):
            pts = adversarial_start("near-touching", n, seed)
            d = distances(pts)
            assert d.min() >= OVERLAP
            assert np.sum(np.abs(d - 2.0) <= NEAR_RANGE[1] + 1e-12) >= n - 1


def test_lattice_starts_touch_to_the_written_precision() -> None:
    for n in (4, 10, 30):
        for seed in range(6):
            built = build_adversarial("lattice", n, seed)
            assert OVERLAP <= min_separation(built.positions) <= 2.0 + 1e-3, built.variant


def test_hex_rows_written_short_are_rounded_up_so_diagonals_do_not_overlap() -> None:
    assert hex_row_height(7) == 1.7320508  # 2 - 7e-9 apart: touching
    assert hex_row_height(3) == 1.733  # 1.732 would put diagonal neighbours 4.4e-5 inside
    assert hex_row_height(5) == 1.73206


def test_vertical_line_is_one_column_of_touching_robots_up_to_one_small_move() -> None:
    for seed in range(10):
        built = build_adversarial("vertical-line", 7, seed)
        pts = built.positions
        assert np.abs(pts[:, 0]).max() <= NEAR_RANGE[1]
        np.testing.assert_allclose(np.diff(pts[:, 1]), 2.0, atol=NEAR_RANGE[1])
        assert min_separation(pts) >= OVERLAP


def test_offset_starts_sit_far_from_the_origin_and_keep_exact_symmetry() -> None:
    for seed in range(12):
        built = build_adversarial("offset", 10, seed)
        far = np.abs(built.positions).min(axis=0)
        assert (far >= 0.9e5).all() and (np.abs(built.positions) <= 1.1e6).all()
        if built.variant.startswith("exact-symmetric:"):
            assert built.axis_x is not None
            assert exactly_mirrored(built.positions, built.axis_x)


def test_exact_translation_keeps_the_relative_geometry_bit_for_bit() -> None:
    pts = mirror_configuration([[1.0, 0.5], [3.25, -2.0]], [4.0], axis_x=3.0)
    moved = translate_exactly(pts, (123456.789, -654321.5))
    back = translate_exactly(moved, (-123456.789, 654321.5))
    np.testing.assert_array_equal(back, pts)


def test_nudging_the_extreme_robot_brings_nobody_closer() -> None:
    pts = adversarial_start("lattice", 12, 3)
    before = distances(pts)
    after = distances(nudge_extreme(pts, (0.3, -1.0), 1e-6))
    assert (after >= before - 1e-12).all()


def centred(points: Points) -> Points:
    """The points about their mean: the goal test is about shape, whatever the offset."""
    out: Points = points - points.mean(axis=0)
    return out


def test_formed_polygons_are_uniform_circles_for_a_four() -> None:
    for n in (2, 3, 5, 16, 40):
        for seed in range(5):
            pts = adversarial_start("formed", n, seed)
            assert is_uniform_circle(centred(pts), 4.0), (n, seed)


def test_rim_robots_stay_near_their_smallest_enclosing_circle() -> None:
    for seed in range(10):
        built = build_adversarial("rim", 24, seed)
        if built.variant in ("circle", "circle-touching"):
            circle = sec(built.positions)
            radii = np.hypot(*(built.positions - circle.center).T)
            np.testing.assert_allclose(radii, circle.radius, rtol=1e-9)


def test_n_outside_a_family_range_and_unknown_families_are_refused() -> None:
    with pytest.raises(ValueError, match="builds n from 3"):
        adversarial_start("rim", 2, 0)
    with pytest.raises(ValueError, match="builds n from 2"):
        adversarial_start("lattice", 1, 0)
    with pytest.raises(ValueError, match="unknown adversarial family"):
        adversarial_start("spiral", 5, 0)


def test_cases_are_deterministic_and_spread_over_families_sizes_and_sides() -> None:
    cases = adversarial_cases(400, seed=7, n_max=20)
    assert cases == adversarial_cases(400, seed=7, n_max=20)
    assert cases != adversarial_cases(400, seed=8, n_max=20)
    per_family = Counter(c.family for c in cases)
    assert set(per_family) == set(DEFAULT_FAMILIES)
    assert max(per_family.values()) - min(per_family.values()) <= 1
    for fam in (f for f in FAMILY_TABLE if f.by_default):
        sizes = {c.n for c in cases if c.family == fam.name}
        assert sizes == set(range(fam.n_min, 21)), fam.name
    assert {c.a for c in cases} == set(SIDES)
    for case in cases:
        if case.family == "formed":
            assert is_uniform_circle(centred(case.start()), case.a)


def test_cases_refuse_a_negative_count_and_a_too_small_n_max() -> None:
    with pytest.raises(ValueError, match="count"):
        adversarial_cases(-1, 0)
    with pytest.raises(ValueError, match="n_max"):
        adversarial_cases(5, 0, n_max=1)
    assert {c.family for c in adversarial_cases(20, 0, n_max=2)} == set(DEFAULT_FAMILIES) - {"rim"}


STRATEGIES = {
    "near_symmetric": strategies.near_symmetric_starts(),
    "near_touching": strategies.near_touching_starts(),
    "lattice": strategies.lattice_starts(),
    "offset": strategies.offset_starts(),
    "rim": strategies.rim_starts(),
    "tied_symmetric": strategies.tied_symmetric_starts(),
    "any": strategies.any_adversarial_start(),
}


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_strategies_build_valid_starts(name: str) -> None:
    @settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.data())
    def check(data: st.DataObject) -> None:
        pts = data.draw(STRATEGIES[name])
        assert pts.ndim == 2 and pts.shape[1] == 2 and len(pts) >= 3
        assert np.isfinite(pts).all()
        validate_configuration(pts)

    check()
