"""What the model adds to the notebook's data and pictures: each robot's light, failed compute and
view in `to_dataframe`, the run's settings in `df.attrs`, a luminous run drawn in its colours with
its model named ("cycle" under async), and `positions_at`/`trajectory` of a path, a record or a
result, the end time taken as the summary prints it."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy.engine import api, notebook
from fatswarm.deploy.view.lights import light_hex
from fatswarm.deploy.view.lights import record_palette as pictures_palette
from fatswarm.domain.robot_model import AXES, AXIS_NAMES
from fatswarm.world.setup import WorldSetup

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def lit(tmp_path_factory: pytest.TempPathFactory) -> tuple[notebook.RunResult, Path]:
    """A luminous async run with limited sight, its views recorded, and its record."""
    path = tmp_path_factory.mktemp("lit") / "lit.jsonl"
    result = fatswarm.run(
        5,
        seed=1,
        algorithm="uniform-circle-lights",
        scheduler="async",
        sight=8.0,
        record_views=True,
        record=path,
    )
    return result, path


@pytest.fixture(scope="module")
def failing(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run whose computes fail: the paper's algorithm needs every robot seen (opaque hides)."""
    path = tmp_path_factory.mktemp("failing") / "failing.jsonl"
    fatswarm.run(6, seed=3, visibility="opaque", max_rounds=40, record=path)
    return path


# --- the DataFrame -------------------------------------------------------------------------------


def test_a_luminous_run_with_views_adds_each_robots_light_and_view(
    lit: tuple[notebook.RunResult, Path],
) -> None:
    pytest.importorskip("pandas")
    record = fatswarm.read_record(lit[1])
    df = record.to_dataframe()
    assert list(df.columns) == list(notebook.columns(lights=True, views=True))
    assert list(df.columns[-3:]) == ["failed", "light", "view"]
    n = record.header.n
    for k, entry in enumerate(record.rounds[:20]):
        rows = df.iloc[k * n : (k + 1) * n]
        assert rows.light.tolist() == entry.extra["lights"]
        views = entry.extra["views"]
        assert rows.view.tolist() == [
            tuple(views[str(i)]) if str(i) in views else None for i in range(n)
        ]
    looked = df[df.view.notna()]
    assert (looked.active).all() and len(looked) == len(record.rounds)  # one Look a cycle
    exploded = looked.explode("view")  # one row per robot seen (tuples explode as lists do)
    assert len(exploded) == sum(max(1, len(v)) for v in looked.view)


def test_a_run_without_lights_or_views_has_neither_column() -> None:
    pytest.importorskip("pandas")
    df = fatswarm.read_record(Path(__file__).parents[1] / "data" / "lockstep-n6-seed1.jsonl")
    frame = df.to_dataframe()
    assert "light" not in frame.columns and "view" not in frame.columns
    assert frame.failed.isna().all()


def test_a_failed_compute_is_on_the_robots_row_and_adds_up_to_the_failures(
    failing: Path,
) -> None:
    pytest.importorskip("pandas")
    record = fatswarm.read_record(failing)
    df = record.to_dataframe()
    failed = df[df.failed.notna()]
    count = fatswarm.summary(record)["failures"]
    assert isinstance(count, int) and len(failed) == count > 0
    assert failed.failed.str.startswith("ViewError: ").all() and failed.active.all()
    for round_no, robot, text in zip(failed["round"], failed.robot, failed.failed, strict=True):
        assert record.rounds[round_no - 1].extra["failed"][str(robot)] == text
    assert (df.groupby("round").failed.count() == df.groupby("round").failures.first()).all()


def test_the_frame_carries_the_runs_settings_and_every_axis_of_its_model(
    lit: tuple[notebook.RunResult, Path],
) -> None:
    pytest.importorskip("pandas")
    result, path = lit
    attrs = fatswarm.read_record(path).to_dataframe().attrs
    assert (attrs["algorithm"], attrs["scheduler"], attrs["seed"], attrs["n"]) == (
        "uniform-circle-lights",
        "async",
        1,
        5,
    )
    assert attrs["params"] == result.params
    assert list(attrs["model"]) == list(AXIS_NAMES)
    assert attrs["model"]["sight"] == 8.0 and attrs["model"]["visibility"] == "transparent"
    assert attrs["record_views"] is True
    assert set(attrs) >= {f for f in WorldSetup.__dataclass_fields__} - {
        "initial",
        "extra",
        "robot_model",
    }


