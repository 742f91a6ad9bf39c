"""Issue 10's async models: robots Look, Compute, Move and Wait on their own clocks in virtual
time, a Look sees robots in the middle of their moves, and collision detection covers paths that
start at different times. Lock-step runs are deterministic from one seed and their records let a
reader rebuild every robot's position at any time."""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from pathlib import Path as FsPath
from typing import Any

import numpy as np
import pytest

from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy import cli
from fatswarm.deploy.engine.lockstep import configured, run_lockstep
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.domain import frames
from fatswarm.domain.adversary import (
    ASYNC_NAMES,
    RANDOM_MAX,
    STALE_STEP,
    STALE_WAIT,
    Delays,
    NotRoundBasedError,
    make_async,
)
from fatswarm.domain.draws import crash_plan, view_order, view_orders
from fatswarm.domain.path import Line, Path, Point, path_length, point_at, remainder, truncate
from fatswarm.world import looks
from fatswarm.world.asynchrony import AsyncWorld, CycleDone, Phase
from fatswarm.world.record import RecordWriter
from fatswarm.world.record_read import read_record

PATHS = [
    Path((Line((3.0, 0.0)),)),
    Path((Line((1.0, 0.0)), Line((1.0, 2.0)), Line((-1.0, 2.0)))),
]


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("s", [0.0, 0.5, 1.0, 2.2, 3.7, 10.0])
def test_the_rest_of_a_path_picks_up_where_its_prefix_stops(path: Path, s: float) -> None:
    from fatswarm.domain.path import Arc

    arcs = Path((*path.segments, Arc((0.0, 2.0), math.pi / 2)))
    start: Point = (0.0, 0.0)
    for p in (path, arcs):
        whole = path_length(start, p)
        head = truncate(start, p, s)
        mid = point_at(start, p, s)
        rest = remainder(start, p, s)
        assert path_length(start, head) + path_length(mid, rest) == pytest.approx(whole)
        for u in (0.0, 0.3, 1.1):
            assert np.allclose(point_at(mid, rest, u), point_at(start, p, s + u), atol=1e-12)


def _drive(
    world: AsyncWorld, plans: dict[int, Path], compute: dict[int, float], until: float
) -> tuple[list[CycleDone], dict[int, Any]]:
    """Each robot moves once by its plan (world-frame, from where it Looks) after its compute
    delay, then waits for good; returns the ended cycles and what each robot saw."""
    done: list[CycleDone] = []
    seen: dict[int, Any] = {}
    while world.now < until:
        t = world.next_time()
        if (
            t <= world.now
            and not world.looking()
            and not any(world.phase(r) is Phase.COMPUTING for r in range(world.n))
        ):
            break
        world.advance(min(t, until))
        done += world.end_moves()
        world.start_moves()
        for robot in world.looking():
            world.begin_cycle(robot)
            seen[robot] = np.delete(world.positions, robot, axis=0) - world.positions[robot]
            here = world.positions[robot]
            plan = plans.get(robot, Path())
            moved = Path(
                tuple(
                    Line((here[0] + s.end[0], here[1] + s.end[1]))  # type: ignore[union-attr]
                    for s in plan.segments
                )
            )
            stayed = world.submit(robot, moved, compute.get(robot, 0.0), 1e6)
            if stayed is not None:
                done.append(stayed)
    return done, seen


def test_a_look_sees_a_robot_in_the_middle_of_its_move() -> None:
    world = AsyncWorld(np.array([[0.0, 0.0], [0.0, 10.0]]), [0.0, 1.5])
    _, seen = _drive(world, {0: Path((Line((8.0, 0.0)),))}, {}, until=3.0)
    assert np.allclose(seen[1], [[1.5, -10.0]], atol=1e-8)  # robot 0, 1.5 along its 8


def _min_gap(cycles: list[CycleDone], initial: np.ndarray, times: np.ndarray) -> float:
    """The least distance between two centres over `times`, rebuilt from the ended cycles."""
    worst = math.inf
    for t in times:
        pos = _positions_at(cycles, initial, float(t))
        d = np.hypot(*(pos[:, None, :] - pos[None, :, :]).transpose(2, 0, 1))
        d[np.diag_indices(len(pos))] = np.inf
        worst = min(worst, float(d.min()))
    return worst


