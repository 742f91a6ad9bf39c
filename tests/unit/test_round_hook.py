"""The round hook (`compute_views`): every robot of a round from its own view in one call, the
very bits of `compute`; the lock step's records are the same with it and without it."""

from __future__ import annotations

import math
from pathlib import Path as FsPath
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import fatswarm
from fatswarm.agent import row_sums
from fatswarm.agent.gathering import ALGORITHM as GATHERING
from fatswarm.agent.gathering import GatheringParams
from fatswarm.agent.oblot_common import OblotRuleError, make_oblot_params
from fatswarm.agent.oblot_go_to_cog import ALGORITHM as GO_TO_COG
from fatswarm.agent.row_sums import fsum_rows, nearest_norms
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.domain.path import Line, Path, Points, StraightMoves
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.domain.tolerance import snap
from fatswarm.world.looks import Looks
from fatswarm.world.record import RecordWriter

SETTINGS = settings(max_examples=80, deadline=None)
FLOATS = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, allow_subnormal=False)


def bits(values: np.ndarray) -> list[int]:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.int64).ravel().tolist()


def fsums(rows: np.ndarray) -> np.ndarray:
    return np.array([math.fsum(row.tolist()) for row in rows], dtype=np.float64)


@SETTINGS
@given(st.integers(1, 6).flatmap(lambda k: arrays(np.float64, (k, 9), elements=FLOATS)))
def test_fsum_rows_gives_math_fsum_bits_for_any_rows(rows: np.ndarray) -> None:
    assert bits(fsum_rows(rows)) == bits(fsums(rows))


def test_fsum_rows_gives_math_fsum_bits_on_ties_cancellations_and_wide_exponents() -> None:
    rng = np.random.default_rng(7)
    ties = np.zeros((6, 4))
    ties[:, 0] = 1.0
    ties[:, 1] = 2.0**-53 * np.array([1, 3, -1, 1, 1, -3])  # exactly half an ulp of 1.0
    ties[:, 2] = [0.0, 0.0, 0.0, 2.0**-300, -(2.0**-300), 2.0**-600]  # what breaks the tie
    cancel = rng.normal(size=(5, 50))
    cancel[:, -1] = -cancel[:, :-1].sum(axis=1)
    wide = rng.normal(size=(5, 40)) * 2.0 ** rng.integers(-80, 80, size=(5, 40))
    grid = rng.integers(-1000, 1000, size=(5, 30)) / 1024.0
    zero_sums = np.array([[0.5, -0.5, -0.0, 0.25, -0.25], [-0.0, 3.0, -0.0, -3.0, -0.0]])
    for rows in (
        ties,
        cancel,
        wide,
        grid,
        zero_sums,  # on a grid, summing to zero: +0.0, as math.fsum
        np.zeros((3, 5)),
        -np.zeros((2, 3)),
        np.ones((2, 0)),
    ):
        assert bits(fsum_rows(rows)) == bits(fsums(rows) if rows.shape[1] else np.zeros(2))


def test_fsum_rows_sums_along_the_second_axis_of_a_view_array() -> None:
    views = np.random.default_rng(3).normal(size=(4, 7, 2)) * 30.0
    want = np.stack([fsums(views[:, :, 0]), fsums(views[:, :, 1])], axis=1)
    assert bits(fsum_rows(views)) == bits(want)


def test_nearest_norms_gives_the_least_hypot_of_every_row_bit_for_bit() -> None:
    rng = np.random.default_rng(11)
    xs, ys = rng.normal(size=(40, 30)) * 50.0, rng.normal(size=(40, 30)) * 50.0
    xs[:10, 1], ys[:10, 1] = ys[:10, 0], xs[:10, 0]  # the same norm twice, swapped
    xs[10:20, 2] = np.nextafter(xs[10:20, 0], np.inf)  # near ties
    ys[10:20, 2] = ys[10:20, 0]
    xs[20, :], ys[20, :] = 1e-200, 3e-200  # squares underflow: np.hypot whole
    xs[21, 3] = np.nan  # NaN, as np.hypot has it
    xs[22, :] = 0.0
    ys[22, :] = 0.0
    want = np.hypot(xs, ys).min(axis=1)
    assert bits(nearest_norms(xs, ys)) == bits(want)
    # rows of one candidate each (every row's least far from its next): no search for them
    assert bits(nearest_norms(xs[23:], ys[23:])) == bits(want[23:])
    assert nearest_norms(xs[:0], ys[:0]).shape == (0,)


