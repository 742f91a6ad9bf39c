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

from fatswarm.domain.quick import quick_init
from fatswarm.world.progress import Progress
from fatswarm.world.record import Header, Result, RoundEntry


@quick_init
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


@dataclass(frozen=True, slots=True)
class Rejected:
    """An input the core refused (counted, never applied): why, in a word, and what it was. A
    shell that may be flooded counts these and says them at most every few seconds
    (`world.rejections`); others log each (`text`)."""

    reason: str  # "move-wrong-round", "look-garbage", ...
    detail: str
    total: int  # refused for this reason so far, this one included

    @property
    def text(self) -> str:
        return f"rejected ({self.reason}): {self.detail} [total {self.total}]"


Effect = Header | Committed | Result | Note | Rejected


__all__ = ["Committed", "Effect", "Level", "Note", "Rejected"]
