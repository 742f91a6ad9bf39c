"""The four oblot-sim ports against oblot-sim's own runs (tests/data/oblot, 4 x 84 cases): every
case replayed round by round (`fatswarm.agent.oblot_replay`) and equal to the peer's positions to
1e-9 relative, or its disagreement pinned here exactly as docs/ports.md traces it."""

from __future__ import annotations

import json
import math
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fatswarm.agent.gathering import centre_of_gravity
from fatswarm.agent.geometry import sec
from fatswarm.agent.oblot_common import OblotParams, with_self
from fatswarm.agent.oblot_gathering_multiplicity import _angle, _sub
from fatswarm.agent.oblot_replay import (
    COMPARE_REL,
    PEER_ALGORITHMS,
    Mover,
    PeerFrame,
    frames_of,
    move,
    peer_goal,
    replay,
    simulate,
    view_of,
)
from fatswarm.domain.path import Arc, Line
from fatswarm.domain.registry import load_algorithm

DATA = Path(__file__).resolve().parents[1] / "data" / "oblot"


@cache
def _cases(peer: str) -> tuple[dict[str, Any], ...]:
    with open(DATA / f"{peer}.json", encoding="utf-8") as fh:
        return tuple(json.load(fh)["cases"])


def _case(peer: str, case_id: str) -> dict[str, Any]:
    return next(c for c in _cases(peer) if c["id"] == case_id)


def _all_ids() -> list[tuple[str, str]]:
    return [(peer, c["id"]) for peer in PEER_ALGORITHMS for c in _cases(peer)]


# The peer's error -> the words of the port's refusal (or of the predicted crash of its world).
REFUSALS = {
    "Gathering with multiplicity does not support 2 robots": "does not support 2 robots",
    "Does not (yet) support an uneven amount": "does not support an odd n",
    "Multiple dense points with density": "dense points hold",
    "The sum of the string of angles is not a full circle": "does not sum to a full turn",
    "Index 2 out of bounds for length 2": "line-then-arc move ends at its end",
}

# Every case that is not equal round by round, with the first round that differs (replay with
# the peer's way of moving) and why; docs/ports.md, "Disagreements", traces each.
BEYOND_PEER = "past the rounds the peer itself repeats across SEC seeds"
DISAGREE: dict[str, tuple[int, str]] = {
    "GatheringWithMultiplicity-n10-random-FSYNC-nonrigid": (4, "peer leaders split"),
    "GatheringWithMultiplicity-n10-random-FSYNC-rigid": (5, BEYOND_PEER),
    "GatheringWithMultiplicity-n10-random-SSYNC-nonrigid": (6, BEYOND_PEER),
    "GatheringWithMultiplicity-n48-random-FSYNC-rigid": (4, BEYOND_PEER),
    "GatheringWithMultiplicity-n48-random-SSYNC-nonrigid": (6, BEYOND_PEER),
    "GatheringWithMultiplicity-n8-collinear-symmetric-SSYNC-rigid": (1, "half turns"),
    "GatheringWithMultiplicity-n8-collinear-symmetric-SSYNC-nonrigid": (1, "half turns"),
    "MoveAlongSEC-n12-robot-at-sec-centre-FSYNC-nonrigid": (1, BEYOND_PEER),
    "MoveAlongSEC-n12-robot-at-sec-centre-SSYNC-nonrigid": (5, BEYOND_PEER),
    "MoveAlongSEC-n64-random-FSYNC-nonrigid": (3, BEYOND_PEER),
}
# The peer throws one rule, the port refuses by another (both on one collinear start).
OTHER_REFUSAL = {
    "GatheringWithMultiplicity-n6-collinear-FSYNC-rigid": "The CoB is null",
    "GatheringWithMultiplicity-n6-collinear-FSYNC-nonrigid": "The CoB is null",
    "GatheringWithMultiplicity-n8-collinear-symmetric-FSYNC-rigid": "multiple leaders",
    "GatheringWithMultiplicity-n8-collinear-symmetric-FSYNC-nonrigid": "multiple leaders",
    "GatheringWithMultiplicity-n8-collinear-symmetric-SSYNC-rigid": "multiple leaders",
    "GatheringWithMultiplicity-n8-collinear-symmetric-SSYNC-nonrigid": "multiple leaders",
}
# The peer crashed in a round its data does not keep (a non-rigid stop at a path's very end).
UNREPLAYABLE_CRASH = {"MoveAlongSEC-n2-horizontal-SSYNC-nonrigid"}


