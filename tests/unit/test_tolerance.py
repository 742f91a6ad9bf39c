"""The supported input range (fatswarm/domain/tolerance.py): the start's smallest enclosing circle,
not its bounding box; the whole run's reach inside the coordinate range; numbers past a limit
shown with the digits that tell them from it."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fatswarm.agent.geometry import sec
from fatswarm.deploy import cli
from fatswarm.domain.tolerance import (
    MAX_COORD,
    MAX_SPAN,
    UnsupportedInputError,
    check_supported,
    enclosing_circle,
    shown_apart,
    shown_beyond,
    target_radius_of,
)

pytestmark = pytest.mark.usefixtures("no_launch")  # tests/unit/conftest.py


def ring(n: int, radius: float, centre: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    angle = 2.0 * math.pi * np.arange(n) / n
    return np.column_stack([centre[0] + radius * np.cos(angle), centre[1] + radius * np.sin(angle)])


def test_the_enclosing_circle_is_the_algorithms_sec() -> None:
    rng = np.random.default_rng(7)
    for k in range(200):
        n = int(rng.integers(1, 40))
        points = rng.normal(size=(n, 2)) * rng.uniform(0.5, 1e3) + rng.uniform(-1e6, 1e6, 2)
        if k % 4 == 0:
            points[:, 1] = points[0, 1]  # collinear
        cx, cy, radius = enclosing_circle(points)
        expected = sec(points)
        assert radius == pytest.approx(expected.radius, rel=1e-9, abs=1e-6)
        assert (cx, cy) == pytest.approx(expected.center, rel=1e-9, abs=1e-6)


@pytest.mark.parametrize(
    "start",
    [
        ring(40, 7100.0),  # its bounding box's half diagonal is about 10040.9
        ring(10, MAX_SPAN),  # a formed 10-gon of radius 1e4 (about 13800.4 by the box)
    ],
    ids=["ring-7100", "formed-10-gon-1e4"],
)
def test_a_start_is_judged_by_its_smallest_enclosing_circle(start: np.ndarray) -> None:
    check_supported(start, 4.0)


def test_a_start_just_past_the_limit_shows_the_digits_that_tell_it_apart() -> None:
    with pytest.raises(UnsupportedInputError) as info:
        check_supported(np.array([[0.0, 0.0], [2.0 * MAX_SPAN + 0.0002, 0.0]]), 4.0)
    said = str(info.value)
    assert said.startswith("the start must fit in a circle of radius 10000 ")
    assert said.endswith(", got 10000.0001"), said


def test_shown_beyond_never_shows_the_limit_itself() -> None:
    assert shown_beyond(10040.93, MAX_SPAN) == "10040.9"
    assert shown_beyond(10000.00004, MAX_SPAN) == "10000.00004"
    assert shown_beyond(2.02e6, MAX_COORD) == "2020000.0"
    assert shown_beyond(1e300, MAX_SPAN) == "1e+300"


def test_the_whole_run_must_stay_inside_the_coordinate_range() -> None:
    start = ring(10, 10.0, (1.999e6, 0.0))
    check_supported(start, 4.0)  # a small target circle: the run stays inside
    a = 4000.0
    assert target_radius_of(10, a) == pytest.approx(6472.1, abs=0.1)
    with pytest.raises(UnsupportedInputError) as info:
        check_supported(start, a)
    assert str(info.value).startswith(
        "the run would reach 2005472.1 (a circle of radius 6472.1 about the start's centre "
        "(1999000.0, 0.0)), but coordinates must stay within +-2000000"
    )


def test_the_cli_refuses_a_run_that_would_leave_the_range_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    start = tmp_path / "far.json"
    far = ring(8, 20.0, (1.995e6, 0.0))
    start.write_text(json.dumps({"positions": far.tolist(), "a": 7000.0}))
    for mode in (["--lockstep"], []):
        assert cli.main(["run", *mode, "--init", str(start), "--seed", "1", "-q"]) == 2
        captured = capsys.readouterr()
        assert captured.out == "" and captured.err.count("\n") == 1, captured.err
        assert captured.err.startswith("fatswarm run: the run would reach ")


@pytest.mark.parametrize(
    ("value", "limit", "shown"),
    [
        (1.99999989, 1.9999999, "1.99999989"),
        (1.9999998999999997, 1.9999999, "1.9999998999999997"),
        (1.5, 1.9999999, "1.5"),
        (2.00000001, 2.0, "2.00000001"),
        (2.0, 2.0, "2.0"),
    ],
)
def test_a_value_is_shown_on_its_own_side_of_the_limit(
    value: float, limit: float, shown: str
) -> None:
    assert shown_apart(value, limit) == shown
