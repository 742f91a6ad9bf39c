"""A compute that fails, networked (real processes on loopback) against lock step: the agent says so
in its move, so the world books it at once (no move timeout), the round lines' `failed` and the
verdict are the lock step's, under a round model and an async one."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from netharness import assert_same_run, fatswarm_runs

from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration

VERDICTS = ("formed", "not formed")  # how the summary's first line starts
MOVE_TIMEOUT_S = 30  # a round that waited for a failing robot's move would take this long

CASES = {
    # the paper's algorithm sees 4 of the 5 others: ViewError, then a stall of failing robots
    "opaque-ssync": ["-n", "6", "--seed", "3", "--visibility", "opaque", "--scheduler", "ssync"],
    # three failures on the way, and formed all the same
    "opaque-centralized": [
        "-n", "5", "--seed", "2", "--visibility", "opaque", "--scheduler", "centralized",
    ],
    "opaque-async": ["-n", "6", "--seed", "3", "--visibility", "opaque", "--scheduler", "async"],
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_failing_compute_is_recorded_the_same_networked_and_in_lock_step_without_a_timeout(
    tmp_path: Path, case: str
) -> None:
    flags = [*CASES[case], "--max-rounds", "200"]
    net, lock = tmp_path / "net.jsonl", tmp_path / "lock.jsonl"
    started = time.monotonic()
    (code, out), (lock_code, lock_out) = fatswarm_runs(  # side by side
        [*flags, "--record", str(net), "--no-dashboard", "--move-timeout", str(MOVE_TIMEOUT_S)],
        [*flags, "--record", str(lock), "--lockstep"],
    )
    wall = time.monotonic() - started  # both runs': the networked one took no longer
    assert code in (0, 1), out
    assert wall < MOVE_TIMEOUT_S, f"a round waited for a failing robot: {wall:.1f} s\n{out}"
    net_verdict = next(line for line in out.splitlines() if line.startswith(VERDICTS))
    assert "; the algorithm failed " in net_verdict and ", first robot " in net_verdict
    assert lock_code in (0, 1), lock_out
    a, b = read_record(str(net)), read_record(str(lock))
    assert_same_run(a, b)
    failed = [entry.extra["failed"] for entry in b.rounds if "failed" in entry.extra]
    assert failed and all("ViewError: the view holds" in why for f in failed for why in f.values())
    assert not any("timed_out" in entry.extra for entry in a.rounds)
    assert net_verdict in lock_out.splitlines()  # the same verdict, failures and all
    assert "Traceback" not in out  # one line per kind of failure, no traceback
