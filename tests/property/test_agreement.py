"""Issue 7's classes of failure, each as a named start: every robot agrees, and the run forms the
circle without a collision in at most n + 2 moves, under fsync, ssync and centralized."""

from __future__ import annotations

import math

import numpy as np
import pytest
import strategies
from agreement import assert_observers_agree
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fatswarm.agent.geometry import target_radius
from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.deploy.scenarios.adversarial import adversarial_start


def polygon(n: int, radius: float, phase: float = 0.0) -> np.ndarray:
    k = np.arange(n)
    t = phase + 2.0 * math.pi * k / n
    return np.column_stack([radius * np.cos(t), radius * np.sin(t)])


def near_symmetric_pair_one_from_l(eps: float) -> np.ndarray:
    """Mirror discs touching across L, one of them off by eps (below EPS_AT: 'symmetric')."""
    pts = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 5.0], [4.0, 3.0], [-4.0, 3.0], [0.0, -4.0]])
    pts[0, 0] += eps
    return pts


def nudged(pts: np.ndarray, row: int, by: tuple[float, float]) -> np.ndarray:
    out = pts.astype(np.float64).copy()
    out[row] += by
    return out


SQUARE = np.array([[2.0 * i, 2.0 * j] for i in range(3) for j in range(3)])
HEXAGONAL = np.array([[2.0 * i + (j % 2), math.sqrt(3.0) * j] for i in range(3) for j in range(3)])
LINE = np.array([[0.0, 2.0 * i] for i in range(4)])
R5 = target_radius(5, 4.0)
R9 = target_radius(9, 4.0)

CASES: dict[str, tuple[np.ndarray, float]] = {
    # 1. Frames that disagreed at thresholds.
    "near-symmetric pair 1 from L, 1e-7": (near_symmetric_pair_one_from_l(1e-7), 4.0),
    "near-symmetric pair 1 from L, 1e-9": (near_symmetric_pair_one_from_l(1e-9), 4.0),
    "square lattice nudged 3e-8": (nudged(SQUARE, 4, (3e-8, 0.0)), 4.0),
    "hexagonal lattice nudged 3e-8": (nudged(HEXAGONAL, 4, (0.0, 3e-8)), 4.0),
    "vertical line, one off by 1e-7": (nudged(LINE, 2, (1e-7, 0.0)), 4.0),
    # 2. Exact ties: mirror-symmetric starts with equal distances to the first target.
    "symmetric, robot on L tied with a pair": (
        np.array([[0.0, 0.0], [3.0, 4.0], [-3.0, 4.0], [0.0, 9.0], [6.0, 9.0], [-6.0, 9.0]]),
        4.0,
    ),
    "two mirror pairs tied": (
        np.array([[3.0, 0.0], [-3.0, 0.0], [0.0, 3.0], [0.0, -3.0], [6.0, 6.0], [-6.0, 6.0]]),
        4.0,
    ),
    # 3. Touching within the world's slack but not within the old agent's.
    "two discs 2 - 5e-8 apart": (np.array([[0.0, 0.0], [2.0 - 5e-8, 0.0]]), 4.0),
    "rosette to 7 decimals": (np.vstack([[0.0, 0.0], np.round(polygon(6, 2.0), 7)]), 4.0),
    "touching pentagon to 7 decimals": (np.round(polygon(5, 1.0 / math.sin(math.pi / 5)), 7), 4.0),
    # 4. Formed far away.
    "formed pentagon at 1e6": (polygon(5, R5) + 1e6, 4.0),
    "formed 9-gon at 1e5": (polygon(9, R9, 0.3) + 1e5, 4.0),
    "cluster at -1e6": (polygon(7, 3.0) - 1e6, 4.0),
    # 7. A FormUCircle move that would shrink the SEC back below r (8 moves for n = 4 before),
    # and robots all settled within EPS_AT whose angular gaps were judged twice as strictly.
    "square of radius r(1 - 1e-6), one off by 1e-6": (
        nudged(polygon(4, target_radius(4, 4.0) * (1 - 1e-6)), 0, (1e-6, 0.0)),
        4.0,
    ),
    "settled square, gaps off by 2 EPS_AT": (
        nudged(polygon(4, target_radius(4, 4.0) * (1 - 1e-6), math.pi / 4), 2, (-1e-6, 0.0)),
        4.0,
    ),
}