def _positions_at(
    cycles: list[CycleDone] | list[dict[str, Any]], initial: np.ndarray, t: float
) -> np.ndarray:
    """Every robot at virtual time t from the moves alone: its last move started by t, followed
    for (t - start) up to the arc length it covered (docs/record.md, "Async runs")."""
    pos = np.array(initial, dtype=np.float64)
    latest: dict[int, tuple[float, Point, Path, float]] = {}
    for c in cycles:
        if isinstance(c, CycleDone):
            robot, start, origin, path, covered = c.robot, c.start, c.origin, c.path, c.traveled
        else:
            robot, start, origin, path, covered = (
                c["robot"],
                c["start"],
                c["origin"],
                c["path"],
                c["traveled"],
            )
        if path and start <= t and (robot not in latest or latest[robot][0] <= start):
            latest[robot] = (start, origin, path, covered)
    for robot, (start, origin, path, covered) in latest.items():
        pos[robot] = point_at(origin, path, min(t - start, covered))
    return pos


@pytest.mark.parametrize(("delay", "meets"), [(0.0, True), (2.0, True), (12.0, False)])
def test_moves_that_start_at_different_times_are_checked_along_their_paths(
    delay: float, meets: bool
) -> None:
    # robot 0 crosses x = 5 at t = 5; robot 1 crosses y = 0 at t = delay + 5
    initial = np.array([[0.0, 0.0], [5.0, -5.0]])
    world = AsyncWorld(initial, [0.0, 0.0])
    cycles, _ = _drive(
        world,
        {0: Path((Line((10.0, 0.0)),)), 1: Path((Line((0.0, 10.0)),))},
        {1: delay},
        until=40.0,
    )
    contacts = [c for cycle in cycles for c in cycle.collisions]
    assert bool(contacts) is meets
    gap = _min_gap(cycles, initial, np.linspace(0.0, 40.0, 4001))
    assert gap >= 2.0 - 1e-6  # discs never overlap, at any instant
    if meets:
        assert gap <= 2.0 + 1e-6  # they touched: contact, not a near miss
        starts = {c.robot: c.start for c in cycles}
        assert starts[1] - starts[0] == pytest.approx(delay)


def test_the_adversary_draws_are_pure_functions_of_seed_robot_and_cycle() -> None:
    model = make_async("async", 6, 7)
    draws = {(r, k): model.cycle(r, k) for r in range(6) for k in range(1, 5)}
    assert draws == {key: make_async("async", 6, 7).cycle(*key) for key in reversed(draws)}
    assert all(0.0 <= d.compute < RANDOM_MAX and 0.0 <= d.wait < RANDOM_MAX for d in draws.values())
    assert len({d.compute for d in draws.values()}) == len(draws)
    slow = make_async("async-slowest", 6, 7)
    assert sorted(slow.rank(r) for r in range(6)) == list(range(6))
    assert {slow.cycle(r, 1).compute for r in range(6)} == {STALE_STEP * k for k in range(6)}
    assert all(slow.cycle(r, 3).wait == STALE_WAIT for r in range(6))
    assert set(ASYNC_NAMES) == {d.value for d in Delays}


def test_an_async_model_refuses_to_pick_rounds() -> None:
    with pytest.raises(NotRoundBasedError, match="no rounds"):
        make_scheduler("async", 4, 0).active(1, [0, 1, 2, 3])


def _record(tmp_path: FsPath, name: str, n: int, seed: int, **kw: Any) -> tuple[Any, Any]:
    path = tmp_path / f"{name}-{n}-{seed}.jsonl"
    with RecordWriter(path) as journal:
        result = run_lockstep(
            random_start(n, seed),
            Params(n),
            make_scheduler(name, n, seed),
            seed=seed,
            record=journal,
            **kw,
        )
    return result, read_record(path)


