"""Every robot-model axis composes with every scheduler and async policy, non-rigid moves and
crashes, in lock step: each combination runs to an end, its record validates against the schema,
names its model in the header, keeps every robot's colour on every line, and two runs of it are
the same bytes."""

from __future__ import annotations

from pathlib import Path

import pytest
from jsonschema import Draft202012Validator
from record_kinds import problems

import fatswarm
from fatswarm.domain.robot_model import RobotModel
from fatswarm.world.record_read import read_record

LIT = str(Path(__file__).resolve().parents[1] / "data" / "lit_spread.py") + ":ALGORITHM"
SCHEDULERS = ("fsync", "ssync", "centralized", "async", "async-slowest")
MODELS = {
    "sight": {"sight": 5.0},
    "opaque": {"visibility": "opaque"},
    "opaque-centres": {"visibility": "opaque-centres", "lights": "external"},
    "internal": {"lights": "internal", "frames": "chirality"},
    "disoriented-every-look": {"frames": "disoriented", "frame_change": "every-look"},
}
FAULTS = {"rigid": {}, "non-rigid": {"non_rigid": 0.5}, "crash": {"crash": 1}}


@pytest.mark.parametrize("fault", sorted(FAULTS))
@pytest.mark.parametrize("model", sorted(MODELS))
@pytest.mark.parametrize("scheduler", SCHEDULERS)
def test_a_model_axis_composes_with_every_scheduler_and_fault(
    tmp_path: Path, validator: Draft202012Validator, scheduler: str, model: str, fault: str
) -> None:
    paths = [tmp_path / "a.jsonl", tmp_path / "b.jsonl"]
    for path in paths:
        fatswarm.run(
            5,
            algorithm=LIT,
            seed=6,
            start="clustered",
            scheduler=scheduler,
            max_rounds=60,
            record=path,
            record_views=True,
            **MODELS[model],  # type: ignore[arg-type]
            **FAULTS[fault],
        )
    assert paths[0].read_bytes() == paths[1].read_bytes()
    assert problems(validator, paths[0]) == []
    run = read_record(str(paths[0]))
    assert run.result is not None and run.rounds
    wanted = RobotModel.of(**MODELS[model])  # type: ignore[arg-type]
    assert run.header.extra["model"] == wanted.to_header()
    assert all(len(entry.extra["lights"]) == 5 and "views" in entry.extra for entry in run.rounds)
