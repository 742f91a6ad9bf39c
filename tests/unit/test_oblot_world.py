"""The oblot-sim ports run through fatswarm's world (lock step, point bodies, both-axes frames,
FSYNC, rigid) from the peer's own starts, against the peer's positions per round (1e-9 relative,
past the world's 2^-30 grid): docs/ports.md, "End to end".

The peer's shared frame is a similarity S of the global frame (its unit, rotation and mirror,
one for every robot), so a peer robot sees S(p_j - p_i) = S(p_j) - S(p_i): exactly what a
both-axes robot of fatswarm sees when the run starts from S(start). The world runs from S(start)
and its positions are mapped back by S^-1.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import fatswarm
from fatswarm.agent.oblot_replay import COMPARE_REL, PEER_ALGORITHMS, frames_of
from fatswarm.domain.robot_model import AXES

DATA = Path(__file__).resolve().parents[1] / "data" / "oblot"
GRID = 2.0**-30  # the world snaps every position to it (docs/model.md)

# Cases where the world parts from the peer, with the first round that differs: the world's grid
# moves a robot the port has just put on the circle (or a regular hexagon's vertices) by up to
# 2^-31, far past the peer's tolerance of 1e-13, so its rules read another configuration
# (docs/ports.md, "The world's grid"; pinned without the world in test_oblot_peer_cases.py).
WORLD_DISAGREE = {
    "GatheringWithMultiplicity-n6-hexagon-FSYNC-rigid": 1,
    "GatheringWithMultiplicity-n16-random-FSYNC-rigid": 3,
    "GatheringWithMultiplicity-n32-random-FSYNC-rigid": 3,
    "GatheringWithMultiplicity-n48-random-FSYNC-rigid": 3,
}


def _missing() -> str | None:
    """What this branch lacks for point robots in both-axes frames, or None."""
    axes = {a.name: a for a in AXES}
    if "bodies" not in axes:
        return "the model axis 'bodies' (--bodies points) is not in robot_model.AXES yet"
    if "both-axes" not in axes["frames"].words:
        return "the frames value 'both-axes' (--frames both-axes) is not there yet"
    return None


@cache
def _cases(peer: str) -> tuple[dict[str, Any], ...]:
    with open(DATA / f"{peer}.json", encoding="utf-8") as fh:
        return tuple(json.load(fh)["cases"])


def _world_cases() -> list[tuple[str, str]]:
    """FSYNC, rigid, one shared frame, at least one round the peer ran (MoveAlongSEC has none:
    the peer crashes at the end of every rigid round, docs/ports.md)."""
    return [
        (peer, c["id"])
        for peer in PEER_ALGORITHMS
        for c in _cases(peer)
        if c["scheduler"] == "FSYNC"
        and c["movement"] == "rigid"
        and c["frames_mode"] == "shared"
        and c["rounds"]
    ]


@pytest.mark.parametrize(("peer", "case_id"), _world_cases())
def test_a_port_run_by_the_world_with_point_bodies_matches_the_peer_round_by_round(
    peer: str, case_id: str
) -> None:
    missing = _missing()
    if missing is not None:
        pytest.skip(f"needs point robots in both-axes frames: {missing}")
    case = next(c for c in _cases(peer) if c["id"] == case_id)
    frame = frames_of(case)[0]
    start = [frame.to_local((x, y), (0.0, 0.0)) for x, y in case["start"]]
    seen: dict[int, np.ndarray] = {}

    def keep(report: Any) -> None:
        pos = np.asarray(report.entry.positions, dtype=np.float64)
        seen[int(report.entry.round)] = np.asarray(
            [frame.to_global((float(x), float(y)), (0.0, 0.0)) for x, y in pos]
        )

    fatswarm.run(
        len(start),
        algorithm=PEER_ALGORITHMS[peer],
        positions=np.asarray(start, dtype=np.float64),
        scheduler="fsync",
        max_rounds=len(case["rounds"]),
        on_round=keep,
        bodies="points",
        frames="both-axes",
    )
    first = WORLD_DISAGREE.get(case_id)
    for rnd in case["rounds"]:
        k = int(rnd["round"])
        peer_pos = np.asarray(rnd["positions"], dtype=np.float64)
        scale = max(1.0, float(np.abs(peer_pos).max()))
        # the world's grid, mapped back by S^-1 (1 / unit), once per round so far
        slack = COMPARE_REL * scale + 2.0 * GRID * k / frame.unit
        equal = k in seen and float(np.abs(seen[k] - peer_pos).max()) <= slack
        assert equal == (first is None or k < first), k
        if first is not None and k == first:
            break
