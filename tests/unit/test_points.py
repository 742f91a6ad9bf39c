"""Point robots (`--bodies points`): robots of radius 0 that may meet and share a point, meeting is
no collision, a point hides another only on the segment between them, and an algorithm sees each
robot (multiplicity detection) or each occupied point once."""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.agent.gathering import ALGORITHM as GATHERING
from fatswarm.domain.path import Line
from fatswarm.domain.path import Path as MovePath
from fatswarm.domain.robot_model import Bodies, RobotModel, Visibility
from fatswarm.domain.seam import Configured
from fatswarm.world.looks import Looks
from fatswarm.world.physics import InvalidConfigurationError, apply_round, validate_configuration
from fatswarm.world.sight import GRAZE_SLACK, seen

DATA = Path(__file__).resolve().parents[1] / "data"
POINTS = RobotModel.of(bodies="points")


def _meet_module() -> object:
    spec = importlib.util.spec_from_file_location("meet_points_test", DATA / "meet_points.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["meet_points_test"] = module
    spec.loader.exec_module(module)
    return module


MEET = _meet_module()


def test_the_bodies_axis_is_written_only_when_not_fat() -> None:
    assert "bodies" not in RobotModel().to_header()
    assert POINTS.to_header()["bodies"] == "points"
    assert RobotModel.from_header(POINTS.to_header()) == POINTS
    assert POINTS.bodies is Bodies.POINTS and POINTS.describe() == "--bodies points"


def test_point_robots_may_start_at_one_point_fat_ones_may_not() -> None:
    start = np.array([[0.0, 0.0], [0.0, 0.0], [0.5, 0.0]])
    assert (validate_configuration(start, bodies_are_points=True) == start).all()
    with pytest.raises(InvalidConfigurationError, match="overlap"):
        validate_configuration(start)


def test_point_movers_cover_their_whole_path_and_meeting_is_no_collision() -> None:
    start = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 0.0]])
    to_two = MovePath((Line((2.0, 0.0)),))  # world frame: both onto robot 2's point
    paths = {0: to_two, 1: to_two}
    outcome = apply_round(start, paths, points=True)
    assert outcome.collisions == []
    assert outcome.positions.tolist() == [[2.0, 0.0], [2.0, 0.0], [2.0, 0.0]]
    assert outcome.traveled == {0: 2.0, 1: 2.0}
    fat = apply_round(start, paths)  # discs: both stop at contact with the robot between
    assert fat.collisions


def test_an_opaque_point_hides_another_only_on_the_segment_between() -> None:
    line = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])  # 1 is on the segment 0-2
    assert seen(line, 0, Visibility.OPAQUE, None, points=True).tolist() == [1]
    assert seen(line, 1, Visibility.OPAQUE, None, points=True).tolist() == [0, 2]
    assert seen(line, 0, Visibility.OPAQUE_CENTRES, None, points=True).tolist() == [1]
    off = line + np.array([[0.0, 0.0], [0.0, 3 * GRAZE_SLACK], [0.0, 0.0]])  # just off it
    assert seen(off, 0, Visibility.OPAQUE, None, points=True).tolist() == [1, 2]
    near = line + np.array([[0.0, 0.0], [0.0, GRAZE_SLACK / 4], [0.0, 0.0]])  # on it, snapped
    assert seen(near, 0, Visibility.OPAQUE, None, points=True).tolist() == [1]
    beyond = np.array([[0.0, 0.0], [3.0, 0.0], [2.0, 0.0]])  # behind the far one: hides nothing
    assert seen(beyond, 0, Visibility.OPAQUE, None, points=True).tolist() == [2]
    shared = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [0.0, 0.0]])  # two at one point
    assert seen(shared, 0, Visibility.OPAQUE, None, points=True).tolist() == [1, 2, 3]


def test_multiplicity_detection_shows_every_robot_its_absence_each_point_once() -> None:
    positions = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [0.0, 0.0], [0.0, 5.0]])
    many = Configured.of(MEET.ALGORITHM, 5)  # type: ignore[attr-defined]
    once = Configured.of(MEET.ONCE, 5)  # type: ignore[attr-defined]
    view = Looks(POINTS, many, 5, 1, False).view(positions, 0, 1)[0]
    assert sorted(map(tuple, np.abs(view).tolist())) == [(0, 0), (0, 5), (2, 0), (2, 0)]
    looks = Looks(POINTS, once, 5, 1, True)
    view = looks.view(positions, 0, 1)[0]
    assert sorted(map(tuple, np.abs(view).tolist())) == [(0, 5), (2, 0)]  # not its own point
    assert len(looks.views[0]) == 2  # the robots whose rows it was shown


def test_a_run_of_point_robots_meets_at_one_point_in_lock_step() -> None:
    start = np.array([[0.0, 0.0], [0.5, 0.0], [3.0, 1.0], [3.0, 1.0], [10.0, -2.0]])
    for algorithm in ("ALGORITHM", "ONCE"):
        result = fatswarm.run(
            positions=start,
            algorithm=f"{DATA / 'meet_points.py'}:{algorithm}",
            scheduler="ssync",
            seed=2,
            bodies="points",
        )
        assert str(result.status) == "formed" and result.collisions == 0
        assert result.outside == ""


def test_a_fat_algorithm_among_points_runs_outside_its_assumption() -> None:
    result = fatswarm.run(4, seed=1, scheduler="ssync", bodies="points", max_rounds=20)
    assert "assumes bodies fat; this run gives it points" in result.outside
    setting = Configured.of(GATHERING, 3)
    assert dataclasses.replace(setting).assumptions.bodies == (Bodies.FAT,)


def test_an_init_file_of_point_robots_may_share_points(tmp_path: Path) -> None:
    from fatswarm.deploy.scenarios.starts import InitFileError, load_init

    init = tmp_path / "start.json"
    init.write_text('{"positions": [[0, 0], [0, 0]]}')
    assert load_init(str(init), points=True)[0].tolist() == [[0.0, 0.0], [0.0, 0.0]]
    with pytest.raises(InitFileError, match="overlap"):
        load_init(str(init))