def test_fsum_rows_gives_math_fsum_bits_past_few_values() -> None:
    """More than FEW values (the largest found by a reduction, not by its index): on a grid (the
    exact path), anywhere, and with a row that does not fit the bound (math.fsum's)."""
    rng = np.random.default_rng(12)
    grid = rng.integers(-(2**20), 2**20, size=(90, 60)) / 1024.0
    anywhere = rng.normal(size=(90, 60)) * 1e3
    anywhere[7, :] = 1e-320  # subnormal: below TINY, every row to math.fsum
    assert grid.size > row_sums.FEW
    for rows in (grid, anywhere, anywhere[8:]):
        assert bits(fsum_rows(rows)) == bits(fsums(rows))


def test_nearest_norms_past_hypot_all_gives_the_least_hypot_bit_for_bit() -> None:
    """More than HYPOT_ALL elements: np.hypot of each row's candidate alone where every row has
    one (also where another element's square overflows), the candidates' where some have more,
    the whole row where its least square is out of range."""
    rng = np.random.default_rng(13)
    xs, ys = rng.normal(size=(40, 30)) * 50.0, rng.normal(size=(40, 30)) * 50.0
    assert xs.size > row_sums.HYPOT_ALL
    xs[3, 4], ys[5, 6] = 1e200, -3e170  # their squares overflow: not the least of their rows
    one = xs.copy()
    xs[9, 1], ys[9, 1] = ys[9, 0], xs[9, 0]  # two candidates
    huge = xs.copy()
    huge[11, :], ys[11, :] = 1e160, 2e160  # every square of the row past SQUARE_HUGE
    with np.errstate(over="ignore"):  # the squares that overflow say so
        for x in (one, xs, huge):
            assert bits(nearest_norms(x, ys)) == bits(np.hypot(x, ys).min(axis=1))


def views_of(positions: Points, rng: np.random.Generator) -> np.ndarray:
    """Every robot's view of `positions`, each turned, mirrored and shuffled its own way."""
    n = len(positions)
    out = np.empty((n, n - 1, 2))
    for robot in range(n):
        others = np.delete(positions, robot, axis=0) - positions[robot]
        angle = rng.uniform(-math.pi, math.pi)
        c, s = math.cos(angle), math.sin(angle)
        x = others[:, 0] * (-1.0 if rng.random() < 0.5 else 1.0)
        view = np.column_stack([c * x - s * others[:, 1], s * x + c * others[:, 1]])
        out[robot] = view[rng.permutation(n - 1)]
    return out


def assert_moves_are_paths(answer: object, paths: list[Path]) -> None:
    """`answer` is StraightMoves whose every row is the Path of `paths` bit for bit: a Line to
    the very floats (signs of zero included) where it goes, STAY elsewhere."""
    assert isinstance(answer, StraightMoves)
    assert answer.ends.shape == (len(paths), 2) and answer.ends.dtype == np.float64
    assert answer.goes.tolist() == [bool(p) for p in paths]
    assert answer.paths() == paths
    for end, go, path in zip(answer.ends, answer.goes, paths, strict=True):
        if go:
            (segment,) = path.segments
            assert type(segment) is Line
            assert bits(end) == bits(np.array(segment.end))