def test_the_data_holds_at_least_20_cases_per_algorithm_with_n_from_2_to_64() -> None:
    for peer in PEER_ALGORITHMS:
        cases = _cases(peer)
        sizes = {len(c["start"]) for c in cases}
        assert len(cases) >= 20 and min(sizes) == 2 and max(sizes) == 64


@pytest.mark.parametrize(("peer", "case_id"), _all_ids())
def test_each_peer_case_is_equal_round_by_round_or_its_disagreement_is_the_pinned_one(
    peer: str, case_id: str
) -> None:
    case = _case(peer, case_id)
    got = replay(case, load_algorithm(PEER_ALGORITHMS[peer]), Mover.PEER)
    assert len(got.rounds) == len(case["rounds"])
    if case_id in DISAGREE:
        first, why = DISAGREE[case_id]
        assert got.first_disagreement == first
        if why == BEYOND_PEER:
            assert first > case["sec_seed_check"]["agreeing_stored_rounds"]
    else:
        assert got.first_disagreement is None, [r for r in got.rounds if r.failed]
        assert got.max_error_rel <= COMPARE_REL
    if case["stopped"] != "error":
        return
    failed = got.error_round_failed
    assert failed is not None
    if case_id in UNREPLAYABLE_CRASH:
        assert failed == {}  # every robot's compute is fine there: the crash is the peer's world
        return
    assert failed, "the peer threw, the port would go on"
    words = OTHER_REFUSAL.get(case_id)
    if words is not None:
        assert words in case["error"]
        assert all("does not sum to a full turn" in m for m in failed.values())
        return
    want = next(ours for theirs, ours in REFUSALS.items() if theirs in case["error"])
    assert all(want in m for m in failed.values()), failed


def test_go_to_cog_and_go_to_rightmost_agree_in_all_168_cases_to_1e_14() -> None:
    worst = 0.0
    for peer in ("GoToCoG", "GoToRightMost"):
        algorithm = load_algorithm(PEER_ALGORITHMS[peer])
        for case in _cases(peer):
            got = replay(case, algorithm, Mover.FATSWARM)
            assert got.first_disagreement is None
            worst = max(worst, got.max_error_rel)
    assert worst < 1e-14


def test_move_along_sec_arc_turns_clockwise_in_the_peer_and_anticlockwise_in_the_port() -> None:
    """The port turns the half circle anticlockwise in the robot's frame (`clockwise = false`,
    MoveAlongSEC.java:20); the peer's world turns it clockwise in global coordinates whatever the
    frame. In a frame without a mirror the two end points of a partial turn are mirror images
    about the robot's diameter: pinned on the first robot of the square's first FSYNC round."""
    case = _case("MoveAlongSEC", "MoveAlongSEC-n4-square-FSYNC-nonrigid")
    frame = frames_of(case)[0]
    assert not frame.chirality
    pos = np.asarray(case["start"], dtype=np.float64)
    budget = float(case["rounds"][0]["move_time"])
    own = (float(pos[0, 0]), float(pos[0, 1]))
    local = load_algorithm("oblot-move-along-sec").compute(
        view_of(pos, 0, frame), OblotParams(4, 0.0)
    )
    path = frame.path_to_global(local, own)
    (arc,) = path.segments  # on the circle: no line first
    assert isinstance(arc, Arc) and arc.sweep == pytest.approx(math.pi)
    ours = move(own, path, False, budget, Mover.FATSWARM)
    theirs = case["rounds"][0]["positions"][0]
    assert move(own, path, False, budget, Mover.PEER) == pytest.approx(theirs, abs=1e-12)
    cx, cy = arc.center
    turned = math.atan2(ours[1] - cy, ours[0] - cx) - math.atan2(own[1] - cy, own[0] - cx)
    back = math.atan2(theirs[1] - cy, theirs[0] - cx) - math.atan2(own[1] - cy, own[0] - cx)
    radius = math.hypot(own[0] - cx, own[1] - cy)
    assert math.remainder(turned, 2 * math.pi) == pytest.approx(budget / radius)
    assert math.remainder(back, 2 * math.pi) == pytest.approx(-budget / radius)


