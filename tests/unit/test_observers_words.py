"""What the world tells its observers in the words a user reads: an async run's agents were last
active in a cycle (a record line), not in a coordinator's instant; the state names the robot
model, so that a dashboard can."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy.engine import lockstep
from fatswarm.domain.outcome import Status
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.wire import ProtocolError, pack, unpack
from fatswarm.world.core import WorldCore
from fatswarm.world.observers import AgentInfo, WorldState
from fatswarm.world.record_read import read_record


def test_an_async_worlds_agents_were_last_active_in_a_cycle_of_its_record(
    tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    worlds: list[WorldCore] = []
    result_of = lockstep._result

    def keep(world: WorldCore, *args: Any) -> lockstep.RunResult:
        worlds.append(world)
        return result_of(world, *args)

    monkeypatch.setattr(lockstep, "_result", keep)
    path = tmp_path / "run.jsonl"
    fatswarm.run(n=4, seed=0, scheduler="async-slowest", algorithm="gathering", record=path)
    record = read_record(str(path))
    state = worlds[0].state()
    last = [max((e.round for e in record.rounds if r in e.active), default=-1) for r in range(4)]
    assert [g.last_active for g in state.agents] == last
    assert max(last) == len(record.rounds) > worlds[0].committed  # cycles, not instants


def _state(model: RobotModel) -> WorldState:
    return WorldState(
        round=4, n=2, algorithm="gathering", params={}, figures={}, scheduler="ssync", swarm="s",
        positions=np.array([[0.0, 0.0], [3.0, 0.0]]), active=(0,), open_round=0, moved=(),
        stopped=(), collisions_total=0, status=Status.RUNNING,
        agents=(AgentInfo(True, 4, 0.0, 0), AgentInfo(True, -1, 0.0, 0)), model=model,
    )  # fmt: skip


def test_the_state_names_the_robot_model_and_sends_none_for_the_papers() -> None:
    model = RobotModel.of(visibility="opaque", sight=5.0, noise=0.25)
    assert WorldState.decode(_state(model).encode()).model == model
    plain = _state(RobotModel())
    assert "model" not in unpack(plain.encode(), "state")  # the paper's: the state as before
    assert WorldState.decode(plain.encode()).model == RobotModel()


def test_a_state_with_a_model_no_run_has_is_refused_in_one_line() -> None:
    fields = unpack(_state(RobotModel()).encode(), "state")
    bad = pack("state", {**fields, "model": {"visibility": "foggy"}})
    with pytest.raises(ProtocolError, match="'model': --visibility must be one of"):
        WorldState.decode(bad)