def drawn_positions(n: int, rng: np.random.Generator, kind: str) -> Points:
    """n centres: anywhere, on the world's grid (snapped, as a run's positions are), or some
    robots at one point (points gather there)."""
    positions = rng.uniform(-3.0 * n, 3.0 * n, size=(n, 2))
    if kind == "grid":
        positions = snap(positions)
    elif kind == "together":
        positions[: n // 2 + 1] = positions[0]
    return positions


def mirrored_views_of(positions: Points, rng: np.random.Generator) -> np.ndarray:
    """Every robot's view of `positions`, x mirrored or not, shuffled: the paper's frames (on the
    grid, the views' sums take `fsum_rows`' exact path)."""
    n = len(positions)
    out = np.empty((n, n - 1, 2))
    for robot in range(n):
        others = np.delete(positions, robot, axis=0) - positions[robot]
        if rng.random() < 0.5:
            others[:, 0] *= -1.0
        out[robot] = others[rng.permutation(n - 1)]
    return out


KINDS = st.sampled_from(["any", "grid", "together"])


@SETTINGS
@given(
    st.integers(2, 60),
    st.integers(0, 2**32 - 1),
    st.sampled_from([1e-3, 0.5, 5.0]),
    KINDS,
    st.booleans(),
)
def test_gathering_hook_gives_every_robot_the_path_of_its_own_compute(
    n: int, seed: int, tolerance: float, kind: str, turned: bool
) -> None:
    rng = np.random.default_rng(seed)
    positions = drawn_positions(n, rng, kind)
    views = views_of(positions, rng) if turned else mirrored_views_of(positions, rng)
    params = GatheringParams(n, tolerance)
    want = [GATHERING.compute(view, params) for view in views]
    assert_moves_are_paths(GATHERING.compute_views(views, params), want)


@SETTINGS
@given(
    st.integers(2, 60), st.integers(0, 2**32 - 1), KINDS, st.booleans(), st.sampled_from([0.0, 1.0])
)
def test_go_to_cog_hook_gives_every_robot_the_path_of_its_own_compute(
    n: int, seed: int, kind: str, turned: bool, tolerance: float
) -> None:
    rng = np.random.default_rng(seed)
    positions = drawn_positions(n, rng, kind)
    if kind == "together" and rng.random() < 0.5:  # point robots gathered at one point
        positions[:] = positions[0]
    views = views_of(positions, rng) if turned else mirrored_views_of(positions, rng)
    params = make_oblot_params(n, {"tolerance": tolerance})
    want = [GO_TO_COG.compute(view, params) for view in views]
    assert_moves_are_paths(GO_TO_COG.compute_views(views, params), want)


def test_gathering_hook_steps_short_of_g_and_stays_as_compute_does() -> None:
    """Views where some robots reach G, some stop short of it (the gap caps the step) and some
    stay (touching): every branch of `_toward` in one call."""
    positions = np.array([[0.0, 0.0], [2.0, 0.0], [10.0, 3.0], [-7.5, 4.25], [3.0, -9.0]])
    rng = np.random.default_rng(1)
    views = mirrored_views_of(positions, rng)
    params = GatheringParams(5, 1e-3)
    want = [GATHERING.compute(view, params) for view in views]
    assert {len(p) for p in want} == {0, 1}
    assert_moves_are_paths(GATHERING.compute_views(views, params), want)


def test_go_to_cog_hook_refuses_a_target_that_is_not_finite_as_compute_does() -> None:
    views = np.array([[[1.0, 2.0]], [[np.inf, 0.0]]])
    params = make_oblot_params(2, {"tolerance": 0.0})
    with pytest.raises(OblotRuleError, match="not a finite point"):
        GO_TO_COG.compute(views[1], params)
    with pytest.raises(OblotRuleError, match="not a finite point"):
        GO_TO_COG.compute_views(views, params)


def test_hooks_answer_a_round_of_empty_views_as_compute_does() -> None:
    views = np.zeros((1, 0, 2))
    params = GatheringParams(1, 1e-3)
    assert_moves_are_paths(
        GATHERING.compute_views(views, params), [GATHERING.compute(views[0], params)]
    )
    oblot = make_oblot_params(1, {"tolerance": 0.0})
    assert_moves_are_paths(
        GO_TO_COG.compute_views(views, oblot), [GO_TO_COG.compute(views[0], oblot)]
    )


@pytest.mark.parametrize(
    "frames, frame_change",
    [("y-axis", "fixed"), ("disoriented", "fixed"), ("chirality", "every-look")],
)
@pytest.mark.parametrize("n", [9, 90])  # 90: the hashes sorted as values (view_orders)
def test_the_views_built_at_once_are_the_views_built_one_by_one(
    frames: str, frame_change: str, n: int
) -> None:
    model = RobotModel.of(frames=frames, frame_change=frame_change)
    setting = Configured.of(GATHERING, n)
    positions = np.random.default_rng(5).uniform(-20.0, 20.0, size=(n, 2))
    robots = [0, 2, 3, 7, 8] if n == 9 else [r for r in range(n) if r % 7]
    at_once = Looks(model, setting, n, 11, False).views_at_once(positions, 4, robots)
    alone = Looks(model, setting, n, 11, False)
    assert at_once is not None
    for row, robot in enumerate(robots):
        assert bits(at_once[row]) == bits(alone.view(positions, robot, 4)[0])


def test_no_views_at_once_where_views_differ_in_kind() -> None:
    setting = Configured.of(GATHERING, 5)
    positions = np.random.default_rng(5).uniform(-20.0, 20.0, size=(5, 2))
    for model, record_views in ((RobotModel.of(sight=3.0), False), (RobotModel(), True)):
        looks = Looks(model, setting, 5, 1, record_views)
        assert looks.views_at_once(positions, 1, [0, 1]) is None


RUNS: list[tuple[str, dict[str, Any]]] = [
    ("gathering", {"scheduler": "fsync"}),
    ("gathering", {"scheduler": "ssync", "non_rigid": 0.3, "frames": "disoriented"}),
    ("gathering", {"scheduler": "centralized", "max_rounds": 60}),
    ("gathering", {"scheduler": "fsync", "crash": 2, "frame_change": "every-look"}),
    ("gathering", {"scheduler": "async", "max_rounds": 60}),
    ("oblot-go-to-cog", {"scheduler": "ssync", "bodies": "points"}),
    ("oblot-go-to-cog", {"scheduler": "fsync", "non_rigid": 0.2, "bodies": "points"}),
]


def record_of(tmp_path: FsPath, name: str, algorithm: str, seed: int, kw: dict[str, Any]) -> bytes:
    target = tmp_path / f"{name}.jsonl"
    fatswarm.run(9 + seed, algorithm=algorithm, seed=seed, record=target, **kw)
    return target.read_bytes()


@pytest.mark.parametrize("algorithm, kw", RUNS)
@pytest.mark.parametrize("seed", [0, 3])
def test_a_record_is_the_same_with_the_round_hook_and_without(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch, algorithm: str, kw: dict[str, Any], seed: int
) -> None:
    with_hook = record_of(tmp_path, "hook", algorithm, seed, kw)
    monkeypatch.setattr(Configured, "views_compute", lambda self: None)
    assert record_of(tmp_path, "alone", algorithm, seed, kw) == with_hook


@pytest.mark.parametrize(
    "algorithm, kw",
    [("gathering", {}), ("oblot-go-to-cog", {"bodies": "points", "frames": "disoriented"})],
)
def test_a_large_round_is_the_same_with_the_round_hook_and_without(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch, algorithm: str, kw: dict[str, Any]
) -> None:
    """n = 70: a round's view orders sorted as values (view_orders), the hook's arrays."""

    def record(name: str) -> bytes:
        target = tmp_path / f"{name}.jsonl"
        fatswarm.run(70, algorithm=algorithm, seed=2, record=target, max_rounds=8, **kw)
        return target.read_bytes()

    with_hook = record("hook")
    monkeypatch.setattr(Configured, "views_compute", lambda self: None)
    assert record("alone") == with_hook


class Faulty:
    """Gathering whose round hook fails: raises in even rounds' calls, else gives one robot
    something that is not a Path, and computes 'boom' robots' paths by raising."""

    def __init__(self) -> None:
        self.calls = 0

    def __getattr__(self, name: str) -> Any:
        return getattr(GATHERING, name)

    name = "faulty-gathering"

    def compute(self, view: Points, params: GatheringParams) -> Path:
        if len(view) and float(view[0, 0]) < -10.0:
            raise ArithmeticError("boom")
        return GATHERING.compute(view, params)

    def compute_views(self, views: np.ndarray, params: GatheringParams) -> list[Any]:
        self.calls += 1
        if self.calls % 2 == 0:
            raise ArithmeticError("the hook failed")
        paths: list[Any] = [self.compute(view, params) for view in views]
        paths[0] = "not a path"
        return paths


def ten_robot_record(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch, algorithm: Any, hook: bool, seed: int
) -> bytes:
    """12 fsync rounds of `algorithm` from a start of 10 discs drawn with `seed`, with its round
    hook or (`hook` False) with each robot's compute alone: the record's bytes."""
    if not hook:
        monkeypatch.setattr(Configured, "views_compute", lambda self: None)
    target = tmp_path / f"{getattr(algorithm, 'name', 'run')}-{hook}.jsonl"
    start = np.random.default_rng(seed).uniform(-30.0, 30.0, size=(10, 2))
    start = np.round(start / 4.0) * 4.0 + np.arange(10)[:, None] * 0.01
    with RecordWriter(target) as journal:
        run_lockstep(
            start,
            Configured.of(algorithm, 10),
            make_scheduler("fsync", 10, 0),
            seed=1,
            max_rounds=12,
            record=journal,
        )
    monkeypatch.undo()
    return target.read_bytes()


def test_a_failing_hook_leaves_each_robot_what_its_own_compute_gives(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch
) -> None:
    with_hook = ten_robot_record(tmp_path, monkeypatch, Faulty(), True, 2)
    assert with_hook == ten_robot_record(tmp_path, monkeypatch, Faulty(), False, 2)


def test_a_subclass_that_changes_compute_does_not_inherit_its_parents_round_hooks() -> None:
    """A subclass of gathering (or of the paper's algorithm) with a compute of its own must not
    have its rounds computed by the parent's hook or shared plan: its own compute runs."""
    from fatswarm.agent.gathering import Gathering
    from fatswarm.agent.uniform_circle import ALGORITHM as PAPER

    class Still(Gathering):
        def compute(self, view: Points, params: GatheringParams) -> Path:
            return Gathering.compute(self, view, params)

    class KeepsHook(Still):
        def compute_views(self, views: Any, params: GatheringParams) -> Any:
            return [self.compute(v, params) for v in views]

    paper_child = type("PaperChild", (type(PAPER),), {"compute": type(PAPER).compute})
    assert Configured.of(Still(), 4, None).views_compute() is None
    assert Configured.of(GATHERING, 4, None).views_compute() is not None
    assert Configured.of(KeepsHook(), 4, None).views_compute() is not None
    assert Configured.of(paper_child(), 8, None).round_planner() is None
    assert Configured.of(PAPER, 8, None).round_planner() is not None


def test_straight_moves_are_the_lines_and_stays_they_stand_for() -> None:
    from fatswarm.domain.path import STAY, Line, StraightMoves

    ends = np.array([[1.5, -2.0], [0.0, 0.0], [3.0, 4.0]], dtype=np.float64)
    moves = StraightMoves(ends, np.array([True, False, True]))
    got = moves.paths()
    assert len(moves) == 3
    assert got == [Path((Line((1.5, -2.0)),)), STAY, Path((Line((3.0, 4.0)),))]
    assert all(type(c) is float for p in got for seg in p for c in seg.end)  # type: ignore[union-attr]


class StraightGathering:
    """Gathering, counting the calls of its compute alone: none while its round hook (which
    answers StraightMoves) answers."""

    name = "straight-gathering"
    computed = 0

    def __getattr__(self, name: str) -> Any:
        return getattr(GATHERING, name)

    def compute(self, view: Points, params: GatheringParams) -> Path:
        StraightGathering.computed += 1
        return GATHERING.compute(view, params)

    def compute_views(self, views: np.ndarray, params: GatheringParams) -> StraightMoves:
        return GATHERING.compute_views(views, params)


def test_a_hook_answering_straight_moves_makes_the_record_of_compute_alone(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch
) -> None:
    with_hook = ten_robot_record(tmp_path, monkeypatch, StraightGathering(), True, 5)
    assert StraightGathering.computed == 0  # every round went through the hook's arrays
    assert ten_robot_record(tmp_path, monkeypatch, StraightGathering(), False, 5) == with_hook
    assert StraightGathering.computed > 0
