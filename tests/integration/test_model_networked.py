"""Every robot-model axis, networked (real processes on loopback) against lock step: the same
record, line for line, for sight, obstruction, each lights model, each frames model, a frame
per Look and noisy sensors (the world draws each Look's error in both), composed with the round
and async schedulers, non-rigid moves and crashes."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from netharness import assert_same_run

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


def _fatswarm_run(flags: list[str]) -> tuple[int, str]:
    """`fatswarm run FLAGS` in its own process group: exit code and output (killed after 240 s)."""
    argv = [sys.executable, "-m", "fatswarm.deploy.cli", "run", *flags]
    proc = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    try:
        out, _ = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, out.decode(errors="replace")


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_model_axis_records_the_same_run_networked_and_in_lock_step(
    tmp_path: Path, case: str
) -> None:
    flags = ["-n", "5", "--seed", "4", "--max-rounds", "400", "-q", *CASES[case]]
    net, lock = tmp_path / "net.jsonl", tmp_path / "lock.jsonl"
    code, out = _fatswarm_run([*flags, "--record", str(net), "--no-dashboard"])
    assert code in (0, 1), out
    code, out = _fatswarm_run([*flags, "--record", str(lock), "--lockstep"])
    assert code in (0, 1), out
    a, b = read_record(str(net)), read_record(str(lock))
    assert a.header.extra.get("model") == b.header.extra.get("model") is not None
    assert_same_run(a, b)
    if "--record-views" in flags:
        assert all("views" in entry.extra for entry in b.rounds)
    if "lit_spread" in str(flags):
        assert all(len(entry.extra["lights"]) == 5 for entry in b.rounds)
