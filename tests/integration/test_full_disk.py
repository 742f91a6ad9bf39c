"""A record that cannot be written (a full disk, simulated with a file size limit) stops a lock-step
run with one line and exit 4; freed, --resume (which drops the torn line the run wrote as it
stopped) ends it exactly as an uninterrupted run.

(A networked run cannot be limited so: Zenoh's shared-memory segments are files too.)"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from netharness import assert_same_run

from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration


def _limited(size: int) -> Callable[[], None]:
    """In the child: files may not grow past `size` bytes (writes then fail: EFBIG)."""

    def limit() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))

    return limit


def _fatswarm(*argv: str, limit: int | None = None) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    if limit is not None:  # coverage (a measured test run) could not save its data either
        for name in ("COVERAGE_PROCESS_CONFIG", "COVERAGE_PROCESS_START"):
            env.pop(name, None)
    return subprocess.run(
        [sys.executable, "-m", "fatswarm.deploy.cli", "run", "-q", *argv],
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
        env=env,
        preexec_fn=None if limit is None else _limited(limit),
    )


def test_a_full_disk_stops_the_run_with_one_line_and_resume_finishes_it_identically(
    tmp_path: Path,
) -> None:
    run = ["--lockstep", "-n", "8", "--seed", "3", "--scheduler", "ssync"]
    whole = tmp_path / "whole.jsonl"
    assert _fatswarm(*run, "--record", str(whole)).returncode == 0
    cut = tmp_path / "cut.jsonl"
    stopped = _fatswarm(*run, "--record", str(cut), limit=whole.stat().st_size // 2)
    assert stopped.returncode == 4, stopped.stdout + stopped.stderr
    said = [line for line in stopped.stderr.splitlines() if "cannot write the run record" in line]
    assert len(said) == 1 and "File too large" in said[0], stopped.stderr
    assert "Traceback" not in stopped.stderr
    kept = read_record(cut, allow_torn_end=True)
    assert kept.result is None and 0 < len(kept.rounds) < len(read_record(whole).rounds)
    assert "go on with `fatswarm run --lockstep --record" in said[0], said[0]
    done = _fatswarm("--lockstep", "--record", str(cut), "--resume")  # the torn end and all
    assert done.returncode == 0, done.stdout + done.stderr
    if kept.torn_line is not None:  # the lock step drops the line it tore itself, and says so
        assert done.stderr.count("dropped the torn last line") == 1, done.stderr
    assert_same_run(read_record(cut), read_record(whole))