@pytest.mark.parametrize("name", ASYNC_NAMES)
@pytest.mark.parametrize("seed", [1, 2])
def test_the_paper_algorithm_forms_under_async_and_the_record_rebuilds_every_instant(
    name: str, seed: int, tmp_path: FsPath
) -> None:
    result, record = _record(tmp_path, name, 5, seed)
    assert (result.status, result.collisions) == ("formed", 0)
    assert record.header.scheduler == name
    assert record.result is not None and record.result.time == result.time
    cycles = []
    for entry in record.rounds:
        (robot,) = entry.active
        assert entry.extra["look"] <= entry.extra["start"] <= entry.extra["end"]
        for move in entry.moves:
            cycles.append(
                {
                    "robot": robot,
                    "start": entry.extra["start"],
                    "origin": tuple(entry.extra["origin"]),
                    "path": move.path,
                    "traveled": move.traveled,
                }
            )
    for entry in record.rounds:  # each line's positions, rebuilt at its end from the moves
        rebuilt = _positions_at(cycles, record.header.initial, entry.extra["end"])
        assert np.allclose(rebuilt, entry.positions, atol=1e-6)
    ends = [entry.extra["end"] for entry in record.rounds]
    assert ends == sorted(ends)  # one line per ended cycle, in the order they end


@pytest.mark.parametrize("name", ASYNC_NAMES)
def test_every_live_robot_looks_again_within_the_stated_bound(name: str, tmp_path: FsPath) -> None:
    _, record = _record(tmp_path, name, 6, 3)
    bound = record.header.extra["fairness_time"]
    assert bound == make_async(name, 6, 3).bound()
    last_end: dict[int, float] = {}
    for entry in sorted(record.rounds, key=lambda e: e.extra["look"]):
        (robot,) = entry.active
        if robot in last_end:
            assert entry.extra["look"] - last_end[robot] <= bound + 1e-9
        last_end[robot] = entry.extra["end"]
    assert set(last_end) == set(range(6))


