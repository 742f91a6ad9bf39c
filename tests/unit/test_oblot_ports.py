"""The four oblot-sim ports as fatswarm algorithms: registered, held to the seam's contract where
their rules allow it, and each rule of docs/ports.md on a hand-made view."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fatswarm.agent.oblot_common import OblotParams, OblotRuleError, make_oblot_params
from fatswarm.agent.oblot_gathering_multiplicity import centre_of_biangularity
from fatswarm.domain.path import Arc, Line, Path
from fatswarm.domain.registry import available, load_algorithm
from fatswarm.domain.seam import AlgorithmParamsError, Configured
from fatswarm.testing import check_algorithm

NAMES = (
    "oblot-go-to-cog",
    "oblot-go-to-rightmost",
    "oblot-gathering-multiplicity",
    "oblot-move-along-sec",
)
P = OblotParams(None, 0.0)


def _line(path: Path) -> tuple[float, float]:
    (seg,) = path.segments
    assert isinstance(seg, Line)
    return seg.end


def test_the_four_ports_are_registered_under_their_names() -> None:
    for name in NAMES:
        assert name in available()
        assert load_algorithm(name).name == name


def test_tolerance_defaults_to_the_peers_rule_and_refuses_a_negative_value() -> None:
    assert Configured.of(load_algorithm("oblot-go-to-cog"), 4, {}).params.tolerance == 0.0
    assert make_oblot_params(None, {"tolerance": 0.5}).tolerance == 0.5
    with pytest.raises(AlgorithmParamsError, match="tolerance"):
        make_oblot_params(4, {"tolerance": -1.0})


@pytest.mark.parametrize(
    ("name", "checks"),
    [
        ("oblot-go-to-cog", ["oblivious", "order", "mirror", "rotation", "rotation-mirror"]),
        ("oblot-go-to-rightmost", ["path", "oblivious", "order", "params"]),
        ("oblot-move-along-sec", ["path", "oblivious", "order", "params"]),
        ("oblot-gathering-multiplicity", ["oblivious", "order", "params"]),
    ],
)
def test_each_port_keeps_the_contract_its_rules_allow(name: str, checks: list[str]) -> None:
    """Not checked, and why (docs/ports.md, "The contract"): the hunt runs fat discs, which the
    ports were not written for; GoToRightMost needs both axes agreed (no mirror); MoveAlongSEC's
    robot near the circle's centre turns with rounding; GatheringWithMultiplicity refuses where
    the peer throws (path) and reads the leftmost point of its own frame (mirror, on ties)."""
    check_algorithm(name, checks=checks)


def test_go_to_cog_goes_to_the_mean_of_all_n_positions_its_own_included() -> None:
    algorithm = load_algorithm("oblot-go-to-cog")
    view = np.array([[3.0, 0.0], [0.0, 6.0]])
    assert _line(algorithm.compute(view, P)) == pytest.approx((1.0, 2.0))
    assert algorithm.compute(np.array([[1.0, 1.0], [-1.0, -1.0]]), P) == Path()
    assert algorithm.compute(view, OblotParams(None, 3.0)) == Path()  # within the tolerance


def test_go_to_rightmost_goes_to_the_largest_x_and_breaks_ties_by_the_smallest_y() -> None:
    algorithm = load_algorithm("oblot-go-to-rightmost")
    assert _line(algorithm.compute(np.array([[2.0, 5.0], [2.0, -1.0], [1.0, 9.0]]), P)) == (
        2.0,
        -1.0,
    )
    # the robot itself is as far right as anyone: it stays
    assert algorithm.compute(np.array([[0.0, 5.0], [-1.0, 0.0]]), P) == Path()


def test_move_along_sec_goes_out_to_the_circle_then_turns_half_of_it_anticlockwise() -> None:
    algorithm = load_algorithm("oblot-move-along-sec")
    # the circle about (0, 1) of radius 2; the robot (the origin) is inside it, 1 from the centre
    view = np.array([[0.0, 3.0], [-2.0, 1.0], [2.0, 1.0], [0.0, -1.0]])
    line, arc = algorithm.compute(view, P).segments
    assert isinstance(line, Line) and isinstance(arc, Arc)
    assert line.end == pytest.approx((0.0, -1.0))  # the circle's nearest point, radially
    assert arc.center == pytest.approx((0.0, 1.0)) and arc.sweep == math.pi
    # on the circle: the half turn only
    (only,) = algorithm.compute(np.array([[0.0, 2.0], [1.0, 1.0]]), P).segments
    assert isinstance(only, Arc) and only.center == pytest.approx((0.0, 1.0))
    # at the centre, no nearest point: stays (the peer divides by zero)
    assert algorithm.compute(np.array([[0.0, 1.0], [0.0, -1.0]]), P) == Path()
    assert algorithm.goal(np.array([[0.0, 1.0], [0.0, -1.0], [1.0, 0.0]]), P)
    assert not algorithm.goal(np.array([[0.0, 1.0], [0.0, -1.0], [0.5, 0.0]]), P)


def test_gathering_multiplicity_refuses_two_and_odd_n_before_the_run_and_at_compute() -> None:
    algorithm = load_algorithm("oblot-gathering-multiplicity")
    for n in (2, 3, 5):
        with pytest.raises(AlgorithmParamsError, match="does not support"):
            Configured.of(algorithm, n, {}).check_start(np.zeros((n, 2)))
        with pytest.raises(OblotRuleError, match="does not support"):
            algorithm.compute(np.arange(2 * (n - 1), dtype=np.float64).reshape(-1, 2), P)


def test_gathering_multiplicity_goes_to_the_one_densest_point_and_refuses_two() -> None:
    algorithm = load_algorithm("oblot-gathering-multiplicity")
    dense = np.array([[3.0, 1.0], [3.0, 1.0], [-2.0, 5.0]])  # two robots share (3, 1)
    assert _line(algorithm.compute(dense, P)) == (3.0, 1.0)
    # the robot itself is one of the densest point's robots: stays
    assert algorithm.compute(np.array([[0.0, 0.0], [4.0, 1.0], [-2.0, 5.0]]), P) == Path()
    two = np.array([[0.0, 0.0], [3.0, 1.0], [3.0, 1.0]])  # (0, 0) and (3, 1) hold two each
    with pytest.raises(OblotRuleError, match="2 dense points hold 2 robots each"):
        algorithm.compute(two, P)


def test_centre_of_biangularity_of_a_square_and_of_a_regular_hexagon_is_the_centre() -> None:
    square = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]
    assert centre_of_biangularity(square) == pytest.approx((0.0, 0.0), abs=1e-12)
    hexagon = [(math.cos(k * math.pi / 3) + 5, math.sin(k * math.pi / 3) - 2) for k in range(6)]
    assert centre_of_biangularity(hexagon) == pytest.approx((5.0, -2.0), abs=1e-12)
    assert centre_of_biangularity([(0.0, 0.0), (4.0, 0.5), (1.0, 3.0), (3.5, 2.0)]) is not None
    general = [(0.0, 0.0), (4.0, 0.5), (1.0, 3.0), (3.5, 2.0), (6.0, 4.0), (-1.0, 5.0)]
    assert centre_of_biangularity(general) is None


def test_four_robots_in_general_position_count_as_biangular() -> None:
    """With n = 4 the alternation test checks two steps of the three it sorts (`:216-238`, the
    step across the cut is not checked), so the crossing of the two median lines passes for most
    quadrilaterals: the peer gathers n = 4 there in one FSYNC round (its table: 1 (1-2))."""
    algorithm = load_algorithm("oblot-gathering-multiplicity")
    pts = np.array([[0.0, 0.0], [4.0, 0.5], [1.0, 3.0], [3.5, 2.0]])
    cob = np.array(centre_of_biangularity([(float(x), float(y)) for x, y in pts]))
    for i in range(4):
        end = _line(algorithm.compute(np.delete(pts, i, axis=0) - pts[i], P))
        assert end == pytest.approx(tuple(cob - pts[i]), abs=1e-9)


def test_gathering_multiplicity_only_the_leader_moves() -> None:
    """Six robots in general position (no dense point, no centre of biangularity): one moves."""
    algorithm = load_algorithm("oblot-gathering-multiplicity")
    pts = np.array([[0.0, 0.0], [4.0, 0.5], [1.0, 3.0], [3.5, 2.0], [6.0, 4.0], [-1.0, 5.0]])
    moves = [
        bool(algorithm.compute(np.delete(pts, i, axis=0) - pts[i], P).segments) for i in range(6)
    ]
    assert moves == [False, True, False, False, False, False]
