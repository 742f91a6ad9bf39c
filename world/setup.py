"""What a run starts from: its setup, and the setup a record's header describes (to resume it)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT
from fatswarm.domain.robot_model import PAPER_MODEL, RobotModel
from fatswarm.domain.seam import ParamValue
from fatswarm.world.record import Header


@dataclass(frozen=True, slots=True)
class WorldSetup:
    """What a run starts from (or what the state file's header says when resuming)."""

    swarm: str
    n: int
    seed: int
    scheduler: str
    initial: Points  # (n, 2)
    max_rounds: int | None
    algorithm: str = DEFAULT  # how every process loads it: a name or module:attribute
    params: Mapping[str, ParamValue] = field(default_factory=dict)  # given ones; defaults fill in
    extra: Mapping[str, Any] = field(default_factory=dict)  # more header fields (how it was run)
    non_rigid: float | None = None  # the adversary's delta (non-rigid moves); None: rigid moves
    crash: int | None = None  # f: robots the adversary crashes for good (`crash_plan`); None: 0
    robot_model: RobotModel = PAPER_MODEL  # sight, obstruction, lights, frames (docs/model.md)
    record_views: bool = False  # each record line names the robots each looker saw


def header_non_rigid(header: Header) -> float | None:
    """The non-rigid adversary's delta a record's header gives (None: rigid moves)."""
    delta = header.extra.get("non_rigid")
    return float(delta) if isinstance(delta, (int, float)) else None


def header_crash(header: Header) -> int | None:
    """The crash adversary's f a record's header gives (None: no crashes)."""
    crash = header.extra.get("crash")
    return crash if isinstance(crash, int) and not isinstance(crash, bool) else None


def setup_from_header(header: Header, swarm: str, max_rounds: int | None) -> WorldSetup:
    """The run described by a state file's header line."""
    saved = header.extra.get("max_rounds", max_rounds)
    return WorldSetup(
        swarm=swarm,
        n=header.n,
        seed=int(header.seed or 0),
        scheduler=header.scheduler,
        initial=np.asarray(header.initial, dtype=np.float64),
        max_rounds=int(saved) if isinstance(saved, int) else max_rounds,
        algorithm=header.algorithm_ref,
        params=dict(header.params),
        extra={
            k: v
            for k, v in header.extra.items()
            if k not in ("max_rounds", "swarm", "non_rigid", "crash", "model", "record_views")
        },
        non_rigid=header_non_rigid(header),
        crash=header_crash(header),
        robot_model=RobotModel.from_header(header.extra.get("model")),
        record_views=header.extra.get("record_views") is True,
    )
