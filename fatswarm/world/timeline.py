"""Where every robot is at any time of a recorded run: t in rounds, or virtual time (async).

Pure: a `RunRecord` in, (n, 2) world-frame positions out (docs/record.md, "Where a robot is at
time t within a round" and "Async runs"). `Timeline(record)` precomputes once; `.at(t)` is cheap.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from numbers import Real

import numpy as np

from fatswarm.domain.adversary import ASYNC_NAMES
from fatswarm.domain.path import Path, Point, Points, point_at
from fatswarm.world.record import Move, RoundEntry, RunRecord, move_origin


@dataclass(frozen=True, slots=True)
class Travel:
    """One recorded move, placed in time: from `origin` along `path` at unit speed, starting at
    timeline time `start`, for arc length `traveled`, then at `stop` (the line's grid-snapped
    position), at the latest from `done` (the line's end) on. `rate`: arc length per unit of
    timeline time (rounds: the round's duration; async: 1)."""

    robot: int
    start: float
    done: float
    rate: float
    origin: Point
    path: Path
    traveled: float
    stop: Point

    def where(self, t: float) -> Point:
        """The robot's centre at timeline time t >= start."""
        s = (t - self.start) * self.rate
        return (
            self.stop
            if s >= self.traveled or t >= self.done
            else point_at(self.origin, self.path, s)
        )


@dataclass(frozen=True, slots=True)
class Contact:
    """A recorded collision placed in time: `robot` stopped against `other` at timeline time `t`,
    its centre at `point`; `line` is the record line (round number) it belongs to."""

    t: float
    robot: int
    other: int
    point: Point
    line: int


class Timeline:
    """Every robot's centre at any time of a record.

    Round-based records: t is in rounds, 0 <= t <= the number of round lines. Round k occupies
    (k - 1, k]; at t = k - 1 + f (0 < f <= 1) it has run for s = f * D_k, D_k its duration (the
    longest `traveled` of its moves, docs/record.md), and robot i is at arc length
    min(s, traveled_i) along its path from the positions before the round. At t = k (f = 1) every
    robot is at round k's recorded `positions`, bit for bit (a finished move ends at the line's
    grid-snapped position); t = 0 is the header's `initial`. Within a round robots keep their
    relative speeds (unit speed, the round's clock stretched so that its longest move fills it).

    Async records: t is virtual time, 0 <= t <= the run's end (the result's `time`, else the last
    line's `end`); robot i follows its cycle line with a move whose `start` is the latest at or
    before t, at `point_at(origin, path, min(t - start, traveled))` and, once the move is over,
    at that line's `positions[i]`; before its first move, at `initial[i]`.
    """

    def __init__(self, record: RunRecord) -> None:
        self.record = record
        self.n = record.header.n
        self.initial: Points = np.array(record.header.initial, dtype=np.float64).reshape(-1, 2)
        self.is_async = is_async(record)
        self.ends: tuple[float, ...] = _line_ends(record, self.is_async)  # line k ends at [k-1]
        self.end = _run_end(record, self.ends, self.is_async)
        self._by_round = [] if self.is_async else _round_travels(record, self.initial)
        self._travels: list[list[Travel]] = [[] for _ in range(self.n)]  # async: by robot
        if self.is_async:
            for travel in sorted(_async_travels(record, self.initial), key=lambda tr: tr.start):
                self._travels[travel.robot].append(travel)
        self._starts = [[tr.start for tr in robot] for robot in self._travels]
        self.contacts: tuple[Contact, ...] = tuple(
            sorted(_contacts(record, self.is_async, self.ends), key=lambda c: c.t)
        )

    def at(self, t: float) -> Points:
        """Every robot's centre at time t, (n, 2); ValueError for t outside [0, end]."""
        if isinstance(t, bool) or not isinstance(t, Real) or not 0.0 <= float(t) <= self.end:
            unit = "virtual time" if self.is_async else "rounds"
            raise ValueError(f"t must be a time between 0 and {self.end:g} ({unit}), got {t!r}")
        if self.is_async:
            return self._async_at(float(t))
        return self._round_at(float(t))

    def span(self, first: int, last: int) -> tuple[float, float]:
        """The times from the start of record line `first` to the end of line `last` (1-based,
        inclusive): (first - 1, last) for rounds; async, from the end of line first - 1 (0 for
        the first line) to the end of line `last`."""
        if not 1 <= first <= last <= len(self.ends):
            raise ValueError(
                f"lines {first}..{last} are not within 1..{len(self.ends)} of this record"
            )
        return (self.ends[first - 2] if first > 1 else 0.0, self.ends[last - 1])

    def lines_done(self, t: float) -> int:
        """How many record lines (rounds, or ended cycles) have ended by time t."""
        return bisect.bisect_right(self.ends, t)

    def travels(self) -> list[Travel]:
        """Every recorded move placed in time: by line (rounds), else by robot and start."""
        return [travel for line in (self._by_round or self._travels) for travel in line]

    def _round_at(self, t: float) -> Points:
        rounds = self.record.rounds
        if t == 0.0 or not rounds:
            return self.initial.copy()
        k = min(math.ceil(t), len(rounds))
        if t >= k:  # the round's end: its line, bit for bit
            return np.array(rounds[k - 1].positions, dtype=np.float64)
        out = self.initial.copy() if k == 1 else np.array(rounds[k - 2].positions, np.float64)
        for tr in self._by_round[k - 1]:
            out[tr.robot] = tr.where(t)
        return out

    def _async_at(self, t: float) -> Points:
        out = self.initial.copy()
        for robot, starts in enumerate(self._starts):
            j = bisect.bisect_right(starts, t) - 1
            if j >= 0:
                out[robot] = self._travels[robot][j].where(t)
        return out


def is_async(record: RunRecord) -> bool:
    """True for a record of an async scheduler (its lines are ended cycles, in virtual time)."""
    return record.header.scheduler in ASYNC_NAMES or any(
        "start" in rr.extra for rr in record.rounds
    )


def _line_ends(record: RunRecord, in_virtual_time: bool) -> tuple[float, ...]:
    """When each record line ends: k for round k; an async cycle line's `end`."""
    if in_virtual_time:
        return tuple(_extra_time(rr, "end") for rr in record.rounds)
    return tuple(float(k) for k in range(1, len(record.rounds) + 1))


def _run_end(record: RunRecord, ends: tuple[float, ...], in_virtual_time: bool) -> float:
    """The last time of the run: its last line's end, or an async result's `time` if later."""
    end = ends[-1] if ends else 0.0
    time = record.result.time if record.result is not None else None
    if in_virtual_time and isinstance(time, (int, float)) and math.isfinite(time):
        end = max(end, float(time))
    return end


def _round_travels(record: RunRecord, initial: Points) -> list[list[Travel]]:
    """Each round's moves, round k's starting at time k - 1 and lasting until k."""
    out: list[list[Travel]] = []
    before = initial
    for k, entry in enumerate(record.rounds, start=1):
        rate = _duration(entry) or 1.0
        out.append([_travel(entry, m, before, (k - 1.0, float(k)), rate) for m in entry.moves])
        before = np.asarray(entry.positions, dtype=np.float64)
    return out


def _async_travels(record: RunRecord, initial: Points) -> list[Travel]:
    """Every cycle's move, from its `start` at unit speed."""
    return [
        _travel(entry, m, initial, (_extra_time(entry, "start"), _extra_time(entry, "end")), 1.0)
        for entry in record.rounds
        for m in entry.moves
    ]


def _contacts(record: RunRecord, is_async: bool, ends: tuple[float, ...]) -> list[Contact]:
    """Every recorded collision at its time on the timeline."""
    out: list[Contact] = []
    for k, entry in enumerate(record.rounds, start=1):
        duration = _duration(entry)
        for c in entry.collisions:
            if is_async:
                t = _extra_time(entry, "start") + c.t
            else:
                t = k - 1.0 + (c.t / duration if duration > 0.0 else 1.0)
            point = (float(c.point[0]), float(c.point[1]))
            out.append(Contact(min(t, ends[k - 1]), c.robot, c.other, point, k))
    return out


def _duration(entry: RoundEntry) -> float:
    """A round's duration: its longest move's `traveled` (0 if nobody moved)."""
    return max((m.traveled for m in entry.moves), default=0.0)


def _extra_time(entry: RoundEntry, key: str) -> float:
    """An async cycle line's `look`, `start` or `end` (0 if missing)."""
    value = entry.extra.get(key)
    return float(value) if isinstance(value, (int, float)) else 0.0


def _travel(
    entry: RoundEntry, move: Move, before: Points, times: tuple[float, float], rate: float
) -> Travel:
    """A move placed in time: `times` is (its start, its line's end)."""
    stop = entry.positions[move.robot]
    return Travel(
        robot=move.robot,
        start=times[0],
        done=times[1],
        rate=rate,
        origin=move_origin(entry, move.robot, before),
        path=move.path,
        traveled=move.traveled,
        stop=(float(stop[0]), float(stop[1])),
    )


def positions_at(record: RunRecord, t: float) -> Points:
    """Every robot's centre (n, 2) at time t of `record`: t in rounds for round-based records
    (t = k: round k's recorded positions), virtual time for async ones (see `Timeline`).

    Builds a `Timeline` each call; to ask for many times, keep one `Timeline(record)`.
    """
    return Timeline(record).at(t)


__all__ = ["Contact", "Timeline", "Travel", "is_async", "positions_at"]
