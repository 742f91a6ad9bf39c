"""Point robots (`--bodies points`), networked (real processes on loopback) against lock step: the
same record, line for line, for robots that meet and share a point, with and without multiplicity
detection, under obstruction by collinearity, round and async schedulers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from netharness import assert_same_run, fatswarm_runs

from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration

MEET = str(Path(__file__).resolve().parents[1] / "data" / "meet_points.py")

CASES = {
    "meet-multiplicity-ssync": ["--algorithm", f"{MEET}:ALGORITHM", "--scheduler", "ssync"],
    "meet-once-fsync-views": [
        "--algorithm", f"{MEET}:ONCE", "--scheduler", "fsync", "--record-views",
    ],
    "meet-once-opaque-async-views": [
        "--algorithm", f"{MEET}:ONCE", "--scheduler", "async", "--visibility", "opaque",
        "--record-views",
    ],
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(CASES))
def test_point_robots_record_the_same_run_networked_and_in_lock_step(
    tmp_path: Path, case: str
) -> None:
    flags = ["-n", "5", "--seed", "4", "--max-rounds", "400", "-q", "--bodies", "points"]
    flags += CASES[case]
    net, lock = tmp_path / "net.jsonl", tmp_path / "lock.jsonl"
    (code, out), (lock_code, lock_out) = fatswarm_runs(
        [*flags, "--record", str(net), "--no-dashboard"],
        [*flags, "--record", str(lock), "--lockstep"],
    )
    assert code in (0, 1), out
    assert lock_code in (0, 1), lock_out
    a, b = read_record(str(net)), read_record(str(lock))
    assert a.header.extra["model"]["bodies"] == b.header.extra["model"]["bodies"] == "points"
    assert_same_run(a, b)
    assert not any(entry.collisions for entry in b.rounds)
    if "opaque" not in case:  # the robots met: every one at one point
        assert b.result is not None and str(b.result.status) == "formed"
        final = b.rounds[-1].positions
        assert np.ptp(final[:, 0]) <= 1e-6 and np.ptp(final[:, 1]) <= 1e-6


def test_point_robots_that_start_at_shared_points_run_the_same_networked(tmp_path: Path) -> None:
    init = tmp_path / "start.json"
    init.write_text('{"positions": [[0, 0], [0, 0], [3, 1], [3, 1], [10, -2]]}')
    flags = ["--init", str(init), "--seed", "1", "-q", "--bodies", "points"]
    flags += ["--algorithm", f"{MEET}:ONCE", "--scheduler", "ssync"]
    net, lock = tmp_path / "net.jsonl", tmp_path / "lock.jsonl"
    (code, out), (lock_code, lock_out) = fatswarm_runs(
        [*flags, "--record", str(net), "--no-dashboard"],
        [*flags, "--record", str(lock), "--lockstep"],
    )
    assert code == 0, out
    assert lock_code == 0, lock_out
    assert_same_run(read_record(str(net)), read_record(str(lock)))