def test_an_async_run_repeats_exactly_from_its_seed(tmp_path: FsPath) -> None:
    a = tmp_path / "a.jsonl"
    b = tmp_path / "b.jsonl"
    for path in (a, b):
        with RecordWriter(path) as journal:
            run_lockstep(
                random_start(6, 4), Params(6), make_scheduler("async", 6, 4), seed=4, record=journal
            )
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("name", ASYNC_NAMES)
@pytest.mark.parametrize("planner", [True, False])
def test_async_decisions_do_not_depend_on_frames_or_view_order(
    name: str, planner: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    n, seed = 6, 5
    setting = configured(Params(n))
    compute = None if planner else (lambda view, params: setting.compute(view))

    def final(flips: Callable[[int], bool]) -> tuple[int, list[list[float]]]:
        monkeypatch.setattr(frames, "draw_flip", lambda _seed, robot: flips(robot))
        result = run_lockstep(
            random_start(n, seed), setting, make_async(name, n, seed), seed=seed, compute=compute
        )
        return result.rounds, result.positions.tolist()

    base = final(lambda r: False)
    assert final(lambda r: True) == base
    assert final(lambda r: r % 2 == 1) == base
    original, originals = view_order, view_orders
    monkeypatch.setattr(looks, "view_order", lambda *a: original(*a)[::-1].copy())
    monkeypatch.setattr(looks, "view_orders", lambda *a: originals(*a)[:, ::-1].copy())
    assert final(lambda r: False) == base


def test_a_colliding_algorithm_collides_under_async_but_discs_never_overlap() -> None:
    def right(view: Any, params: Any) -> Path:
        del view, params
        return Path((Line((3.0, 0.0)),))

    start = np.array([[0.0, 0.0], [2.5, 0.3], [5.0, 0.0], [-2.2, 0.0]])
    result = run_lockstep(
        start, Params(4), make_scheduler("async", 4, 1), seed=1, compute=right, max_rounds=60
    )
    assert result.collisions > 0
    d = np.hypot(*(result.positions[:, None] - result.positions[None]).transpose(2, 0, 1))
    d[np.diag_indices(4)] = np.inf
    assert d.min() >= 2.0 - 1e-9


def test_a_crashed_robot_never_looks_again_and_the_goal_is_the_live_robots(
    tmp_path: FsPath,
) -> None:
    result, record = _record(tmp_path, "async", 6, 2, crash=1)
    ((robot, at),) = crash_plan(2, 6, 1).items()
    cycles = [e for e in record.rounds if e.active == (robot,)]
    assert len(cycles) == at - 1  # it crashed instead of its Look number `at`
    assert len(record.rounds) > 4 * at  # the others went on well past it
    assert result.status in ("formed", "stalled", "max_rounds")
    assert record.header.extra["crash"] == 1


def test_run_lockstep_async_from_the_command_line_and_its_resume_makes_the_same_bytes(
    tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.jsonl"
    code = cli.main(
        [
            "run",
            "--lockstep",
            "--scheduler",
            "async-slowest",
            "-n",
            "5",
            "--seed",
            "1",
            "--record",
            str(out),
            "-q",
        ]
    )
    assert code == 0
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert lines[0]["scheduler"] == "async-slowest"
    assert f"virtual time {lines[-1]['time']:.3f}" in capsys.readouterr().out
    assert {"look", "start", "end", "origin"} <= set(lines[1])
    capsys.readouterr()
    whole = out.read_bytes()
    out.write_text("".join(line + "\n" for line in out.read_text().splitlines()[:5]))
    assert cli.main(["run", "--lockstep", "--record", str(out), "--resume", "-q"]) == 0
    assert out.read_bytes() == whole  # replayed from its start, checked, then appended to


@pytest.mark.parametrize("name", ASYNC_NAMES)
def test_plot_and_replay_draw_each_async_move_from_where_it_started(
    name: str, tmp_path: FsPath
) -> None:
    from fatswarm.deploy.view.plot import TRAIL_STEP, trajectories
    from fatswarm.deploy.view.replay import build_frames

    _, record = _record(tmp_path, name, 6, 1)
    final = record.rounds[-1].positions
    for robot, route in enumerate(trajectories(record)):
        assert np.allclose(route[-1], final[robot], atol=1e-6)
        steps = np.hypot(*np.diff(route, axis=0).T)
        assert steps.max(initial=0.0) <= TRAIL_STEP + 1e-6  # no jump: each move from its origin
    frames = build_frames(record, source="test")
    trails = [trail for frame in frames for trail in frame.trails]
    assert trails and all(
        any(np.allclose(trail[0], e.extra["origin"], atol=1e-12) for e in record.rounds)
        for trail in trails
    )


def _async_world(n: int = 3) -> Any:
    from fatswarm.world.core import WorldCore
    from fatswarm.world.journal import load_configured
    from fatswarm.world.setup import WorldSetup

    start = np.array([[3.0 * i, 0.0] for i in range(n)])
    setup = WorldSetup("t", n, 0, "async", start, 100)
    core_ = WorldCore(setup, load_configured(setup))
    for robot in range(n):
        core_.set_alive(robot, True)
    return core_


def test_a_begin_the_world_cannot_open_yet_is_answered_with_what_is_due_and_when() -> None:
    from fatswarm.world.protocol import Begin, Commit

    world = _async_world()
    first = ((0, 5.0), (1, 1.0), (2, 9.0))
    reply, _ = world.control(Begin(1, (0,), at=5.0, looks=first))
    assert reply.ok and reply.open_round == 0  # robot 1 Looks first, at 1.0
    assert (reply.now, dict(reply.looks), reply.unset) == (1.0, dict(first), ())
    reply, _ = world.control(Begin(1, (1,), at=1.0))
    assert reply.ok and reply.open_round == 1 and world.may_look(1) and not world.may_look(0)
    refused, _ = world.control(Commit(1))
    assert not refused.ok and "delays" in refused.reason
    reply, _ = world.control(Commit(1, (1,), delays=((1, 0.5, 2.0),)))  # it stays: no move
    assert reply.ok and reply.committed == 1
    assert dict(reply.looks)[1] == 1.0 + 0.5 + 2.0  # its next Look: after compute and wait
    assert world.tracker.snapshot().rounds == 1  # one ended cycle, recorded


def test_the_async_coordinator_plans_the_first_looks_then_follows_the_world() -> None:
    from fatswarm.coordinator.async_rounds import AsyncCoordinatorCore
    from fatswarm.coordinator.rounds import Ask, Finished, RoundTimes
    from fatswarm.world.protocol import Begin, Commit, MoveSubmitted

    world = _async_world()
    model = make_async("async", 3, 0)
    coordinator = AsyncCoordinatorCore(lambda n: model, RoundTimes(), resume_live=range(3))
    for robot in range(3):
        coordinator.on_alive(robot, True, 0.0)
    actions = coordinator.start(0.0)
    begins: list[Begin] = []
    while not any(isinstance(a, Finished) for a in actions):
        (ask,) = actions
        assert isinstance(ask, Ask)
        request = ask.request
        known = dict(world.reply(True).looks)  # the Looks the world knows of
        opened = world.active
        reply, _ = world.control(request)
        if isinstance(request, Begin):
            begins.append(request)
            looks = {**known, **dict(request.looks)}
            assert request.at == min(looks.values())  # the earliest Look the world had said
        if isinstance(request, Commit):  # the adversary's delays, for the instant's robots
            assert [(r, c, w) for r, c, w in request.delays] == [
                (r, *dataclasses.astuple(model.cycle(r, 1))) for r in opened
            ]
        actions = coordinator.on_reply(reply, 0.0)
        if world.open_round:
            for robot in world.active:  # every Look answered; everyone asks to stay
                assert world.look(robot) is not None
                world.move(robot, MoveSubmitted(robot, world.open_round, Path()))
            notice = world.moves_notice()
            assert notice is not None
            actions += coordinator.on_held(notice, 0.0)
            actions = [a for a in actions if isinstance(a, (Ask, Finished))]
    assert dict(begins[0].looks) == {r: model.first_look(r) for r in range(3)}
    assert all(not b.looks for b in begins[1:])
    assert world.status == "stalled" and world.tracker.snapshot().rounds == 3
    assert len(begins) == 3  # one instant per robot: random first Looks never tie


def test_a_move_ending_at_the_instant_of_another_cycle_still_counts_as_a_change() -> None:
    # found by `fatswarm hunt` (async-slowest, offset family): robot 0's move ends at the very
    # instant robot 1 Looks again (their moves are of one length and its waits are whole), so the
    # line before robot 0's shows the same positions; counted as "wanting to move but unchanged",
    # the run was judged stalled although the goal held.
    start = np.array(
        [
            [-703732.7838699885, 389743.93924828107],
            [-703734.7838705648, 389743.9392482138],
            [-703733.7838705629, 389749.74798139185],
        ]
    )
    result = run_lockstep(start, Params(3), make_async("async-slowest", 3, 2), seed=2)
    assert (result.status, result.rounds) == ("formed", 13)


def test_the_smallest_enclosing_circle_is_right_far_from_the_origin() -> None:
    # found by `fatswarm hunt`: at 7e5 the circumcentre's rounding (1e-10) exceeded the relative
    # enclosure slack, and `sec` fell back to a circle through two points that missed the third
    from fatswarm.agent.geometry import sec

    side = 5.17960098
    triangle = np.array([[0.0, 0.0], [side, 0.0], [side / 2, side * math.sqrt(3) / 2]])
    for offset in ([0.0, 0.0], [-703733.78, 389745.26], [1.9e6, -1.9e6]):
        circle = sec(triangle + offset)
        assert circle.radius == pytest.approx(side / math.sqrt(3), rel=1e-9)
        assert np.allclose(circle.center, triangle.mean(axis=0) + offset, atol=1e-8)


def test_a_cycle_with_no_move_in_time_is_marked_timed_out() -> None:
    from fatswarm.world.effects import Committed
    from fatswarm.world.protocol import Begin, Commit

    world = _async_world()
    world.take_effects()  # the header
    world.control(Begin(1, (1,), at=1.0, looks=((0, 5.0), (1, 1.0), (2, 9.0))))
    reply, _ = world.control(Commit(1, (1,), delays=((1, 0.5, 2.0),)))  # robot 1 sent nothing
    assert reply.ok
    lines = [
        {"active": e.entry.active, **e.entry.extra}
        for e in world.take_effects()
        if isinstance(e, Committed)
    ]
    assert lines == [
        {
            "active": (1,),
            "look": 1.0,
            "start": 1.0,
            "end": 1.0,
            "origin": [3.0, 0.0],
            "timed_out": [1],
        }
    ]
    assert world.timeouts[1] == 1
