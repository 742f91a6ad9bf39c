"""The executor seam's pure parts: how many runs a task holds (`Batcher`), and `--cluster`
without dask installed (one line naming the extra, exit 2)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.sweep import executor
from fatswarm.deploy.sweep.executor import MISSING_DASK, TASK_S, Batcher


def test_a_task_holds_one_run_until_a_run_is_timed() -> None:
    assert Batcher(slots=2).size(left=1000) == 1


def test_a_task_holds_about_a_second_of_runs() -> None:
    batcher = Batcher(slots=2)
    for _ in range(4):
        batcher.observe(0.01)
    assert batcher.size(left=100_000) == round(TASK_S / 0.01)


def test_the_last_runs_are_shared_so_that_every_slot_stays_busy() -> None:
    batcher = Batcher(slots=2)
    batcher.observe(0.001)
    assert batcher.size(left=40) == 10  # 40 runs over 2 slots, 2 tasks each
    assert batcher.size(left=3) == 1


def test_a_slow_run_goes_alone() -> None:
    batcher = Batcher(slots=8)
    batcher.observe(5.0)
    assert batcher.size(left=1000) == 1


@pytest.mark.parametrize("command", ["sweep", "hunt"])
def test_cluster_without_dask_is_one_line_naming_the_extra(
    command: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    out = tmp_path / ("runs.csv" if command == "sweep" else "found")
    argv = ["-n", "4", "--cluster", "tcp://127.0.0.1:8786", "--out", str(out), "-q"]
    argv += ["--seeds", "1"] if command == "sweep" else ["--budget-runs", "1"]
    assert cli.main([command, *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"fatswarm {command}: {MISSING_DASK}"]
    assert "pip install 'fatswarm[cluster]'" in MISSING_DASK
    assert executor.CONNECT_S <= 10
