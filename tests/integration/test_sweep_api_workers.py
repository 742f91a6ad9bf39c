"""`fatswarm.sweep(...)` on worker processes: the rows and columns of `fatswarm sweep`'s CSV on the
same grid (as pandas reads it), resumed from `out`; a sweep in which every run fails exits 1 with
one line. (On a Dask cluster: tests/integration/test_cluster.py.)"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

import fatswarm
from fatswarm.deploy import cli

pd: Any = pytest.importorskip("pandas")

pytestmark = pytest.mark.integration
VOLATILE = ["wall_s"]  # the only cells that differ between two runs of one configuration
# a small grid with a model axis (the model columns) and an async scheduler (the time column)
ARGV = ["-n", "4,5", "--scheduler", "fsync,async", "--seeds", "2", "--sight", "6,unlimited"]
KEYWORDS: dict[str, Any] = dict(
    n=[4, 5], scheduler=["fsync", "async"], seeds=2, sight=[6, None], jobs=1
)


def test_a_python_sweep_gives_the_rows_and_columns_of_the_clis_csv(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    assert cli.main(["sweep", *ARGV, "--jobs", "1", "-q", "--out", str(out)]) == 0
    from_cli = pd.read_csv(out)
    from_api = fatswarm.sweep(**KEYWORDS)
    assert list(from_api.columns) == list(from_cli.columns)
    assert len(from_api) == len(from_cli) == 16
    pd.testing.assert_frame_equal(from_api.drop(columns=VOLATILE), from_cli.drop(columns=VOLATILE))
    assert from_api.sight.fillna(0).tolist()[:4] == [6.0, 6.0, 0, 0]  # the model's column


def test_a_python_sweep_resumes_from_its_out_and_runs_only_what_it_lacks(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    first = fatswarm.sweep(n=4, scheduler="fsync", seeds=[0, 1], jobs=1, out=out)
    wider = fatswarm.sweep(n=4, scheduler="fsync", seeds=3, jobs=1, out=out)
    assert first.seed.tolist() == [0, 1] and wider.seed.tolist() == [0, 1, 2]
    pd.testing.assert_frame_equal(wider.iloc[:2], first)  # read back, not run again
    assert len(pd.read_csv(out)) == 3


def test_a_sweep_in_which_every_run_fails_exits_1_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "runs.csv"
    # a = 20000 is refused for 4 robots only once the start is drawn (in the worker)
    argv = ["-n", "4", "--scheduler", "fsync", "--seeds", "2", "--param", "a=20000", "-q"]
    assert cli.main(["sweep", *argv, "--jobs", "1", "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(
        f"fatswarm sweep: every one of the 2 runs of the grid failed, none ran to an end "
        f"(status error in {out}); the first: UnsupportedInputError: "
    )
    assert not [line for line in err if line.startswith("  fatswarm run")]  # no list of commands
    assert cli.main(["sweep", *argv, "--jobs", "1", "--out", str(out)]) == 1  # resumed: the same
