"""min_gap as a sweep column: an older table (written before min_gap) resumes with it blank (a
sweep runs its worker processes, so the test is an integration one; tests/unit/test_min_gap.py has
the rest)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.sweep import table
from fatswarm.deploy.sweep.pool import RunTable

pytestmark = pytest.mark.integration

# a sweep table of the fatswarm before min_gap (its header and a row, as it wrote them)
BEFORE_MIN_GAP = (
    "algorithm,n,start,scheduler,seed,params,max_rounds,non_rigid,crash,status,rounds,time,epochs,"
    "looks,moves,collisions,total_distance,bound,ratio,wall_s,values,round_cap,error,warning,"
    "fatswarm_version,command\n"
    "uniform-circle,4,clustered,fsync,0,,,,,formed,6,,6,24,5,0,4.798929,4.389946,1.093164,0.081,"
    "a=4.0,140,,,0.1.0,fatswarm run --lockstep -n 4 --seed 0 --start clustered --scheduler fsync\n"
)


def test_min_gap_is_a_sweep_column_and_an_older_table_resumes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "runs.csv"
    out.write_text(BEFORE_MIN_GAP)
    argv = ["sweep", "-n", "4", "--seeds", "1", "--scheduler", "fsync,ssync", "--out", str(out)]
    assert cli.main(argv) == 0
    assert "1 run" in capsys.readouterr().err  # the fsync run was there: one to go
    table_ = RunTable.open(str(out))
    try:
        old, new = table_.rows
    finally:
        table_.close()
    assert "min_gap" in table.plain_columns() and out.read_text().startswith(
        table.header_line(table.plain_columns())
    )
    assert old["min_gap"] == "" and old["rounds"] == "6"  # not measured then
    assert float(new["min_gap"]) >= 0.0  # a collision-free ssync run
