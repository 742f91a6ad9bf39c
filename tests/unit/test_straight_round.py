"""A round whose hook answers StraightMoves goes from the hook's arrays to physics as arrays
(`Lockstep._straight`, `WorldCore.hold_lines`, `Looks.lines_to_world`, `FrameRows`, the commit's
`LineMoves`): the very bits and the very records of the per-robot Paths and of compute alone."""

from __future__ import annotations

import math
from pathlib import Path as FsPath
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.agent.gathering import ALGORITHM as GATHERING
from fatswarm.agent.oblot_go_to_cog import ALGORITHM as GO_TO_COG
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.domain.frames import Frame, FrameRows
from fatswarm.domain.path import STAY, Line, Path, Points, StraightMoves
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.domain.wire import MAX_COORD
from fatswarm.world import physics, rounds
from fatswarm.world.core import WorldCore
from fatswarm.world.looks import Looks
from fatswarm.world.protocol import Begin
from fatswarm.world.record import RecordWriter
from fatswarm.world.setup import WorldSetup

FLOATS = st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from(
    [0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e16, -3e5, MAX_COORD, -MAX_COORD]
)
ROTATIONS = st.sampled_from([0.0, math.pi, -0.0]) | st.floats(0.0, 2.0 * math.pi)


def bits(values: Any) -> list[int]:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.int64).ravel().tolist()


def path_bits(path: Path) -> list[int]:
    assert all(type(seg) is Line for seg in path.segments)
    return bits([seg.end for seg in path.segments])  # type: ignore[union-attr]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(ROTATIONS, st.booleans(), FLOATS, FLOATS), min_size=1, max_size=12))
def test_frame_rows_turn_lines_to_world_with_the_bits_of_each_frame_alone(
    rows: list[tuple[float, bool, float, float]],
) -> None:
    frames = [Frame(rotation, mirror) for rotation, mirror, _, _ in rows]
    ends = np.array([[x, y] for _, _, x, y in rows], dtype=np.float64)
    world = FrameRows.of(frames).lines_to_world(ends)
    for frame, end, got in zip(frames, ends.tolist(), world, strict=True):
        alone = frame.path_to_world(Path((Line((end[0], end[1])),)))
        assert bits(got) == path_bits(alone)


@pytest.mark.parametrize(
    "frames, frame_change",
    [
        ("y-axis", "fixed"),
        ("both-axes", "fixed"),
        ("disoriented", "fixed"),
        ("chirality", "every-look"),
        ("disoriented", "every-look"),
        ("y-axis", "every-look"),
    ],
)
def test_looks_turn_a_rounds_lines_to_world_as_each_robots_to_world(
    frames: str, frame_change: str
) -> None:
    n = 12
    model = RobotModel.of(frames=frames, frame_change=frame_change)
    looks = Looks(model, Configured.of(GATHERING, n), n, 7, False)
    for robots in ([0, 3, 4, 9, 11], list(range(n)), [11, 2, 5]):  # some, everyone, any order
        ends = np.random.default_rng(len(robots)).normal(size=(len(robots), 2)) * 40.0
        ends[0] = (-0.0, 0.0)
        world = looks.lines_to_world(robots, 5, ends)
        for robot, end, got in zip(robots, ends.tolist(), world, strict=True):
            alone = looks.to_world(robot, 5, Path((Line((end[0], end[1])),)))
            assert bits(got) == path_bits(alone)


def open_world(n: int = 6, frames: str = "disoriented") -> WorldCore:
    start = np.array([[4.0 * i, 0.0] for i in range(n)])
    setup = WorldSetup(
        "t", n, 3, "fsync", start, 50, "gathering", robot_model=RobotModel.of(frames=frames)
    )
    world = WorldCore(setup, Configured.of(GATHERING, n))
    world.take_effects()
    assert world.control(Begin(1, tuple(range(n))))[0].ok
    return world


def state(world: WorldCore) -> tuple[Any, ...]:
    return (
        {r: [path_bits(p)] for r, p in world.held.items()},
        sorted(world.missing),
        dict(world.rejected),
        [type(e).__name__ for e in world.take_effects()],
    )