@pytest.mark.parametrize("name", list(CASES))
def test_every_observer_agrees_on_the_start(name: str) -> None:
    pts, a = CASES[name]
    assert_observers_agree(pts, Params(len(pts), a))


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
@pytest.mark.parametrize("name", list(CASES))
def test_the_circle_forms_without_collision_in_n_plus_2_moves(name: str, scheduler: str) -> None:
    pts, a = CASES[name]
    n = len(pts)
    for seed in range(3):  # the seed draws the private flips and the schedule
        result = run_lockstep(pts, Params(n, a), make_scheduler(scheduler, n, seed), seed=seed)
        assert (result.status, result.collisions) == ("formed", 0), (seed, result.status)
        assert result.moves <= n + 2, (seed, result.moves)


ADVERSARIAL = settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
SIDES = st.sampled_from([3.2, 4.0, 6.0])


@ADVERSARIAL
@given(strategies.any_adversarial_start(), SIDES)
def test_every_observer_agrees_on_adversarial_starts(pts: np.ndarray, a: float) -> None:
    # Near-symmetric, near-touching, tied, lattices to a few decimals, offsets, rims: every robot
    # in both of its frames and with a shuffled view decides on the same canonical bits.
    assert_observers_agree(pts, Params(len(pts), a))


@ADVERSARIAL
@given(
    strategies.any_adversarial_start(),
    SIDES,
    st.sampled_from(["fsync", "ssync", "centralized"]),
    st.integers(0, 2**16),
)
def test_adversarial_starts_form_without_collision(
    pts: np.ndarray, a: float, scheduler: str, seed: int
) -> None:
    n = len(pts)
    result = run_lockstep(pts, Params(n, a), make_scheduler(scheduler, n, seed), seed=seed)
    assert (result.status, result.collisions) == ("formed", 0)
    assert result.moves <= n + 2


# 5. Robots near one circle: after most targets were filled, the last robots sat just inside the
# rim where the chord and the single slide both hit settled robots: stalled under every
# scheduler until G14b (any free path). Found by bench/bench_adversarial.py.
RIM_STALLS = [
    (40, 1476104628, 4.0),
    (32, 982055690, 3.2),
    (59, 498886429, 4.0),
    (70, 894669965, 6.0),
]


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
@pytest.mark.parametrize(("n", "seed", "a"), RIM_STALLS)
def test_robots_near_one_circle_fill_every_target(
    n: int, seed: int, a: float, scheduler: str
) -> None:
    pts = adversarial_start("rim", n, seed)
    result = run_lockstep(pts, Params(n, a), make_scheduler(scheduler, n, seed), seed=seed)
    assert (result.status, result.collisions) == ("formed", 0)
    assert result.moves <= n + 2


# 1-2. Starts on which the old main's robots disagreed and collided (found by
# bench/bench_adversarial.py on commit 6e5d3b6): an exact tie between a robot on L and a side
# robot (formed, with 2 collisions, and exit 0), the same tie perturbed, a nudged hexagonal lattice
# written to 3 decimals.
OLD_COLLISIONS = [
    ("exact-symmetric", 9, 1049947267, 4.0),
    ("near-symmetric", 9, 1949635111, 3.2),
    ("lattice", 6, 1165938632, 4.0),
]


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
@pytest.mark.parametrize(("family", "n", "seed", "a"), OLD_COLLISIONS)
def test_starts_where_robots_used_to_disagree_form_without_collision(
    family: str, n: int, seed: int, a: float, scheduler: str
) -> None:
    pts = adversarial_start(family, n, seed)
    assert_observers_agree(pts, Params(n, a))
    result = run_lockstep(pts, Params(n, a), make_scheduler(scheduler, n, seed), seed=seed)
    assert (result.status, result.collisions) == ("formed", 0)
    assert result.moves <= n + 2
