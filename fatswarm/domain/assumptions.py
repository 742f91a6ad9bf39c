"""What an algorithm's paper assumes (`Assumptions`): the robot model on every axis, the schedulers
and moves it was written for, whether it detects multiplicity and whether it knows n; and the ways
a run is outside them (`outside`). A run outside them goes ahead (that is the experiment) and says
so wherever it shows a result (docs/algorithms.md, "Assumptions").
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass, fields
from typing import Final

from fatswarm.domain.robot_model import (
    AXES,
    Axis,
    Bodies,
    FrameChange,
    Frames,
    Lights,
    ModelError,
    RobotModel,
    Value,
    Visibility,
)


class Movement(enum.StrEnum):
    """How a robot's move may end: at its destination, or cut short by the adversary."""

    RIGID = "rigid"  # every move reaches its destination (the paper's)
    NON_RIGID = "non-rigid"  # the adversary may stop a move after at least delta (`--non-rigid`)


SSYNC: Final = ("fsync", "ssync", "centralized", "scripted")
"""The round schedulers: every one an SSYNC scheduler (fsync, centralized and a script are SSYNC's
special cases); the same names as `fatswarm.coordinator.schedule.ROUND_NAMES` (a test says so)."""


@dataclass(frozen=True, slots=True)
class Assumptions:
    """What an algorithm assumes. Each field named for a model axis (`robot_model.AXES`: a test
    holds every axis to a field here) is the tuple of that axis's values the algorithm was written
    for, or None for any; `schedulers` the scheduler names (`SSYNC`, or the async models' names),
    None for any; `movement` likewise. Words are taken as the flags give them ("y-axis"); sight's
    None is unlimited.

    Undeclared: an axis an algorithm does not name is any value, but frames, whose default is
    the paper's (`y-axis`), as it was before an algorithm could declare more than its frames.

    `multiplicity` and `knows_n` are not conditions of a run but what the world gives the
    algorithm: with `multiplicity` a view shows one row per robot, so robots that share a point
    (point bodies) are repeated rows; without, each point once. With `knows_n` False the algorithm
    is not given n (`make_params` gets None).
    """

    visibility: tuple[Visibility, ...] | None = None
    sight: tuple[float | None, ...] | None = None
    lights: tuple[Lights, ...] | None = None
    frames: tuple[Frames, ...] | None = (Frames.Y_AXIS,)
    frame_change: tuple[FrameChange, ...] | None = None
    noise: tuple[float, ...] | None = None
    bodies: tuple[Bodies, ...] | None = None
    multiplicity: bool = False
    knows_n: bool = True
    schedulers: tuple[str, ...] | None = None
    movement: tuple[Movement, ...] | None = None

    def __post_init__(self) -> None:
        """Every value as its axis holds it (a member, a float or None); ModelError for one that
        is not a value of its axis, or an empty tuple (None is "any")."""
        for a in AXES:
            given = getattr(self, a.name)
            if given is not None:
                object.__setattr__(self, a.name, _values(a, given))
        if self.schedulers is not None:
            if not isinstance(self.schedulers, tuple) or not self.schedulers:
                raise ModelError(f"schedulers must be a non-empty tuple, got {self.schedulers!r}")
            if not all(isinstance(s, str) and s for s in self.schedulers):
                raise ModelError(f"schedulers must be names, got {self.schedulers!r}")
        if self.movement is not None:
            if not isinstance(self.movement, tuple) or not self.movement:
                raise ModelError(f"movement must be a non-empty tuple, got {self.movement!r}")
            try:
                moves = tuple(Movement(m) for m in self.movement)
            except ValueError:
                choices = ", ".join(m.value for m in Movement)
                raise ModelError(f"movement takes {choices}, got {self.movement!r}") from None
            object.__setattr__(self, "movement", moves)
        for flag in ("multiplicity", "knows_n"):
            if not isinstance(getattr(self, flag), bool):
                raise ModelError(f"{flag} must be True or False, got {getattr(self, flag)!r}")

    def outside(
        self, model: RobotModel, scheduler: str | None = None, non_rigid: float | None = None
    ) -> tuple[Outside, ...]:
        """The ways a run under `model`, `scheduler` (None: not checked) and `non_rigid` (None:
        rigid moves) is outside these assumptions, in declaration order; () when within them."""
        out: list[Outside] = []
        for a in AXES:
            allowed: tuple[Value, ...] | None = getattr(self, a.name)
            given = model.value(a.name)
            if allowed is not None and given not in allowed:
                out.append(Outside(a.name, _words(a.text(v) for v in allowed), a.text(given)))
        if (
            self.schedulers is not None
            and scheduler is not None
            and scheduler not in self.schedulers
        ):
            out.append(Outside("scheduler", _words(self.schedulers), scheduler))
        move = Movement.RIGID if non_rigid is None else Movement.NON_RIGID
        if self.movement is not None and move not in self.movement:
            out.append(Outside("movement", _words(self.movement), move.value))
        return tuple(out)

    def lines(self) -> tuple[str, ...]:
        """Every assumption as `name: values` (`any` for None), for `fatswarm algorithms`."""
        shown: list[str] = []
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool):
                text = "yes" if value else "no"
            elif value is None:
                text = "any"
            else:
                axis = next((a for a in AXES if a.name == f.name), None)
                text = _words(axis.text(v) if axis else str(v) for v in value)
            shown.append(f"{f.name.replace('_', ' ')}: {text}")
        return tuple(shown)


@dataclass(frozen=True, slots=True)
class Outside:
    """One way a run is outside an algorithm's assumptions: what (`frames`, `scheduler`), what the
    algorithm assumes (its values, in words) and what the run gives it."""

    what: str
    assumed: str
    given: str


def outside_line(algorithm: str, outside: Iterable[Outside]) -> str:
    """The one line a run outside its algorithm's assumptions carries ('' when within), e.g.
    `algorithm uniform-circle assumes frames y-axis; this run gives it chirality (outside its
    assumption)`: one clause per way, joined by '; '."""
    clauses = [f"assumes {o.what} {o.assumed}; this run gives it {o.given}" for o in outside]
    if not clauses:
        return ""
    return f"algorithm {algorithm} " + "; ".join(clauses) + " (outside its assumption)"


def _values(a: Axis, given: object) -> tuple[Value, ...]:
    """`given` (a non-empty tuple of values of axis `a`) as the axis holds them; ModelError."""
    if not isinstance(given, tuple) or not given:
        raise ModelError(f"{a.name} must be a non-empty tuple of values or None, got {given!r}")
    return tuple(a.check(v) for v in given)


def _words(values: Iterable[str]) -> str:
    return ", ".join(values)


PAPER_ASSUMPTIONS: Final = Assumptions(
    visibility=(Visibility.TRANSPARENT,),
    sight=(None,),
    frames=(Frames.Y_AXIS,),
    noise=(0.0,),
    bodies=(Bodies.FAT,),
    knows_n=True,
    schedulers=SSYNC,
    movement=(Movement.RIGID,),
)
"""The reference paper's (Mondal and Gan Chaudhuri): transparent unit discs seeing all, agreeing
on Y alone, exact sensors, n known, semi-synchronous and rigid (its section 2 and Theorem 1)."""


__all__ = [
    "PAPER_ASSUMPTIONS",
    "SSYNC",
    "Assumptions",
    "Movement",
    "Outside",
    "outside_line",
]
