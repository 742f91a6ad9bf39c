"""The Python API in a notebook: what `fatswarm.run` and `fatswarm.read_record` hand back (one line
of text, a picture of the final frame, a DataFrame), positions at any time, plain summaries,
torn records and `dir(fatswarm)` (`python -m fatswarm` starts a process: its test is in
tests/integration/test_notebook_process.py)."""

from __future__ import annotations

import sys
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine import api, notebook
from fatswarm.deploy.engine.lockstep import RunResult as LockstepResult
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.domain.path import Line
from fatswarm.domain.path import Path as MovePath
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Configured
from fatswarm.world import timeline
from fatswarm.world.physics import Collision
from fatswarm.world.record import Header, Move, RecordFormatError, RoundEntry
from fatswarm.world.record import RunRecord as RecordLines

DATA = Path(__file__).resolve().parents[1] / "data"
LOCKSTEP = DATA / "lockstep-n6-seed1.jsonl"  # header, 17 rounds, result
SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory) -> tuple[notebook.RunResult, Path]:
    """One run of the API and the record it wrote."""
    path = tmp_path_factory.mktemp("notebook") / "run.jsonl"
    return fatswarm.run(6, seed=1, scheduler="ssync", record=path), path


def small_record() -> RecordLines:
    """Three robots, two rounds: robot 0 moves 2 and is stopped by contact with robot 1 in round
    1; robot 2 moves 1 in round 2."""
    start = np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
    after_1 = np.array([[2.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
    after_2 = np.array([[2.0, 0.0], [5.0, 0.0], [0.0, 6.0]])
    hit = Collision(robot=0, other=1, t=2.0, point=(2.0, 0.0))
    return RecordLines(
        Header(3, 7, "fsync", start),
        (
            RoundEntry(
                1, (0, 1, 2), (Move(0, MovePath((Line((4.0, 0.0)),)), 2.0),), after_1, (hit,)
            ),
            RoundEntry(2, (2,), (Move(2, MovePath((Line((0.0, 6.0)),)), 1.0),), after_2, ()),
        ),
        None,
    )


# --- what the API hands back ---------------------------------------------------------------------


def test_a_run_knows_the_run_it_was_and_is_still_the_lock_steps_result(
    made: tuple[notebook.RunResult, Path],
) -> None:
    result, path = made
    assert isinstance(result, LockstepResult)
    assert (result.n, result.seed, result.scheduler, result.algorithm) == (
        6,
        1,
        "ssync",
        "uniform-circle",
    )
    assert result.params == {"a": 4.0} and result.record == str(path)


def test_a_result_and_a_record_show_as_one_short_line_without_arrays(
    made: tuple[notebook.RunResult, Path],
) -> None:
    result, path = made
    record = fatswarm.read_record(path)
    for shown in (repr(result), repr(record), str(result)):
        assert "\n" not in shown and "array" not in shown, shown
        assert len(shown.replace(str(path), "")) < 175, shown  # one line, model named
    assert repr(result).startswith("RunResult(status='formed', rounds=17, n=6, seed=1, ")
    assert "algorithm='uniform-circle', model='paper', " in repr(result)
    assert repr(record) == (
        f"RunRecord(path={str(path)!r}, n=6, algorithm='uniform-circle', scheduler='ssync', "
        "seed=1, rounds=17, status='formed')"
    )


def picture(svg: str) -> ET.Element:
    return ET.fromstring(svg)  # our own drawing


def test_jupyter_draws_the_final_frame_of_a_result_and_of_its_record(
    made: tuple[notebook.RunResult, Path],
) -> None:
    result, path = made
    record = fatswarm.read_record(path)
    for shown in (result._repr_svg_(), record._repr_svg_()):
        root = picture(shown)
        discs = [c for c in root.iter(f"{SVG}circle") if c.get("fill") == notebook.END_FILL]
        assert len(discs) == 6
        texts = [t.text for t in root.iter(f"{SVG}text")]
        assert texts[:6] == [str(i) for i in range(6)]  # the robots, numbered
        assert texts[6:] == [
            "formed in 17 rounds, collision-free",
            "n=6 ssync seed 1",
            "robot model: paper's",
        ]
    assert result._repr_svg_() == record._repr_svg_()


def test_the_picture_is_to_scale_with_the_world_y_axis_up() -> None:
    start = np.array([[0.0, 0.0], [10.0, 0.0]])
    end = np.array([[0.0, 0.0], [0.0, 10.0]])
    root = picture(notebook.frame_svg(start, end, ("a", "b")))
    ends = [c for c in root.iter(f"{SVG}circle") if c.get("fill") == notebook.END_FILL]
    (x0, y0), (x1, y1) = ((float(c.get("cx", "")), float(c.get("cy", ""))) for c in ends)
    assert x0 == pytest.approx(x1) and y1 == pytest.approx(y0 - 10.0)  # +Y is up the picture
    assert float(ends[0].get("r", "")) == 1.0  # unit discs, in world units


def test_discs_of_a_huge_circle_are_enlarged_to_be_seen() -> None:
    angles = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
    end = 1e4 * np.column_stack([np.cos(angles), np.sin(angles)])
    root = picture(notebook.frame_svg(end, end, ("a", "b")))
    disc = next(c for c in root.iter(f"{SVG}circle") if c.get("fill") == notebook.END_FILL)
    inner = next(e for e in root.iter(f"{SVG}svg") if e is not root)
    px = (
        float(disc.get("r", "0")) / float(inner.get("viewBox", "").split()[2]) * notebook.PICTURE_PX
    )
    assert px == pytest.approx(notebook.MIN_DISC_PX, rel=1e-4)  # a unit disc would be 0.02 pixels


def test_the_caption_says_how_a_run_ended() -> None:
    assert notebook.outcome_text("formed", 1, 0) == "formed in 1 round, collision-free"
    assert notebook.outcome_text("formed", 9, 2) == "formed in 9 rounds, with 2 collisions"
    assert notebook.outcome_text("stalled", 3, 1) == "stalled after 3 rounds, with 1 collision"
    assert notebook.outcome_text("max_rounds", 40, 0) == "stopped at the round cap (40 rounds)"
    assert notebook.outcome_text("unfinished", 2, 0) == "unfinished after 2 rounds"


# --- positions at any time -----------------------------------------------------------------------


def test_positions_at_is_the_timelines_and_places_robots_within_a_round() -> None:
    record = small_record()
    assert np.array_equal(fatswarm.positions_at(record, 1.5), timeline.positions_at(record, 1.5))
    assert np.array_equal(fatswarm.positions_at(record, 1.0), record.rounds[0].positions)
    half = fatswarm.positions_at(record, 0.5)  # robot 0 half-way through its move of 2
    assert half[0] == pytest.approx([1.0, 0.0]) and half[2] == pytest.approx([0.0, 5.0])


# --- DataFrames ----------------------------------------------------------------------------------


def test_the_dataframe_has_one_row_per_robot_per_round() -> None:
    pd = pytest.importorskip("pandas")
    df = notebook.RunRecord.of(small_record(), None).to_dataframe()
    assert isinstance(df, pd.DataFrame)
    assert (
        list(df.columns)
        == list(notebook.columns())
        == [
            "round",
            "robot",
            "x",
            "y",
            "active",
            "moved",
            "distance",
            "collided",
            "min_gap",  # the round's, derived from the positions (fatswarm.domain.figures)
            "failures",  # the round's failed computes, from its line's `failed`
            "failed",  # why the robot's compute failed in the round (None: it did not)
        ]
    )
    assert df[["round", "robot"]].values.tolist() == [
        [1, 0],
        [1, 1],
        [1, 2],
        [2, 0],
        [2, 1],
        [2, 2],
    ]
    assert df.x.tolist() == [2.0, 5.0, 0.0, 2.0, 5.0, 0.0]
    assert df.y.tolist() == [0.0, 0.0, 5.0, 0.0, 0.0, 6.0]
    assert df.active.tolist() == [True, True, True, False, False, True]
    assert df.moved.tolist() == [True, False, False, False, False, True]
    assert df.distance.tolist() == [2.0, 0.0, 0.0, 0.0, 0.0, 1.0]
    assert df.collided.tolist() == [True, False, False, False, False, False]
    assert [str(t) for t in df.dtypes] == ["int64"] * 2 + ["float64"] * 2 + ["bool"] * 2 + [
        "float64",
        "bool",
        "float64",
        "int64",
        "object",
    ]


def test_the_dataframe_of_a_read_record_adds_up_to_its_figures() -> None:
    pytest.importorskip("pandas")
    record = fatswarm.read_record(LOCKSTEP)
    df = record.to_dataframe()
    assert len(df) == 6 * 17 and df["round"].max() == 17
    assert df.distance.sum() == pytest.approx(record.result.total_distance)  # type: ignore[union-attr]
    assert int(df.moved.sum()) == record.result.moves  # type: ignore[union-attr]
    last = df[df["round"] == 17][["x", "y"]].to_numpy()
    assert np.array_equal(last, record.rounds[-1].positions)


def test_without_pandas_the_dataframe_says_what_to_install_in_one_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    with pytest.raises(ImportError) as caught:
        notebook.RunRecord.of(small_record(), None).to_dataframe()
    assert str(caught.value) == (
        "RunRecord.to_dataframe needs pandas: pip install 'fatswarm[notebook]'"
    )


# --- summaries -----------------------------------------------------------------------------------


def test_a_summary_is_plain_values_for_a_result_and_for_its_record(
    made: tuple[notebook.RunResult, Path],
) -> None:
    result, path = made
    of_result = fatswarm.summary(result)
    of_record = fatswarm.summary(fatswarm.read_record(path))
    assert type(of_result["status"]) is str and of_result["status"] == "formed"
    assert all(v is None or type(v) in (str, int, float) for v in of_result.values())
    assert of_record.keys() == of_result.keys()
    assert of_record.pop("total_distance") == pytest.approx(of_result.pop("total_distance"))
    assert of_record == of_result
    assert of_result["n"] == 6 and of_result["seed"] == 1 and of_result["scheduler"] == "ssync"


def test_a_summary_of_an_unfinished_record_counts_its_lines() -> None:
    figures = fatswarm.summary(small_record())
    assert figures["status"] == "unfinished" and figures["rounds"] == 2
    assert (figures["moves"], figures["collisions"], figures["looks"]) == (2, 1, 4)
    assert figures["total_distance"] == 3.0 and figures["epochs"] is None


def test_a_summary_of_the_lock_steps_own_result_leaves_the_unknown_empty() -> None:
    setting = Configured.of(load_algorithm("uniform-circle"), 3, {})
    start = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    result = run_lockstep(start, setting, make_scheduler("fsync", 3, 0, None, None), seed=0)
    figures = fatswarm.summary(result)
    assert figures["n"] == 3 and figures["seed"] is None and type(figures["status"]) is str
    with pytest.raises(TypeError, match="summary takes a RunResult or a RunRecord, got dict"):
        fatswarm.summary(figures)  # type: ignore[arg-type]


# --- torn records --------------------------------------------------------------------------------


def test_a_torn_record_is_read_with_the_note_replay_gives(tmp_path: Path) -> None:
    lines = LOCKSTEP.read_bytes().splitlines(keepends=True)
    torn = tmp_path / "torn.jsonl"
    torn.write_bytes(b"".join(lines[:-1]) + lines[-1][: len(lines[-1]) // 2])
    with pytest.warns(api.TornRecordWarning) as caught:
        record = fatswarm.read_record(torn)
    assert [str(w.message) for w in caught] == [
        f"{torn} ends with a torn line (line {len(lines)}, a crash mid-write); showing the 17 "
        "complete rounds"
    ]
    assert len(record.rounds) == 17 and record.status == "unfinished"
    assert record.torn_line == len(lines) and "torn_line=" in repr(record)
    with pytest.raises(RecordFormatError, match=rf"torn.jsonl:{len(lines)}: not JSON"):
        fatswarm.read_record(torn, allow_torn_end=False)


def test_a_whole_record_is_read_without_a_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert fatswarm.read_record(LOCKSTEP).torn_line is None


# --- the package ---------------------------------------------------------------------------------


def test_dir_lists_the_lazy_api_and_no_private_import() -> None:
    names = dir(fatswarm)
    for name in ("run", "read_record", "positions_at", "summary", "trajectory", "RunResult"):
        assert name in names and callable(getattr(fatswarm, name))
    assert not {"import_module", "version", "Any", "PackageNotFoundError"} & set(names)
