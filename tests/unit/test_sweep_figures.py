"""`fatswarm sweep --plot` leaves the ratio figure out, saying why, when runs formed but none has
the distance's bound (scipy missing): not an empty figure claiming "no formed run"."""

from __future__ import annotations

from pathlib import Path

import pytest

from fatswarm.deploy.sweep import figures
from fatswarm.deploy.sweep.summary import Cell

pytest.importorskip("matplotlib")


def cell(formed: int, ratio: tuple[float, float, float] | None) -> Cell:
    rounds = (5.0, 6.0, 7.0) if formed else None
    return Cell(
        "uniform-circle", "clustered", "fsync", 4, 3, formed, formed, 0, 0, 0, 0, rounds, ratio
    )


def test_no_bound_for_formed_runs_leaves_the_ratio_figure_out_and_says_why(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(figures, "has_scipy", lambda: False)
    written = figures.draw_figures([cell(3, None)], str(tmp_path))
    assert [Path(p).name for p in written] == ["success.png", "rounds.png"]
    assert not (tmp_path / "ratio.png").exists()
    err = capsys.readouterr().err
    assert err.startswith("fatswarm sweep: no ratio.png: the distance's bound needs scipy")
    assert err.count("\n") == 1


def test_a_ratio_or_no_formed_run_draws_every_figure(tmp_path: Path) -> None:
    assert figures.no_ratio_reason([cell(3, (1.0, 1.1, 1.2))]) is None
    assert figures.no_ratio_reason([cell(0, None)]) is None  # the figure says "no formed run"
    written = figures.draw_figures([cell(3, (1.0, 1.1, 1.2))], str(tmp_path))
    assert [Path(p).name for p in written] == list(figures.FIGURES)
