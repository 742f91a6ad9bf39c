"""Every robot-model axis, networked (real processes on loopback) against lock step: the same
record, line for line, for sight, obstruction, each lights model, each frames model, a frame
per Look and noisy sensors (the world draws each Look's error in both), composed with the round
and async schedulers, non-rigid moves and crashes."""

from __future__ import annotations

from pathlib import Path

import pytest
from netharness import assert_same_run, fatswarm_runs

from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration

LIT = str(Path(__file__).resolve().parents[1] / "data" / "lit_spread.py") + ":ALGORITHM"

CASES = {
    "sight-opaque-views-ssync": [
        "--algorithm", LIT, "--scheduler", "ssync", "--sight", "6", "--visibility", "opaque",
        "--record-views",
    ],
    "internal-disoriented-every-look-async-slowest-non-rigid": [
        "--algorithm", LIT, "--scheduler", "async-slowest", "--lights", "internal",
        "--frames", "disoriented", "--frame-change", "every-look", "--non-rigid", "1",
    ],
    "external-opaque-centres-fsync-crash": [
        "--algorithm", LIT, "--scheduler", "fsync", "--lights", "external",
        "--visibility", "opaque-centres", "--crash", "1", "--record-views",
    ],
    "paper-chirality-ssync": ["--scheduler", "ssync", "--frames", "chirality"],
    "noise-chirality-ssync-views": [
        "--scheduler", "ssync", "--noise", "0.02", "--frames", "chirality", "--record-views",
    ],
    "gathering-sight-opaque-async-views": [
        "--algorithm", "gathering", "--scheduler", "async", "--sight", "8",
        "--visibility", "opaque", "--record-views",
    ],
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_model_axis_records_the_same_run_networked_and_in_lock_step(
    tmp_path: Path, case: str
) -> None:
    # noisy sensors never form here: 100 rounds (each Look's error drawn alike) pin what 400 did
    rounds = "100" if "--noise" in CASES[case] else "400"
    flags = ["-n", "5", "--seed", "4", "--max-rounds", rounds, "-q", *CASES[case]]
    net, lock = tmp_path / "net.jsonl", tmp_path / "lock.jsonl"
    (code, out), (lock_code, lock_out) = fatswarm_runs(
        [*flags, "--record", str(net), "--no-dashboard"],
        [*flags, "--record", str(lock), "--lockstep"],
    )
    assert code in (0, 1), out
    assert lock_code in (0, 1), lock_out
    a, b = read_record(str(net)), read_record(str(lock))
    assert a.header.extra.get("model") == b.header.extra.get("model") is not None
    assert_same_run(a, b)
    if "--record-views" in flags:
        assert all("views" in entry.extra for entry in b.rounds)
    if "lit_spread" in str(flags):
        assert all(len(entry.extra["lights"]) == 5 for entry in b.rounds)
