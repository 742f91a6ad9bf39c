"""A round's active set is one tuple from the coordinator's plan to the world's moves notice while
the set stays the same (fsync's whole run): the lock step's checks compare it by identity, and
the lines held at once keep the world's rows of it, read only. The same answers as before, where
another tuple of the same robots comes (a networked world decodes a new one every round)."""

from __future__ import annotations

import numpy as np

from fatswarm.agent.gathering import ALGORITHM as GATHERING
from fatswarm.coordinator.rounds import Ask, CoordinatorCore, RoundTimes
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.domain.outcome import Status
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.world.core import WorldCore
from fatswarm.world.protocol import Begin, Commit, ControlReply, MovesHeld
from fatswarm.world.setup import WorldSetup

N = 5


def _world() -> WorldCore:
    start = np.array([[4.0 * i, 0.0] for i in range(N)])
    setup = WorldSetup(
        "t", N, 3, "fsync", start, 50, "gathering", robot_model=RobotModel.of(frames="disoriented")
    )
    world = WorldCore(setup, Configured.of(GATHERING, N))
    world.take_effects()
    return world


def _all_lines(world: WorldCore, round_no: int) -> None:
    """Every active robot Looks and holds a line at once, as a lock step's round hook does."""
    assert world.admit_looks(world.active) == [True] * N
    world.hold_lines(world.active, round_no, np.full((N, 2), 0.5))


def test_the_world_keeps_its_active_tuple_for_an_equal_set_and_takes_a_new_set() -> None:
    world = _world()
    assert world.control(Begin(1, tuple(range(N))))[0].ok
    first = world.active
    _all_lines(world, 1)
    notice = world.moves_notice()
    assert notice is not None and notice.robots is first  # every one held: the tuple itself
    robots, _ = world.held_lines() or (None, None)
    assert robots is not None and robots.tolist() == list(range(N))
    assert not robots.flags.writeable  # kept for the next rounds: nobody may write it
    # an equal set in another tuple (as decoded off the wire): the world's own is kept
    assert world.control(Commit(1, then_active=tuple(list(range(N)))))[0].ok
    assert world.active is first and world.open_round == 2
    # another set: taken, and its own rows made
    assert world.control(Commit(2, then_active=(0, 2, 4)))[0].ok
    assert world.active == (0, 2, 4) and world.active_set == frozenset((0, 2, 4))
    assert world.admit_looks(world.active) == [True] * 3
    world.hold_lines(world.active, 3, np.full((3, 2), 0.5))
    robots, _ = world.held_lines() or (None, None)
    assert robots is not None and robots.tolist() == [0, 2, 4]
    notice = world.moves_notice()
    assert notice is not None and notice.robots == (0, 2, 4)


def test_a_commit_whose_next_set_names_no_robot_of_the_run_is_refused_even_after_one_passed() -> (
    None
):
    world = _world()
    assert world.control(Begin(1, tuple(range(N))))[0].ok
    assert world.control(Commit(1, then_active=tuple(range(N))))[0].ok  # checked, and kept
    reply, changed = world.control(Commit(2, then_active=(0, N)))
    assert not reply.ok and not changed and world.open_round == 2  # refused whole


def test_the_coordinator_plans_an_unchanged_set_as_the_very_tuple_it_opened() -> None:
    core = CoordinatorCore(lambda n: make_scheduler("fsync", n, 0), RoundTimes())
    for robot in range(N):
        core.on_alive(robot, True, 0.0)
    (hello,) = core.start(0.0)
    assert isinstance(hello, Ask)
    (begin,) = core.on_reply(ControlReply(True, "", N, 0, 0, Status.RUNNING), 0.0)
    assert isinstance(begin, Ask) and isinstance(begin.request, Begin)
    active = begin.request.active
    assert core.on_reply(ControlReply(True, "", N, 0, 1, Status.RUNNING), 0.0) == []
    for round_no in (1, 2, 3):
        (commit,) = core.on_held(MovesHeld(round_no, active), 0.0)
        assert isinstance(commit, Ask) and isinstance(commit.request, Commit)
        assert commit.request.timed_out == () and commit.request.then_active is active
        reply = ControlReply(True, "", N, round_no, round_no + 1, Status.RUNNING)
        assert core.on_reply(reply, 0.0) == []  # the next round open: its moves awaited
        assert core.active is active and core.round == round_no + 1
    # a notice in another tuple of the same robots (a networked world's) counts the same
    (commit,) = core.on_held(MovesHeld(4, tuple(list(active))), 0.0)
    assert isinstance(commit, Ask) and isinstance(commit.request, Commit)
    assert commit.request.timed_out == ()
