"""The views a record keeps (`--record-views`) re-checked from the record alone, by a computation
independent of world/sight.py: centre distances for sight, segment distances for opaque-centres,
rim sampling for opaque (pairs within the sampling's margin are left out, and counted)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.world.record_read import read_record

LIT = str(Path(__file__).resolve().parents[1] / "data" / "lit_spread.py") + ":ALGORITHM"
RIM = 2048  # rim samples for `opaque`; margin: a sample is at most pi / RIM of arc from any point


def _clearance(o: np.ndarray, p: np.ndarray, others: np.ndarray) -> float:
    """The least distance from the centres `others` to the segment o-p."""
    if not len(others):
        return np.inf
    d = p - o
    t = np.clip(((others - o) @ d) / float(d @ d), 0.0, 1.0)
    return float(np.min(np.hypot(*(o + t[:, None] * d - others).T)))


def _sees(pos: np.ndarray, o: int, j: int, rule: str) -> bool | None:
    """Whether o sees j under `rule` (None: too close to call by sampling)."""
    third = np.delete(pos, [o, j], axis=0)
    if rule == "transparent":
        return True
    if rule == "opaque-centres":
        return _clearance(pos[o], pos[j], third) >= 1.0 - 1e-8
    if not len(third):
        return True
    angles = np.linspace(0.0, 2 * np.pi, RIM, endpoint=False)
    d = pos[j] + np.stack((np.cos(angles), np.sin(angles)), axis=1) - pos[o]  # (RIM, 2)
    rel = third - pos[o]  # (k, 2)
    t = np.clip((d @ rel.T) / np.sum(d * d, axis=1)[:, None], 0.0, 1.0)  # (RIM, k)
    gap = np.hypot(t * d[:, :1] - rel[:, 0], t * d[:, 1:] - rel[:, 1])
    best = float(gap.min(axis=1).max())
    margin = np.pi / RIM
    if abs(best - 1.0) <= margin:
        return None
    return best > 1.0


@pytest.mark.parametrize(
    ("scheduler", "visibility", "sight"),
    [
        ("fsync", "opaque-centres", None),
        ("ssync", "opaque", None),
        ("fsync", "transparent", 5.0),
        ("ssync", "opaque", 7.0),
    ],
)
def test_every_recorded_view_is_what_an_independent_computation_sees(
    tmp_path: Path, scheduler: str, visibility: str, sight: float | None
) -> None:
    record = tmp_path / "r.jsonl"
    fatswarm.run(
        9,
        algorithm=LIT,
        seed=2,
        start="clustered",
        scheduler=scheduler,
        visibility=visibility,
        sight=sight,
        record_views=True,
        record=record,
        max_rounds=25,
    )
    run = read_record(str(record))
    before = np.asarray(run.header.initial, dtype=np.float64)
    checked = uncertain = hidden = 0
    for entry in run.rounds:
        assert set(entry.extra["views"]) == {str(r) for r in entry.active}
        for robot, ids in entry.extra["views"].items():
            o = int(robot)
            for j in range(len(before)):
                if j == o:
                    continue
                near = sight is None or np.hypot(*(before[j] - before[o])) <= sight
                sees = _sees(before, o, j, visibility) if near else False
                if sees is None:
                    uncertain += 1
                    continue
                checked += 1
                hidden += not sees
                assert (j in ids) == sees, (entry.round, o, j)
        before = np.asarray(entry.positions, dtype=np.float64)
    assert checked > 200 and uncertain <= checked // 100
    assert hidden > 0  # the case hides someone: the check can fail