def test_move_along_sec_peer_times_the_arc_from_the_line_length_not_after_it() -> None:
    """A robot off the circle goes straight to it (length l1), then along the arc (l2): past the
    line the peer times the arc over the budget's [l1, l2] instead of [l1, l1 + l2]
    (CombinedPath.java:73-77), so it turns (d - l1) / (l2 - l1) of the arc, not (d - l1) / l2,
    and clockwise in global coordinates. Pinned on robot 0 of the two dense pairs, FSYNC round 1
    (l1 = 2.42, l2 = 28.95, d = 3.02)."""
    case = _case("MoveAlongSEC", "MoveAlongSEC-n8-two-dense-pairs-FSYNC-nonrigid")
    pos = np.asarray(case["start"], dtype=np.float64)
    frame = frames_of(case)[0]
    budget = float(case["rounds"][0]["move_time"])
    own = (float(pos[0, 0]), float(pos[0, 1]))
    local = load_algorithm("oblot-move-along-sec").compute(
        view_of(pos, 0, frame), OblotParams(8, 0.0)
    )
    path = frame.path_to_global(local, own)
    line, arc = path.segments
    assert isinstance(line, Line) and isinstance(arc, Arc)
    l1 = math.hypot(line.end[0] - own[0], line.end[1] - own[1])
    radius = math.hypot(line.end[0] - arc.center[0], line.end[1] - arc.center[1])
    l2 = math.pi * radius
    assert 0 < l1 < budget < l2
    cx, cy = arc.center
    start_angle = math.atan2(line.end[1] - cy, line.end[0] - cx)
    peer = case["rounds"][0]["positions"][0]
    peer_turn = math.remainder(math.atan2(peer[1] - cy, peer[0] - cx) - start_angle, 2 * math.pi)
    assert peer_turn == pytest.approx(-math.pi * (budget - l1) / (l2 - l1), rel=1e-9)
    ours = move(own, path, False, budget, Mover.FATSWARM)
    our_turn = math.remainder(math.atan2(ours[1] - cy, ours[0] - cx) - start_angle, 2 * math.pi)
    sense = -1.0 if frame.chirality else 1.0  # anticlockwise in the robot's frame
    assert our_turn == pytest.approx(sense * math.pi * (budget - l1) / l2, rel=1e-9)


def test_move_along_sec_rigid_rounds_crash_in_the_peer_and_end_at_the_antipode_in_the_port() -> (
    None
):
    """Under rigid moves the peer places the robot of the longest path at exactly its end time,
    where its line-then-arc interpolation runs off its array (CombinedPath.java:60-67): all 42
    rigid cases throw in round 1. The port's move ends on the far side of the circle."""
    port = load_algorithm("oblot-move-along-sec")
    rigid = [c for c in _cases("MoveAlongSEC") if c["movement"] == "rigid"]
    assert len(rigid) == 42
    for case in rigid:
        assert case["rounds"] == [] and "Index 2 out of bounds" in case["error"]
        pos = np.asarray(case["start"], dtype=np.float64)
        frames = frames_of(case)
        for i in range(len(pos)):
            own = (float(pos[i, 0]), float(pos[i, 1]))
            local = port.compute(view_of(pos, i, frames[i]), OblotParams(len(pos), 0.0))
            end = move(own, frames[i].path_to_global(local, own), True, 0.0, Mover.FATSWARM)
            circle = sec(pos)
            assert math.hypot(end[0] - circle.center[0], end[1] - circle.center[1]) == (
                pytest.approx(circle.radius, rel=1e-9)
            )


