"""A sweep table of an earlier schema (before the non_rigid, crash and time columns) resumes with
its new columns blank: the sweep runs the rest on worker processes, so the test is an integration
one (tests/unit/test_sweep.py has the table's other tests)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.sweep.table import (
    PLAIN_COLUMNS,
    PRE_MODEL_COLUMNS,
    format_line,
    header_line,
    parse_table,
)

pytestmark = pytest.mark.integration


def sweep(argv: list[str]) -> int:
    return cli.main(["sweep", *argv])


EARLIER_ROW = (
    "uniform-circle,4,clustered,fsync,0,,,formed,6,6,24,5,0,4.798929,4.389946,1.093164,0.081,"
    "a=4.0,140,,,0.1.0,fatswarm run --lockstep -n 4 --seed 0 --start clustered --scheduler fsync\n"
)


def test_a_table_of_the_earlier_schema_resumes_with_its_new_columns_blank(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "runs.csv"
    out.write_text(format_line(PRE_MODEL_COLUMNS) + EARLIER_ROW)
    assert sweep(["-n", "4", "--seeds", "1", "--scheduler", "fsync,ssync", "--out", str(out)]) == 0
    assert "1 run" in capsys.readouterr().err  # the fsync run was in the table: one to go
    lines = out.read_text().splitlines(keepends=True)
    assert lines[0] == header_line(PLAIN_COLUMNS) and len(lines) == 3
    (kept, _) = parse_table("".join(lines), "t.csv")
    earlier = dict(zip(PRE_MODEL_COLUMNS, next(csv.reader([EARLIER_ROW])), strict=True))
    assert {c: kept[c] for c in PRE_MODEL_COLUMNS} == earlier
    assert all(kept[c] == "" for c in PLAIN_COLUMNS if c not in PRE_MODEL_COLUMNS)
