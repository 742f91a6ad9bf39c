"""`fatswarm plot`: trajectories to scale, a one-line message and exit 2 without matplotlib."""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
from dataclasses import replace

import pytest

from fatswarm.deploy.view.plot import (
    MISSING_MATPLOTLIB,
    add_arguments,
    default_title,
    final_positions,
    main,
    trajectories,
)
from fatswarm.world.record import Header
from fatswarm.world.record_read import read_record

RECORD = pathlib.Path(__file__).resolve().parents[1] / "data" / "replay-small.jsonl"


def run_plot(*argv: object) -> int:
    p = argparse.ArgumentParser()
    add_arguments(p)
    return main(p.parse_args([str(a) for a in argv]))


def test_each_route_runs_from_the_start_to_the_end_position() -> None:
    record = read_record(RECORD)
    routes = trajectories(record)
    end = final_positions(record)
    assert len(routes) == record.header.n
    for i, route in enumerate(routes):
        assert route[0].tolist() == record.header.initial[i].tolist()
        assert route[-1].tolist() == pytest.approx(end[i].tolist())
    # robot 2 turned about the origin: its route keeps radius 3 and is finely sampled
    assert len(routes[2]) > 10
    assert [math.hypot(x, y) for x, y in routes[2]] == pytest.approx([3.0] * len(routes[2]))
    # robot 0 followed two segments through the corner (0, -2)
    assert [0.0, -2.0] in routes[0].tolist()


@pytest.mark.parametrize("suffix", [".svg", ".png"])
def test_plot_writes_the_picture(tmp_path: pathlib.Path, suffix: str) -> None:
    pytest.importorskip("matplotlib")
    out = tmp_path / f"run{suffix}"
    assert run_plot(RECORD, out) == 0
    data = out.read_bytes()
    assert data.startswith(b"\x89PNG") if suffix == ".png" else b"<svg" in data[:2000]


def test_missing_matplotlib_says_how_to_install_and_exits_2(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # makes `import matplotlib` fail
    assert run_plot(RECORD, tmp_path / "x.svg") == 2
    err = capsys.readouterr().err
    assert err == MISSING_MATPLOTLIB + "\n" and "fatswarm[plot]" in err
    assert not (tmp_path / "x.svg").exists()


def test_unknown_picture_format_exits_2(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_plot(RECORD, tmp_path / "x.jpg") == 2
    assert "must end in .svg, .png, .gif or .mp4" in capsys.readouterr().err


def test_unreadable_record_exits_2(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_plot(tmp_path / "none.jsonl", tmp_path / "x.svg") == 2
    assert "none.jsonl" in capsys.readouterr().err


def test_a_header_with_an_unreadable_model_is_not_drawn(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = pathlib.Path(RECORD).read_text().splitlines()
    header = json.loads(lines[0])
    header["model"] = {"visibility": "foggy"}
    bad = tmp_path / "foggy.jsonl"
    bad.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    assert run_plot(bad, tmp_path / "x.svg") == 2
    err = capsys.readouterr().err
    assert "foggy.jsonl:1: unreadable robot 'model'" in err and err.count("\n") == 1
    assert not (tmp_path / "x.svg").exists()


def test_title_names_the_algorithm_and_its_parameters() -> None:
    record = read_record(RECORD)
    title = default_title(record, 3.0)
    assert title.startswith("uniform-circle a=4, n=4, scripted, seed 7: max_rounds after 3 rounds")
    header = record.header
    gathering = Header(
        header.n,
        header.seed,
        header.scheduler,
        header.initial,
        "gathering",
        {"tolerance": 0.5},
        "gathering",
    )
    other = default_title(replace(record, header=gathering), 3.0)
    assert other.startswith("gathering tolerance=0.5, n=4,") and "a=" not in other