def _leaders(pts: list[tuple[float, float]], skip_reverse_of: int | None) -> list[int]:
    """Who leads by the string of angles over every start and both senses, optionally without
    the reverse string that starts at `skip_reverse_of` (the one the peer never tries)."""
    circle = sec(np.asarray(pts))
    vecs = [_sub(p, circle.center) for p in pts]
    n = len(pts)
    order = sorted(range(n), key=lambda i: math.atan2(vecs[i][1], vecs[i][0]))
    sa = [_angle(vecs[order[i]], vecs[order[(i + 1) % n]]) for i in range(n)]
    cands = []
    for j in range(n):
        cands.append((sa[j:] + sa[:j], [order[(j + i) % n] for i in range(n)]))
        if order[j] != skip_reverse_of:
            cands.append(
                ([sa[(j - 1 - i) % n] for i in range(n)], [order[(j - i) % n] for i in range(n)])
            )
    _, who = min(cands, key=lambda c: c[0])
    r = circle.radius
    return [i for i in who if not abs(math.hypot(*vecs[i]) - r) < r * 1e-13]


def test_gathering_multiplicity_peer_robots_split_on_the_leader_where_the_port_agrees() -> None:
    """n = 10, FSYNC, non-rigid, after round 3 (a round the peer repeats across SEC seeds): every
    port robot names robot 8 the leader and robot 8 moves out to the circle; the peer moves nobody
    then or in any of its 196 later rounds. Its leader search never tries the reverse of its first
    string (GatheringWithMultiplicity.java:106-134), and which string is first is decided per robot
    by the sign of a rounding (robot 4 stands diametrically opposite robot 0, the sort's
    reference, :52): without the string that starts at robot 4 backwards, the leader is robot 1,
    and robots that name 1 wait for robots that name 8 and the other way round."""
    case = _case("GatheringWithMultiplicity", "GatheringWithMultiplicity-n10-random-FSYNC-nonrigid")
    after3 = np.asarray(case["rounds"][2]["positions"], dtype=np.float64)
    port = load_algorithm("oblot-gathering-multiplicity")
    frames = frames_of(case)
    movers = [
        i
        for i in range(10)
        if port.compute(view_of(after3, i, frames[i]), OblotParams(10, 0.0)).segments
    ]
    assert movers == [8]
    pts = [(float(x), float(y)) for x, y in after3]
    assert _leaders(pts, None)[0] == 8
    assert _leaders(pts, 4)[0] == 1
    circle = sec(after3)
    v0, v4 = _sub(pts[0], circle.center), _sub(pts[4], circle.center)
    assert abs(abs(_angle(v0, v4)) - math.pi) < 1e-12  # robots 0 and 4: ends of a diameter
    for rnd in case["rounds"][3:]:
        assert rnd["positions"] == case["rounds"][2]["positions"]  # the peer: nobody moves
    assert case["stopped"] == "cap" and case["rounds_run"] == 200


def test_gathering_multiplicity_exactly_collinear_start_is_refused_by_rounding_in_both() -> None:
    """Eight robots evenly spaced on a line: every angle of the string is 0 or a half turn, whose
    sign is the rounding of a zero determinant. The peer's robots split between "multiple
    leaders", "not a full circle" and staying (its data: robots 0 and 7 active in SSYNC round 1
    stay, the next round throws); the port's robots 0, 1, 3, 4, 5 refuse by the sum (:99), the
    others stay."""
    case = _case(
        "GatheringWithMultiplicity", "GatheringWithMultiplicity-n8-collinear-symmetric-SSYNC-rigid"
    )
    got = replay(case, load_algorithm("oblot-gathering-multiplicity"), Mover.PEER)
    assert case["rounds"][0]["active"] == [0, 7]
    assert case["rounds"][0]["positions"] == case["start"]  # the peer's two stay
    assert got.rounds[0].error_rel == 0.0 and set(got.rounds[0].failed) == {0}
    assert got.error_round_failed is not None and sorted(got.error_round_failed) == [0, 1, 3, 4, 5]
    assert "multiple leaders" in case["error"]