def test_a_new_axis_reaches_the_frames_model_with_no_other_edit(
    lit: tuple[notebook.RunResult, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    record = fatswarm.read_record(lit[1])
    monkeypatch.setattr(notebook, "AXES", AXES[:2])  # the declaration is iterated, not copied
    assert list(notebook.run_attrs(record)["model"]) == list(AXIS_NAMES[:2])


# --- the picture ---------------------------------------------------------------------------------


def fills(svg: str) -> list[str]:
    root = ET.fromstring(svg)
    return [
        c.get("fill", "")
        for c in root.iter(f"{SVG}circle")
        if c.get("fill") not in ("none", None) and c.get("stroke") == "black"
    ]


def texts(svg: str) -> list[str]:
    return ["".join(t.itertext()) for t in ET.fromstring(svg).iter(f"{SVG}text")]


def test_a_luminous_run_is_drawn_in_its_lights_colours_as_replay_and_plot_draw_them(
    lit: tuple[notebook.RunResult, Path],
) -> None:
    result, path = lit
    record = fatswarm.read_record(path)
    palette = pictures_palette(record)
    last = record.rounds[-1].extra["lights"]
    expected = [light_hex(palette, name) for name in last]
    assert fills(record._repr_svg_()) == expected == fills(result._repr_svg_())
    assert expected != [notebook.END_FILL] * len(expected)  # not every robot green
    assert result.palette == palette == notebook.record_palette(record)
    assert result._repr_svg_() == record._repr_svg_()
    legend = texts(record._repr_svg_())[-1]
    assert legend == "lights: " + ", ".join(f"\u25cf {name}" for name in palette)


def test_the_caption_counts_cycles_under_async_and_names_the_model(
    lit: tuple[notebook.RunResult, Path],
) -> None:
    result, _ = lit
    caption = texts(result._repr_svg_())[-4:]
    assert caption[0] == f"formed in {result.rounds} cycles, collision-free"
    assert caption[1:3] == ["n=5 async seed 1", "robot model: --sight 8.0"]
    assert notebook.outcome_text("max_rounds", 9, 0, cycles=True) == (
        "stopped at the cycle cap (9 cycles)"
    )


# --- positions_at and trajectory -----------------------------------------------------------------


def test_positions_at_and_trajectory_take_a_path_a_record_or_a_result(
    lit: tuple[notebook.RunResult, Path],
) -> None:
    result, path = lit
    record = fatswarm.read_record(path)
    t = result.time / 2  # type: ignore[operator]
    at = fatswarm.positions_at(record, t)
    for of in (str(path), path, result):
        assert np.array_equal(fatswarm.positions_at(of, t), at)
        assert np.array_equal(fatswarm.trajectory(of), fatswarm.trajectory(record))
        assert np.array_equal(fatswarm.moved_by_round(of), fatswarm.moved_by_round(record))


def test_a_result_without_a_record_or_another_object_is_refused_in_one_line() -> None:
    result = fatswarm.run(3, seed=0)
    with pytest.raises(api.RunArgumentError, match=r"^positions_at needs the run's rounds.*"):
        fatswarm.positions_at(result, 1.0)
    with pytest.raises(api.RunArgumentError) as info:
        fatswarm.trajectory(42)  # type: ignore[arg-type]
    assert str(info.value) == (
        "trajectory takes a record, its path (str or os.PathLike) or a fatswarm.run result, got int"
    )


def test_the_end_time_as_the_summary_prints_it_is_the_end(
    lit: tuple[notebook.RunResult, Path],
) -> None:
    result, path = lit
    end = result.time
    assert end is not None
    printed = float(f"{end:.3f}")
    record = fatswarm.read_record(path)
    assert np.array_equal(fatswarm.positions_at(record, printed), result.positions)
    assert np.array_equal(fatswarm.positions_at(record, end), result.positions)
    with pytest.raises(ValueError) as info:
        fatswarm.positions_at(record, end + 0.01)
    message = str(info.value)
    assert message.startswith(f"t must be between 0 and the run's end, {end!r} (virtual time; ")
    assert f"as printed, {end:.3f}" in message and "\n" not in message
    with pytest.raises(ValueError, match=re.escape("got -1")):
        fatswarm.positions_at(record, -1)
