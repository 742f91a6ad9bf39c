"""A record that cannot be written (a full disk, simulated with a file size limit) stops a lock-step
run with one line and exit 4; freed, --resume (which drops the torn line the run wrote as it
stopped) ends it exactly as an uninterrupted run. A networked run on a full file system (a small
tmpfs) says the lock step's line, its world, coordinator and launcher naming the same rounds."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from netharness import assert_same_run

from fatswarm.deploy import cli
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
    # the uninterrupted run in this process (cli.main); the others are `fatswarm run` processes
    run = ["--lockstep", "-n", "8", "--seed", "3", "--scheduler", "ssync"]
    whole = tmp_path / "whole.jsonl"
    assert cli.main(["run", "-q", *run, "--record", str(whole)]) == 0
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


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 8 kB file system (tmpfs) to write a record on; skipped where it cannot be mounted (not
    root). A networked run cannot be limited with RLIMIT_FSIZE: its agents' Zenoh shared memory
    lives in files too."""
    disk = tmp_path / "small"
    disk.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=8k", "tmpfs", str(disk)],
        capture_output=True,
        check=False,
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {mounted.stderr.decode().strip()}")
    try:
        yield disk
    finally:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True, check=False)


def test_a_full_disk_stops_a_networked_run_with_the_lock_steps_line_and_one_round(
    tmp_path: Path, small_disk: Path
) -> None:
    run = ["-n", "8", "--seed", "3", "--scheduler", "ssync"]
    cut = small_disk / "cut.jsonl"
    stopped = _fatswarm(*run, "--record", str(cut), "--no-dashboard")
    assert stopped.returncode == 4, stopped.stdout + stopped.stderr
    assert "Traceback" not in stopped.stderr
    kept = read_record(cut, allow_torn_end=True)
    assert kept.result is None and len(kept.rounds) > 0
    done = len(kept.rounds)
    last = stopped.stderr.rstrip("\n").splitlines()[-1]
    assert last == (
        f"fatswarm run: the run stopped after round {done}; once that is fixed, go on with "
        f"`fatswarm run --record {cut} --resume`"
    ), stopped.stderr
    # the lock step's words (one definition of them), the networked run's command
    from fatswarm.deploy.view.stopped import stopped_line

    assert last.endswith(
        stopped_line("stopped", done, record=str(cut), scheduler="ssync", fix=True)
    )
    world = [line for line in stopped.stderr.splitlines() if line.startswith("fatswarm world:")]
    assert len(world) == 1 and "No space left on device" in world[0], stopped.stderr
    assert f"the world stops after round {done}, the last its record holds" in world[0]
    coordinator = [line for line in stopped.stderr.splitlines() if "coordinator" in line]
    assert all(f"round {done + 1}" in line for line in coordinator), coordinator  # the one lost
    moved = tmp_path / "cut.jsonl"  # freed: the record moves where there is room
    moved.write_bytes(cut.read_bytes())
    resumed = _fatswarm("--record", str(moved), "--resume", "--no-dashboard")
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    whole = tmp_path / "whole.jsonl"
    assert _fatswarm(*run, "--lockstep", "--record", str(whole)).returncode == 0
    assert_same_run(read_record(moved), read_record(whole))