def test_the_peer_view_holds_the_others_in_the_robots_frame() -> None:
    case = _case("GoToCoG", "GoToCoG-n7-random-FSYNC-rigid")
    pos = np.asarray(case["start"], dtype=np.float64)
    frame = frames_of(case)[3]
    view = view_of(pos, 3, frame)
    assert view.shape == (6, 2)
    own = (float(pos[3, 0]), float(pos[3, 1]))
    back = [frame.to_global((float(x), float(y)), own) for x, y in view]
    assert np.allclose(back, np.delete(pos, 3, axis=0), rtol=0, atol=1e-12)
    # the centre of gravity is the same in any frame: the port's target maps back onto it
    local = load_algorithm("oblot-go-to-cog").compute(view, OblotParams(7, 0.0))
    (line,) = local.segments
    assert isinstance(line, Line)
    assert frame.to_global(line.end, own) == pytest.approx(centre_of_gravity(pos), abs=1e-12)
    assert len(with_self(view)) == 7


def test_the_worlds_grid_alone_parts_gathering_multiplicity_from_the_peer() -> None:
    """The runs the world cannot match (test_oblot_world.py, WORLD_DISAGREE) replayed here in the
    peer's shared frame S, from S(start), both-axes robots: exact, they equal the peer; with every
    position snapped to fatswarm's 2^-30 grid, they part at the world's round (a robot just put on
    the circle is off it by up to 2^-31, and the peer's rules test 1e-13)."""
    grid = 2.0**-30
    port = load_algorithm("oblot-gathering-multiplicity")
    same = PeerFrame(1.0, 0.0, False)
    for name, first in (("n6-hexagon", 1), ("n16-random", 3), ("n32-random", 3)):
        case = _case("GatheringWithMultiplicity", f"GatheringWithMultiplicity-{name}-FSYNC-rigid")
        frame = frames_of(case)[0]
        for snap in (False, True):
            pos = np.asarray([frame.to_local((x, y), (0.0, 0.0)) for x, y in case["start"]])
            if snap:
                pos = np.round(pos / grid) * grid
            parted = None
            for rnd in case["rounds"]:
                new = pos.copy()
                for i in range(len(pos)):
                    own = (float(pos[i, 0]), float(pos[i, 1]))
                    try:
                        local = port.compute(view_of(pos, i, same), OblotParams(len(pos), 0.0))
                    except ValueError:
                        continue
                    new[i] = move(own, same.path_to_global(local, own), True, 0.0, Mover.FATSWARM)
                pos = np.round(new / grid) * grid if snap else new
                back = [frame.to_global((float(x), float(y)), (0.0, 0.0)) for x, y in pos]
                if not np.allclose(back, rnd["positions"], rtol=0, atol=1e-8):
                    parted = int(rnd["round"])
                    break
            assert parted == (first if snap else None), (name, snap)


def test_free_runs_from_the_peers_table_match_its_fsync_rigid_counts() -> None:
    """bench/bench_oblot.py's free runs (`simulate`) on the table's 140 starts: FSYNC with rigid
    moves is the peer's very run, and GoToCoG and GoToRightMost reach the goal in the same round
    as the peer in every one of them (round 1)."""
    with open(DATA / "table.json", encoding="utf-8") as fh:
        table = json.load(fh)
    for peer in ("GoToCoG", "GoToRightMost"):
        port = load_algorithm(PEER_ALGORITHMS[peer])
        theirs = table["results"][peer]["FSYNC rigid"]
        for st, want in zip(table["starts"], theirs, strict=True):
            start = np.asarray(st["start"], dtype=np.float64)
            frame = PeerFrame(float(st["frame"][0]), float(st["frame"][1]), bool(st["frame"][2]))
            got = simulate(
                start,
                [frame] * len(start),
                port,
                peer_goal(peer, start),
                False,
                True,
                np.random.default_rng(0),
                5,
            )
            assert (got.stopped, got.goal_round) == (want["stopped"], want["goal_round"])