@pytest.mark.parametrize(
    "robots, looked, round_no",
    [
        ([0, 1, 2, 4, 5], [0, 1, 2, 4, 5], 1),  # every check passes: held as lines
        ([0, 1, 2, 4, 5], [0, 1, 2, 5], 1),  # robot 4 has not looked: refused, counted
        ([0, 1, 1, 4], [0, 1, 4], 1),  # robot 1 twice: the second refused as a duplicate
        ([0, 1, 2], [0, 1, 2], 2),  # not the open round
    ],
)
def test_hold_lines_holds_and_refuses_as_hold_does_for_each_robot(
    robots: list[int], looked: list[int], round_no: int
) -> None:
    ends = np.random.default_rng(4).normal(size=(len(robots), 2))
    goes = np.array([i % 3 != 1 for i in range(len(robots))])
    at_once, alone = open_world(), open_world()
    for world in (at_once, alone):
        for robot in looked:
            assert world.admit_look(robot)
    at_once.hold_lines(robots, round_no, ends, goes)
    for robot, (x, y), go in zip(robots, ends.tolist(), goes.tolist(), strict=True):
        alone.hold(robot, round_no, Path((Line((x, y)),)) if go else STAY, None)
    assert state(at_once) == state(alone)


def test_held_lines_stand_for_the_held_paths_until_held_is_read() -> None:
    world = open_world()
    for robot in range(6):
        world.admit_look(robot)
    ends = np.array([[1.0, 2.0], [0.0, 0.0], [3.0, -1.0], [0.5, 0.5]])
    world.hold_lines([5, 1, 3, 0], 1, ends, np.array([True, False, True, True]))
    lines = world.held_lines()
    assert lines is not None
    movers, world_ends = lines
    assert movers.tolist() == [0, 3, 5]  # ascending, stays left out
    held = world.held  # made Paths: the lines are now the per-robot form's
    assert sorted(held) == [0, 1, 3, 5] and held[1] == STAY
    assert [path_bits(held[r]) for r in (0, 3, 5)] == [bits(e) for e in world_ends]
    assert world.held_lines() is None  # read whole: the commit takes the Paths
    mixed = open_world()
    for robot in range(6):
        mixed.admit_look(robot)
    mixed.hold(2, 1, Path((Line((1.0, 1.0)),)), None)  # a move of its own beside the lines
    mixed.hold_lines([0, 1], 1, ends[:2], np.array([True, True]))
    assert mixed.held_lines() is None


def _as_paths(answer: Any) -> Any:
    """A round hook's answer as k Paths (the inner hooks answer StraightMoves)."""
    return answer.paths() if isinstance(answer, StraightMoves) else answer


class Straight:
    """`inner`'s round hook answered as StraightMoves (where every path is a line or a stay);
    `wild`: a robot whose view's first row has x < -12 asks for a NaN line, y > 12 for a line
    beyond the wire's bounds (alone as through the hook)."""

    name = "straight"

    def __init__(self, inner: Any, wild: bool = False) -> None:
        self.inner, self.wild = inner, wild
        self.answered = 0  # hook calls answered as StraightMoves

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)

    def _wild(self, view: Points, path: Path) -> Path:
        if self.wild and len(view):
            if float(view[0, 0]) < -40.0:
                return Path((Line((math.nan, 1.0)),))
            if float(view[0, 1]) > 40.0:
                return Path((Line((0.5, 2.0 * MAX_COORD)),))
        return path

    def compute(self, view: Points, params: Any) -> Path:
        return self._wild(view, self.inner.compute(view, params))

    def compute_views(self, views: np.ndarray, params: Any) -> Any:
        paths = [
            self._wild(v, p)
            for v, p in zip(views, _as_paths(self.inner.compute_views(views, params)), strict=True)
        ]
        if not all(not p or (len(p) == 1 and type(p.segments[0]) is Line) for p in paths):
            return paths
        self.answered += 1
        ends = [p.segments[0].end if p else (0.0, 0.0) for p in paths]  # type: ignore[union-attr]
        goes = np.array([bool(p) for p in paths], dtype=np.bool_)
        return StraightMoves(np.array(ends, dtype=np.float64).reshape(-1, 2), goes)


class AsPaths(Straight):
    """`Straight` whose hook gives the same moves as k Paths (`StraightMoves.paths`)."""

    def compute_views(self, views: np.ndarray, params: Any) -> Any:
        answer = Straight.compute_views(self, views, params)
        return answer.paths() if isinstance(answer, StraightMoves) else answer


