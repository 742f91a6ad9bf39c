"""The run's settings (`WorldSetup`): what a run is, in one frozen type, and its one codec to and
from the record's header (`header`, `from_header`). Every run mode builds its run from it: the
lock step, the launcher and the world part, `--resume` (the recorded settings), sweep, hunt and the
Python API (through `deploy.engine.config.RunConfig.resolve`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np

from fatswarm.domain.assumptions import outside_line
from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT
from fatswarm.domain.robot_model import PAPER_MODEL, RobotModel
from fatswarm.domain.seam import Configured, ParamValue
from fatswarm.world.record import Header

# The header keys of the settings below, in the order the header writes them: how the run moves
# (`max_rounds` ... `record_views`), the note on its frames, open fields, then how it was made.
SETTINGS_KEYS: Final = ("max_rounds", "swarm", "non_rigid", "crash", "model", "record_views")
MADE_KEYS: Final = (
    "fatswarm_version",
    "start",
    "init",
    "fairness",
    "schedule",
    "move_timeout",
    "command",
)
DERIVED_KEYS: Final = ("assumption",)  # written from the settings and the algorithm, never read
KNOWN_KEYS: Final = frozenset((*SETTINGS_KEYS, *MADE_KEYS, *DERIVED_KEYS))


@dataclass(frozen=True, slots=True)
class WorldSetup:
    """The run's settings: what a run is (the first group), how it was made (the second: what the
    header keeps so that it can be repeated), and open header fields (`extra`: `fatswarm world
    --header`, or a newer writer's fields, kept as they are).

    One codec to and from the header (`header`, `from_header`): an unset setting (None, False,
    the paper's model) is a key the header leaves out, so every record reads as before.
    """

    swarm: str
    n: int
    seed: int
    scheduler: str
    initial: Points  # (n, 2)
    max_rounds: int | None
    algorithm: str = DEFAULT  # how every process loads it: a name or module:attribute
    params: Mapping[str, ParamValue] = field(default_factory=dict)  # given ones; defaults fill in
    extra: Mapping[str, Any] = field(default_factory=dict)  # open header fields, kept as they are
    non_rigid: float | None = None  # the adversary's delta (non-rigid moves); None: rigid moves
    crash: int | None = None  # f: robots the adversary crashes for good (`crash_plan`); None: 0
    robot_model: RobotModel = PAPER_MODEL  # the model's axes (docs/model.md)
    record_views: bool = False  # each record line names the robots each looker saw
    # how the run was made (the header's provenance; None: not said)
    version: str | None = None  # the fatswarm that made the run
    start: str | None = None  # the kind of its random start (drawn from the seed)
    init: str | None = None  # the start file, absolute
    fairness: int | None = None  # the round schedulers' bound K, as resolved for n
    schedule: str | None = None  # the scripted scheduler's file, absolute
    move_timeout: float | None = None  # networked: seconds a robot has to move
    command: tuple[str, ...] | None = None  # the command line

    def header(self, algorithm: Configured, initial: Points) -> Header:
        """The record's first line for this run of `algorithm` (configured) from `initial`."""
        return Header(
            self.n,
            self.seed,
            self.scheduler,
            initial,
            algorithm=algorithm.name,
            params=dict(algorithm.values),
            algorithm_ref=self.algorithm,
            extra=self.header_fields(self.outside(algorithm)),
        )

    def outside(self, algorithm: Configured) -> str:
        """The line saying how this run is outside `algorithm`'s assumptions ('' if within)."""
        return outside_assumption(algorithm, self.robot_model, self.scheduler, self.non_rigid)

    def header_fields(self, assumption: str = "") -> dict[str, Any]:
        """The header's fields beyond the start and the algorithm, in the order it writes them
        (`SETTINGS_KEYS`, the `assumption` note if any, `extra`'s (an async run's
        `fairness_time` among them: `world.instants.async_setup`), then `MADE_KEYS`)."""
        made = {
            "fatswarm_version": self.version,
            "start": self.start,
            "init": self.init,
            "fairness": self.fairness,
            "schedule": self.schedule,
            "move_timeout": self.move_timeout,
            "command": None if self.command is None else list(self.command),
        }
        return {
            "max_rounds": self.max_rounds,
            "swarm": self.swarm,
            **({} if self.non_rigid is None else {"non_rigid": self.non_rigid}),
            **({} if self.crash is None else {"crash": self.crash}),
            **({} if self.robot_model.is_paper else {"model": self.robot_model.to_header()}),
            **({"record_views": True} if self.record_views else {}),
            **({"assumption": assumption} if assumption else {}),
            **self.extra,
            **{key: value for key, value in made.items() if value is not None},
        }

    @staticmethod
    def from_header(header: Header, swarm: str, max_rounds: int | None) -> WorldSetup:
        """The settings a record's header says (the inverse of `header`); `swarm` and
        `max_rounds` where the header says none. Keys it does not know stay in `extra`; a value
        of the wrong type reads as not said. Raises ModelError for a `model` of another shape."""
        x = header.extra
        saved = x.get("max_rounds", max_rounds)
        return WorldSetup(
            swarm=swarm,
            n=header.n,
            seed=int(header.seed or 0),
            scheduler=header.scheduler,
            initial=np.asarray(header.initial, dtype=np.float64),
            max_rounds=saved if isinstance(saved, int) and _is_int(saved) else max_rounds,
            algorithm=header.algorithm_ref,
            params=dict(header.params),
            extra={k: v for k, v in x.items() if k not in KNOWN_KEYS},
            non_rigid=_number(x.get("non_rigid")),
            crash=x["crash"] if _is_int(x.get("crash")) else None,
            robot_model=RobotModel.from_header(x.get("model")),
            record_views=x.get("record_views") is True,
            version=_text(x.get("fatswarm_version")),
            start=_text(x.get("start")),
            init=_text(x.get("init")),
            fairness=x["fairness"] if _is_int(x.get("fairness")) else None,
            schedule=_text(x.get("schedule")),
            move_timeout=_number(x.get("move_timeout")),
            command=_command(x.get("command")),
        )


def setup_from_header(header: Header, swarm: str, max_rounds: int | None) -> WorldSetup:
    """The run described by a state file's header line (`WorldSetup.from_header`)."""
    return WorldSetup.from_header(header, swarm, max_rounds)


def outside_assumption(
    algorithm: Configured,
    model: RobotModel,
    scheduler: str | None = None,
    non_rigid: float | None = None,
) -> str:
    """One line if the run (its model, scheduler and moves; a scheduler of None is not checked)
    is outside what the algorithm declares it assumes (`Assumptions`), else ''."""
    outside = algorithm.assumptions.outside(model, scheduler, non_rigid)
    return outside_line(algorithm.name, outside)


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value: object) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _text(value: object) -> str | None:
    return value if isinstance(value, str) else None


def _command(value: object) -> tuple[str, ...] | None:
    if isinstance(value, list) and all(isinstance(word, str) for word in value):
        return tuple(value)
    return None


__all__ = [
    "DERIVED_KEYS",
    "KNOWN_KEYS",
    "MADE_KEYS",
    "SETTINGS_KEYS",
    "WorldSetup",
    "outside_assumption",
    "setup_from_header",
]
