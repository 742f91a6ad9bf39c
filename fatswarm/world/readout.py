"""What the shells read of the world core: its round, its positions and its progress, read only.

The shells (the Zenoh shell world/service.py, the lock step deploy/engine/lockstep.py, the journal)
send the core their commands (looks, moves, control requests, agents coming and going) and read it
through `WorldCore.readout` alone, never through its books.
"""

from __future__ import annotations

from collections.abc import KeysView
from typing import Protocol

from fatswarm.domain.frames import Frame
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points
from fatswarm.world.model import Books, Model
from fatswarm.world.progress import Progress
from fatswarm.world.setup import WorldSetup


class Readable(Books, Protocol):
    """The core's books that a readout reads (`world.core.WorldCore`), and its model of time."""

    model: Model


class CoreReadout:
    """The world core as a shell reads it: every figure read anew from the core at each call."""

    __slots__ = ("_core",)

    def __init__(self, core: Readable) -> None:
        self._core = core

    @property
    def setup(self) -> WorldSetup:
        """The run's settings as the world runs them (an async model's with its fairness bound)."""
        return self._core.setup

    @property
    def status(self) -> Status:
        return self._core.status

    @property
    def committed(self) -> int:
        """The last committed round (an async run: instant); 0 before the first."""
        return self._core.committed

    @property
    def open_round(self) -> int:
        """The open round (an async run: instant); 0 while none is open."""
        return self._core.open_round

    @property
    def active(self) -> tuple[int, ...]:
        """The robots active in the open round (else in the last committed one)."""
        return self._core.active

    @property
    def held(self) -> KeysView[int]:
        """The robots whose move of the open round the world holds."""
        return self._core.held.keys()

    @property
    def positions(self) -> Points:
        """Every robot's position now, (n, 2), world frame."""
        return self._core.positions

    def frame(self, robot: int, look_round: int) -> Frame:
        """Robot `robot`'s private frame for its Look of round `look_round`."""
        return self._core.looks.frame(robot, look_round)

    def lights(self) -> tuple[str, ...]:
        """Every robot's colour name now (() without lights)."""
        return self._core.looks.names()

    def progress(self) -> Progress:
        """The run's figures so far (`ProgressTracker.snapshot`)."""
        return self._core.tracker.snapshot()

    def time(self) -> float | None:
        """The virtual time now (async models), else None."""
        return self._core.model.time()


__all__ = ["CoreReadout", "Readable"]
