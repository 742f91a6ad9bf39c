"""What the world core asks its shell to do: append a line to the run record, say something on the
log. The core queues these as it handles events; the shell takes them and performs them (write the
record, log), so the core itself touches no file and no logger.

A committed round (or an async run's ended cycle) is one shape from end to end: the record's
`RoundEntry`, with the run's figures after it (`Committed`); the journal writes the entry, the lock
step hands it to its round callback, and the record reader gives the same entries back.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from fatswarm.world.progress import Progress
from fatswarm.world.record import Header, Result, RoundEntry


@dataclass(frozen=True, slots=True)
class Committed:
    """A round committed (or, under an async model, a cycle ended): its record line and the run's
    figures right after it."""

    entry: RoundEntry
    progress: Progress


class Level(enum.IntEnum):
    """How loud a note is (the values are the `logging` module's)."""

    INFO = 20
    WARNING = 30


@dataclass(frozen=True, slots=True)
class Note:
    """A line for the world's log: a refused input, a crash, a resume, a failing hook."""

    level: Level
    text: str


Effect = Header | Committed | Result | Note


__all__ = ["Committed", "Effect", "Level", "Note"]
