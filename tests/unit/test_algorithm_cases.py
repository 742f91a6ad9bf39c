"""Each configuration of algorithm-cases.json (the implementer's notes, G1-G22) as a named test.

For each: the phase and the kind of the first plan, the figures the notes give, and a full
lockstep run that forms the circle with zero collisions under every scheduler.
"""

from __future__ import annotations

import json
from pathlib import Path as FsPath

import numpy as np
import pytest

from fatswarm.agent.algorithm import plan
from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.domain.path import end_point, path_length

CASES = json.loads((FsPath(__file__).parents[1] / "data" / "algorithm-cases.json").read_text())
PHASE = {"SECExpansion": "expansion", "FormUCircle": "formation"}


def first_plan(name: str):  # type: ignore[no-untyped-def]
    case = CASES[name]
    pts = np.asarray(case["positions"], dtype=np.float64)
    return pts, plan(pts, Params(case["n"], case["a"]))


@pytest.mark.parametrize("name", sorted(CASES))
def test_case_first_plan_matches_the_notes(name: str) -> None:
    case = CASES[name]
    _, p = first_plan(name)
    assert p.kind == case["expected_first_plan"]
    if p.kind.startswith("exp"):
        assert p.phase == "expansion"
    elif p.kind == "done":
        assert p.phase == "done"
    else:
        assert p.phase == PHASE[case["expected_phase"]]


@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
def test_case_forms_the_circle_without_collision(name: str, scheduler: str) -> None:
    case = CASES[name]
    params = Params(case["n"], case["a"])
    result = run_lockstep(
        np.asarray(case["positions"]), params, make_scheduler(scheduler, params.n, seed=3), seed=7
    )
    assert result.status == "formed"
    assert result.collisions == 0
    # every robot moves at most once in FormUCircle, plus one expansion move (notes §5)
    assert result.moves <= params.n + 2


def lengths(name: str) -> dict[int, float]:
    pts, p = first_plan(name)
    return {i: path_length((pts[i, 0], pts[i, 1]), path) for i, path in p.moves.items()}


def test_e1_case_decided_on_sec_robots_only() -> None:
    # G3: only the interior robot is unmatched; the SEC robots are symmetric -> pair (±3, 0)
    pts, p = first_plan("E1_case1_no_leader")
    assert sorted(p.moves) == [0, 1]
    ends = sorted(end_point((pts[i, 0], pts[i, 1]), p.moves[i]) for i in p.moves)
    assert ends[0] == pytest.approx((-3.364, 0.0), abs=1e-3)
    assert ends[1] == pytest.approx((3.364, 0.0), abs=1e-3)


def test_e2_north_robot_leads_when_all_sec_robots_are_on_l() -> None:
    _, p = first_plan("E2_case2b_no_pair")  # G4
    assert list(p.moves) == [0]
    assert end_point((0.0, 2.5), p.moves[0]) == pytest.approx((0.0, 3.1569), abs=1e-4)


def test_e3_mirror_leaders_move_radially_not_to_the_same_q() -> None:
    pts, p = first_plan("E3_case2_same_q")  # G5
    ends = {i: end_point((pts[i, 0], pts[i, 1]), p.moves[i]) for i in p.moves}
    assert ends[0] == pytest.approx((-1.5796, 3.6193), abs=1e-4)
    assert ends[1] == pytest.approx((1.5796, 3.6193), abs=1e-4)


def test_e4_leader_moves_radially_and_the_robot_at_o_stays() -> None:
    assert lengths("E4_q_branch") == {2: pytest.approx(1.507, abs=1e-3)}


def test_e5_settled_robots_do_not_move_and_the_free_one_slides() -> None:
    assert lengths("E5_settled_oscillation") == {3: pytest.approx(4.638, abs=1e-3)}  # G8, G14


def test_e6_interior_robot_goes_first_to_keep_the_sec() -> None:
    assert lengths("E6_sec_shrink") == {2: pytest.approx(4.0)}  # G9


def test_e7_single_blockers_take_their_targets_by_chord() -> None:
    assert list(lengths("E7_all_blocked").values()) == [pytest.approx(1.478, abs=1e-3)]  # G7


def test_e9_side_four_turns_the_deadlock_into_an_expansion() -> None:
    _, p = first_plan("E9_double_block_deadlock")  # G1
    assert p.kind == "exp-case1" and list(p.moves) == [0]


def test_e10_robot_on_l_slides_around_its_touching_neighbour() -> None:
    assert lengths("E10_collinear_L") == {1: pytest.approx(3.176, abs=1e-3)}  # G13, G14


def test_e11_equal_candidates_do_not_both_move() -> None:
    _, p = first_plan("E11_tie_same_y")  # G11, G12
    assert list(p.moves) == [2]


def test_e12_rotated_pair_is_already_final() -> None:
    _, p = first_plan("E12_n2_rotated")  # G10
    assert p.kind == "done" and not p.moves


def test_e16_robot_on_l_breaks_the_symmetry_alone() -> None:
    assert lengths("E16_sym_onL_breaking") == {2: pytest.approx(2.399, abs=1e-3)}  # G13


def test_e17_blocked_sec_robot_reaches_its_target_without_a_swap() -> None:
    assert lengths("E17_note_swap") == {5: pytest.approx(8.153, abs=1e-3)}  # G15


def test_e18_dense_mirror_pair_slides() -> None:
    got = lengths("E18_dense_cluster")  # G14
    assert sorted(got) == [5, 6]
    assert all(v == pytest.approx(1.966, abs=1e-3) for v in got.values())
