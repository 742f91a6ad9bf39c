"""The Python API for notebooks and scripts: run a configuration, read a record, walk its rounds.

    import fatswarm
    result = fatswarm.run(n=8, seed=1, scheduler="fsync", record="run.jsonl")
    record = fatswarm.read_record("run.jsonl")
    for rnd in record.rounds:            # each committed round; positions are (n, 2) arrays
        print(rnd.round, rnd.active, rnd.positions.mean(axis=0))

Runs here are lock-step runs (one process): the same world and coordinator cores as a networked
run, so their records are the same. `fatswarm run` is the networked emulator.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fatswarm.deploy.engine.config import DEFAULT_SCHEDULER, DEFAULT_START, RunConfig
from fatswarm.deploy.engine.lockstep import RoundReport, RunResult, run_lockstep
from fatswarm.domain.path import Points
from fatswarm.domain.robot_model import RobotModel
from fatswarm.world.record import RecordWriter, RunRecord
from fatswarm.world.record_read import read_record


def run(
    n: int | None = None,
    *,
    algorithm: str = "uniform-circle",
    params: Mapping[str, object] | None = None,
    seed: int = 0,
    start: str = DEFAULT_START,
    positions: Points | None = None,
    init: str | os.PathLike[str] | None = None,
    scheduler: str = DEFAULT_SCHEDULER,
    fairness: int | None = None,
    schedule: str | os.PathLike[str] | None = None,
    max_rounds: int | None = None,
    non_rigid: float | None = None,
    crash: int | None = None,
    visibility: str = "transparent",
    sight: float | None = None,
    lights: str = "full",
    frames: str = "y-axis",
    frame_change: str = "fixed",
    record_views: bool = False,
    record: str | os.PathLike[str] | None = None,
    on_round: Callable[[RoundReport], None] | None = None,
) -> RunResult:
    """Run one configuration in lock step and return how it ended (`RunResult`).

    The start is `positions` ((n, 2) world coordinates), else the JSON file `init`, else a random
    start of kind `start` drawn from `seed`. `record`: write the run record there (overwritten).
    `on_round` is called after every committed round. `non_rigid`: the adversary's delta (a move
    may be stopped anywhere after the robot travelled delta, drawn from `seed`); None: rigid.
    `crash`: f robots the adversary crashes for good (which and when drawn from `seed`,
    `world.core.crash_plan`; the goal is then judged on the live robots); None: no crashes.
    `visibility`, `sight`, `lights`, `frames`, `frame_change`: the robot model, as the flags of
    `fatswarm run` (docs/model.md); `record_views`: each record line names what each looker saw.
    Raises one of `fatswarm.deploy.engine.config.input_errors()` (a ValueError) for a configuration
    it refuses.
    """
    config = RunConfig(
        n=n,
        algorithm=algorithm,
        params=dict(params or {}),
        seed=seed,
        start=start,
        init=None if init is None else os.fspath(init),
        positions=None if positions is None else np.asarray(positions, dtype=np.float64),
        scheduler=scheduler,
        schedule=None if schedule is None else os.fspath(schedule),
        fairness=fairness,
        max_rounds=max_rounds,
        non_rigid=non_rigid,
        crash=crash,
        model=RobotModel.of(visibility, sight, lights, frames, frame_change),
        record_views=record_views,
    )
    return _run_config(config, record, on_round)


def _run_config(
    config: RunConfig,
    record: str | os.PathLike[str] | None,
    on_round: Callable[[RoundReport], None] | None,
) -> RunResult:
    """Resolve `config` and run it in lock step, writing its record to `record` (if not None)."""
    setup = config.resolve()
    writer = None if record is None else RecordWriter(record)
    try:
        return run_lockstep(
            setup.initial,
            setup.params,
            setup.scheduler,
            seed=setup.seed,
            max_rounds=setup.max_rounds,
            record=writer,
            on_round=on_round,
            algorithm_ref=setup.algorithm_ref,
            header_extra=config.header_extra(networked=False, n=setup.params.n),
            non_rigid=setup.non_rigid,
            crash=setup.crash,
            robot_model=setup.robot_model,
            record_views=setup.record_views,
        )
    finally:
        if writer is not None:
            writer.close()


def trajectory(record: RunRecord) -> NDArray[np.float64]:
    """Every robot's centre at the start and after each committed round: (rounds + 1, n, 2)."""
    frames = [record.header.initial, *(entry.positions for entry in record.rounds)]
    return np.stack([np.asarray(f, dtype=np.float64) for f in frames])


def moved_by_round(record: RunRecord) -> NDArray[np.bool_]:
    """(rounds, n): whether each robot asked for a move (a non-empty path) in each round."""
    out = np.zeros((len(record.rounds), record.header.n), dtype=bool)
    for k, entry in enumerate(record.rounds):
        out[k, [m.robot for m in entry.moves]] = True
    return out


def summary(result: RunResult) -> dict[str, Any]:
    """The result's figures as a plain dict (for a table or a DataFrame row)."""
    return {
        "status": result.status,
        "rounds": result.rounds,
        "epochs": result.epochs,
        "moves": result.moves,
        "total_distance": result.total_distance,
        "collisions": result.collisions,
        "looks": result.looks,
    }


__all__ = ["RunResult", "moved_by_round", "read_record", "run", "summary", "trajectory"]
