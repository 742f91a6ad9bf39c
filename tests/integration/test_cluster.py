"""`fatswarm sweep` and `fatswarm hunt --cluster` on a real Dask LocalCluster (two worker
processes on loopback, started and closed here): the same CSV rows (less the wall time) and the
same hunt folders as a local run of one worker (that two local workers give those of one is
pinned by test_sweep_models_workers.py and test_hunt_workers.py); an unreachable address is one
line."""

from __future__ import annotations

import csv
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.sweep import executor

distributed: Any = pytest.importorskip("distributed")

pytestmark = pytest.mark.integration
ROOT = Path(__file__).resolve().parents[2]
PLANTED = f"{ROOT / 'tests' / 'data' / 'always_right.py'}:ALGORITHM"
VOLATILE = {"wall_s"}
SWEEP = ["-n", "4,5,6", "--scheduler", "fsync,ssync", "--seeds", "2", "-q"]  # 12 runs
HUNT = [
    "--algorithm",
    PLANTED,
    "--scheduler",
    "fsync,ssync,centralized",
    "-n",
    "3..6",
    "--budget-runs",
    "40",
    "--max-failures",
    "2",
    "--seed",
    "3",
    "-q",
]


@pytest.fixture(scope="module")
def scheduler() -> Iterator[str]:
    """The address of a LocalCluster of two single-threaded worker processes on loopback."""
    cluster = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=":0",  # a free port: None means the default 8787, maybe taken
    )
    try:
        yield str(cluster.scheduler_address)
    finally:
        cluster.close()


def rows_of(path: Path) -> set[tuple[str, ...]]:
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {tuple(v for k, v in row.items() if k not in VOLATILE) for row in rows}


def folders_of(out: Path) -> dict[str, dict[str, str]]:
    """Every saved folder's files, with the --out path written as OUT."""
    return {
        folder.name: {
            f.name: f.read_text().replace(str(out), "OUT") for f in sorted(folder.iterdir())
        }
        for folder in sorted(out.iterdir())
    }


def test_a_sweep_on_a_cluster_writes_the_rows_of_a_local_worker(
    scheduler: str, tmp_path: Path
) -> None:
    tables = {}
    for where in (["--jobs", "1"], ["--cluster", scheduler]):
        out = tmp_path / f"{where[1].replace('/', '_').replace(':', '_')}.csv"
        assert cli.main(["sweep", *SWEEP, *where, "--out", str(out)]) == 0
        tables[where[0] + where[1]] = rows_of(out)
    local = tables["--jobs1"]
    assert len(local) == 12
    assert tables["--cluster" + scheduler] == local


def test_a_hunt_on_a_cluster_saves_the_folders_of_a_local_worker(
    scheduler: str, tmp_path: Path
) -> None:
    saved = {}
    for name, where in (("1", ["--jobs", "1"]), ("c", ["--cluster", scheduler])):
        out = tmp_path / f"hunt{name}"
        assert cli.main(["hunt", *HUNT, *where, "--out", str(out)]) == 1
        saved[name] = folders_of(out)
    assert len(saved["1"]) == 2
    assert saved["c"] == saved["1"]


def test_a_resumed_sweep_on_a_cluster_runs_only_what_the_table_lacks(
    scheduler: str, tmp_path: Path
) -> None:
    out = tmp_path / "runs.csv"
    first = ["-n", "4", "--scheduler", "fsync", "--seeds", "2", "-q", "--out", str(out)]
    assert cli.main(["sweep", *first, "--jobs", "1"]) == 0
    wider = ["-n", "4", "--scheduler", "fsync", "--seeds", "4", "-q", "--out", str(out)]
    assert cli.main(["sweep", *wider, "--cluster", scheduler]) == 0
    rows = rows_of(out)
    assert len(rows) == 4


def test_a_relative_algorithm_path_runs_on_workers_started_in_another_directory(
    scheduler: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    here = tmp_path / "here"  # not the workers' directory, which has no halfway.py
    here.mkdir()
    (here / "halfway.py").write_text((ROOT / "tests" / "data" / "always_right.py").read_text())
    monkeypatch.chdir(here)
    argv = ["-n", "3,4", "--scheduler", "fsync", "--seeds", "2", "-q", "--out", "runs.csv"]
    code = cli.main(["sweep", "--algorithm", "halfway.py:ALGORITHM", *argv, "--cluster", scheduler])
    with (here / "runs.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4 and code == 0
    assert {row["status"] for row in rows} != {"error"}, rows[0]["error"]
    assert {row["algorithm"] for row in rows} == {"halfway.py:ALGORITHM"}  # as typed


def test_a_python_sweep_on_a_client_gives_the_rows_of_the_cli_and_leaves_it_open(
    scheduler: str, tmp_path: Path
) -> None:
    pd = pytest.importorskip("pandas")
    import fatswarm

    out = tmp_path / "runs.csv"
    assert cli.main(["sweep", *SWEEP, "--jobs", "1", "--out", str(out)]) == 0
    with distributed.Client(scheduler, set_as_default=False) as client:
        frame = fatswarm.sweep(n=[4, 5, 6], scheduler=["fsync", "ssync"], seeds=2, cluster=client)
        assert client.status == "running"
    pd.testing.assert_frame_equal(
        frame.drop(columns=list(VOLATILE)), pd.read_csv(out).drop(columns=list(VOLATILE))
    )


def test_an_unreachable_cluster_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(executor, "CONNECT_S", 0.2)  # nothing listens: refused however long
    address = "tcp://127.0.0.1:9"  # the discard port: nothing listens there
    out = tmp_path / "runs.csv"
    code = cli.main(["sweep", "-n", "4", "--seeds", "1", "--cluster", address, "--out", str(out)])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"fatswarm sweep: --cluster {address}: no Dask scheduler answered")
    code = cli.main(
        ["hunt", "--budget-runs", "2", "--cluster", address, "--out", str(tmp_path / "h")]
    )
    assert code == 2
    assert "no Dask scheduler answered" in capsys.readouterr().err
