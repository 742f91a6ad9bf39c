"""`fatswarm.sweep(...)` without a worker: its keywords are the CLI's flags (refusals in the
keywords' words), a grid already in `out` is read back, not run; the runs travel with an
algorithm file's absolute path and come back as typed; a grid whose every run failed exits 1.
Sweeps on worker processes: tests/integration/test_sweep_api_workers.py."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest

import fatswarm
from fatswarm.deploy import cli
from fatswarm.deploy.sweep import api
from fatswarm.deploy.sweep.command import Shipped, all_failed_text
from fatswarm.deploy.sweep.executor import absolute_ref
from fatswarm.deploy.sweep.grid import RunSpec, SweepInputError
from fatswarm.deploy.sweep.pool import run_spec
from fatswarm.deploy.sweep.table import ERROR, PLAIN_COLUMNS, header_line, make_row, row_line
from fatswarm.domain.robot_model import AXIS_NAMES
from fatswarm.domain.version import __version__


def test_sweep_is_the_apis_and_its_keywords_are_the_flags_and_the_axes() -> None:
    assert fatswarm.sweep is api.sweep and "sweep" in dir(fatswarm)
    assert set(AXIS_NAMES) <= api.KEYWORDS
    assert {"n", "seeds", "scheduler", "non_rigid", "crash", "cluster", "out"} <= api.KEYWORDS


@pytest.mark.parametrize(
    ("keywords", "error", "message"),
    [
        ({"n": [0]}, SweepInputError, "n values must be >= 1, got 0"),
        ({"seeds": "x"}, SweepInputError, "seeds takes whole numbers"),
        ({"scheduler": "warp"}, SweepInputError, "scheduler='warp' is not a scheduler"),
        ({"sight": [-1]}, SweepInputError, "sight takes distances > 0"),
        ({"max_rounds": 0}, SweepInputError, "max_rounds must be at least 1, got 0"),
        ({"max_rounds": "3"}, api.SweepArgumentError, "max_rounds must be an int or None"),
        ({"non_rigid": [object()]}, api.SweepArgumentError, "non_rigid takes a value or a list"),
        ({"warp": 1}, api.SweepArgumentError, "unexpected keyword argument 'warp'"),
        ({"params": {"b": 1}}, ValueError, "has no parameter 'b'"),
    ],
)
def test_what_the_cli_refuses_is_refused_in_the_keywords_words(
    keywords: dict[str, Any], error: type[Exception], message: str
) -> None:
    pytest.importorskip("pandas")
    with pytest.raises(error) as info:
        fatswarm.sweep(**keywords)
    assert message in str(info.value) and "--" not in str(info.value)
    assert "\n" not in str(info.value)


def test_a_grid_already_in_out_is_read_back_without_a_worker(tmp_path: Path) -> None:
    pd = pytest.importorskip("pandas")
    specs = [RunSpec("uniform-circle", 3, "clustered", "fsync", seed) for seed in (0, 1)]
    out = tmp_path / "runs.csv"
    rows = [make_row(spec, run_spec(spec), __version__) for spec in specs]
    out.write_text(header_line(PLAIN_COLUMNS) + "".join(row_line(r, PLAIN_COLUMNS) for r in rows))
    frame = fatswarm.sweep(n=3, scheduler="fsync", seeds=2, out=out)  # no process is started
    pd.testing.assert_frame_equal(frame, pd.read_csv(out))
    assert frame.seed.tolist() == [0, 1] and list(frame.columns) == list(PLAIN_COLUMNS)


def test_the_runs_travel_with_an_absolute_file_path_and_come_back_as_typed() -> None:
    given = [
        RunSpec("halfway.py:ALGORITHM", 4, "clustered", "fsync", 0),
        RunSpec(os.path.abspath("halfway.py") + ":ALGORITHM", 4, "clustered", "fsync", 0),
        RunSpec("gathering", 4, "clustered", "fsync", 0),
    ]
    shipped = Shipped(given)
    assert [s.algorithm for s in shipped.runs] == [
        os.path.abspath("halfway.py") + ":ALGORITHM",
        os.path.abspath("halfway.py") + ":ALGORITHM",
        "gathering",
    ]
    assert [shipped.given(sent) for sent in shipped.runs] == given  # two rows, each once
    assert absolute_ref("pkg.module:ALGORITHM") == "pkg.module:ALGORITHM"


def test_a_grid_whose_every_run_failed_exits_1_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a = 20000 is refused for 4 robots once the start is drawn: every run of the grid raises
    specs = [
        RunSpec("uniform-circle", 4, "clustered", "fsync", seed, (("a", "20000.0"),))
        for seed in (0, 1)
    ]
    rows = [make_row(spec, run_spec(spec), __version__) for spec in specs]
    assert {row["status"] for row in rows} == {ERROR}
    out = tmp_path / "runs.csv"
    out.write_text(header_line(PLAIN_COLUMNS) + "".join(row_line(r, PLAIN_COLUMNS) for r in rows))
    argv = ["sweep", "-n", "4", "--scheduler", "fsync", "--seeds", "2", "--param", "a=20000"]
    assert cli.main([*argv, "-q", "--out", str(out)]) == 1  # all in the table: nothing runs
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [all_failed_text(rows, str(out))]
    assert err[0].startswith("fatswarm sweep: every one of the 2 runs of the grid failed")
    assert rows[0]["error"] in err[0]
