"""Algorithms of other kinds through the seam: networked runs equal lock-step runs bit for bit."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from netharness import assert_same_run

import fatswarm
from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration
EXAMPLE = str(Path(__file__).resolve().parents[2] / "examples" / "spread_out.py") + ":ALGORITHM"


def _networked(tmp_path: Path, *flags: str) -> Path:
    record = tmp_path / "net.jsonl"
    argv = [
        sys.executable,
        "-m",
        "fatswarm.deploy.cli",
        "run",
        "--no-dashboard",
        "-q",
        "--record",
        str(record),
        *flags,
    ]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=240, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "formed in" in done.stdout, done.stdout
    return record


@pytest.mark.parametrize(
    ("algorithm", "params", "flags"),
    [
        ("gathering", {}, ()),
        (EXAMPLE, {"spacing": "5"}, ("--param", "spacing=5")),
    ],
    ids=["gathering", "example-file"],
)
def test_a_networked_run_of_another_algorithm_records_the_lockstep_run(
    tmp_path: Path, algorithm: str, params: dict[str, str], flags: tuple[str, ...]
) -> None:
    net = _networked(
        tmp_path, "-n", "5", "--seed", "3", "--scheduler", "ssync", "--algorithm", algorithm, *flags
    )
    lock = tmp_path / "lock.jsonl"
    result = fatswarm.run(
        5, algorithm=algorithm, params=params, seed=3, scheduler="ssync", record=lock
    )
    assert result.status == "formed" and result.collisions == 0
    assert_same_run(read_record(net), read_record(lock))
    header = read_record(net).header
    assert header.algorithm_ref == algorithm
    assert {"fatswarm_version", "start", "fairness", "move_timeout", "command"} <= set(header.extra)