RUNS: list[tuple[str, str, dict[str, Any]]] = [
    ("gathering", "fsync", {}),
    ("gathering", "ssync", {"frames": "disoriented"}),
    ("gathering", "fsync", {"frames": "chirality", "frame_change": "every-look"}),
    ("gathering", "centralized", {"frames": "disoriented", "frame_change": "every-look"}),
    ("gathering", "fsync", {"frames": "both-axes", "crash": 2}),
    ("gathering", "ssync", {"non_rigid": 0.3, "frames": "disoriented"}),
    ("gathering", "async", {"frames": "disoriented"}),
    ("gathering", "fsync", {"frames": "disoriented", "wild": True}),
    ("gathering", "ssync", {"frame_change": "every-look", "wild": True}),
    ("oblot-go-to-cog", "fsync", {"bodies": "points"}),
    ("oblot-go-to-cog", "ssync", {"bodies": "points", "non_rigid": 0.2, "frames": "chirality"}),
]
INNER = {"gathering": GATHERING, "oblot-go-to-cog": GO_TO_COG}


def record(
    tmp_path: FsPath, name: str, algorithm: Any, scheduler: str, seed: int, kw: dict[str, Any]
) -> bytes:
    kw = dict(kw)
    n = 10 + seed
    model_kw = {k: kw.pop(k) for k in ("frames", "frame_change", "bodies") if k in kw}
    rng = np.random.default_rng(seed + 11)
    cells = rng.choice(16 * 16, size=n, replace=False)  # distinct cells 4 apart: discs apart
    start = np.column_stack([cells % 16, cells // 16]) * 4.0 - 30.0 + 0.01 * np.arange(n)[:, None]
    target = tmp_path / f"{name}.jsonl"
    rounds_cap = 40 if scheduler == "async" else 25
    with RecordWriter(target) as journal:
        run_lockstep(
            start,
            Configured.of(algorithm, n),
            make_scheduler(scheduler, n, seed),
            seed=seed,
            max_rounds=rounds_cap,
            record=journal,
            robot_model=RobotModel.of(**model_kw),
            **kw,
        )
    return target.read_bytes()


@pytest.mark.parametrize("inner, scheduler, kw", RUNS)
@pytest.mark.parametrize("seed", [0, 5])
def test_a_record_is_the_same_through_straight_moves_through_paths_and_alone(
    tmp_path: FsPath,
    monkeypatch: pytest.MonkeyPatch,
    inner: str,
    scheduler: str,
    kw: dict[str, Any],
    seed: int,
) -> None:
    kw = dict(kw)
    wild = kw.pop("wild", False)
    lined = 0
    real = physics.apply_lines

    def counted(*args: Any, **kwargs: Any) -> Any:
        nonlocal lined
        lined += 1
        return real(*args, **kwargs)

    monkeypatch.setattr(rounds, "apply_lines", counted)
    straight = Straight(INNER[inner], wild)
    arrays = record(tmp_path, "arrays", straight, scheduler, seed, kw)
    assert straight.answered > 0  # the hook answered in arrays
    if scheduler != "async" and "non_rigid" not in kw:
        assert lined > 0  # and rounds went to physics as arrays
    if wild:  # and some rows broke the wire's rules: refused, the robot timed out
        assert b'"timed_out"' in arrays
    through_paths = record(tmp_path, "paths", AsPaths(INNER[inner], wild), scheduler, seed, kw)
    monkeypatch.setattr(Configured, "views_compute", lambda self: None)
    alone = record(tmp_path, "alone", Straight(INNER[inner], wild), scheduler, seed, kw)
    assert arrays == through_paths == alone


class Misshapen(Straight):
    """`Straight` whose StraightMoves have a row too many: not the contract's, so each robot's
    own compute answers (as for a hook that gives k + 1 Paths)."""

    def compute_views(self, views: np.ndarray, params: Any) -> Any:
        answer = Straight.compute_views(self, views, params)
        if not isinstance(answer, StraightMoves):
            return answer
        ends = np.vstack([answer.ends, [[1.0, 1.0]]])
        return StraightMoves(ends, np.append(answer.goes, True))


def test_straight_moves_of_the_wrong_shape_leave_each_robot_its_own_compute(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch
) -> None:
    misshapen = Misshapen(GATHERING)
    hooked = record(tmp_path, "misshapen", misshapen, "fsync", 1, {"frames": "disoriented"})
    assert misshapen.answered > 0
    monkeypatch.setattr(Configured, "views_compute", lambda self: None)
    alone = record(tmp_path, "alone", Straight(GATHERING), "fsync", 1, {"frames": "disoriented"})
    assert hooked == alone
