"""Schedulers: which robots are active in each round. Seeded, reproducible, fair.

Every scheduler tolerates a `live` set that changes between rounds (agents die and rejoin in the
networked emulator): it only ever activates live robots and forgets robots that left.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from fatswarm.domain.adversary import ASYNC_NAMES, make_async
from fatswarm.domain.draws import SCHEDULE_STREAM

SSYNC_P = 0.5  # each live robot is drawn with this probability: every subset is equally likely
ROUND_NAMES = ("fsync", "ssync", "centralized", "scripted")
NAMES = (
    *ROUND_NAMES,
    *ASYNC_NAMES,
)  # the async models have no rounds: fatswarm/domain/adversary.py
AFTER_SCRIPT = ("repeat", "fsync")  # what a script does once its rounds are used up


class ScheduleError(ValueError):
    """An unknown scheduler name or an unusable fairness bound."""


class ScheduleFileError(ScheduleError):
    """A `--schedule` file is missing or not of the documented shape."""


class Scheduler(Protocol):
    """Picks the active set of a round among the live robots."""

    @property
    def name(self) -> str: ...

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        """The sorted, non-empty active subset of `live` for round `round_no` (1-based)."""
        ...


def default_fairness(n: int) -> int:
    """Default bound K: every live robot is active at least once in every K rounds (2n, >= 2)."""
    return max(2, 2 * n)


def _live_list(live: Sequence[int]) -> list[int]:
    robots = sorted({int(r) for r in live})
    if not robots:
        raise ScheduleError("no live robot to activate")
    return robots


class _Deadlines:
    """Per-robot deadline bookkeeping: robot i must be active by round `due[i]` (fairness K)."""

    def __init__(self, fairness: int) -> None:
        self.fairness = fairness
        self.due: dict[int, int] = {}

    def sync(self, round_no: int, live: list[int]) -> None:
        """Forget robots that left; a robot that (re)joins must be active within K rounds."""
        live_set = set(live)
        if self.due.keys() == live_set:  # (nobody came or went: nothing to do)
            return
        for robot in [r for r in self.due if r not in live_set]:
            del self.due[robot]
        for robot in live:
            self.due.setdefault(robot, round_no + self.fairness - 1)

    def mark(self, round_no: int, robots: Sequence[int]) -> None:
        for robot in robots:
            self.due[robot] = round_no + self.fairness


@dataclass(slots=True)
class Fsync:
    """Fully synchronous: every live robot in every round."""

    name: str = "fsync"
    # the last live tuple and its active set (a coordinator asks with the same tuple until an
    # agent comes or goes)
    _last: tuple[tuple[int, ...], list[int]] | None = field(
        default=None, init=False, repr=False, compare=False
    )

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        del round_no
        if type(live) is not tuple:
            return _live_list(live)
        if self._last is None or self._last[0] is not live:
            self._last = (live, _live_list(live))
        return list(self._last[1])


class Ssync:
    """Semi-synchronous: a uniformly random non-empty subset of the live robots each round.

    Any subset (all robots included) can occur; a robot that was left out for K - 1 rounds is
    forced in, so every live robot is active at least once in every K rounds.
    """

    name = "ssync"

    def __init__(self, seed: int, fairness: int) -> None:
        if fairness < 1:
            raise ScheduleError(f"the fairness bound must be >= 1 round, got {fairness}")
        self.fairness = fairness
        self._rng = np.random.default_rng([SCHEDULE_STREAM, seed & 0xFFFFFFFF, 1])
        self._deadlines = _Deadlines(fairness)

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        robots = _live_list(live)
        self._deadlines.sync(round_no, robots)
        chosen: set[int] = set()
        while not chosen:  # redrawing keeps the subset uniform over the non-empty ones
            picked = self._rng.random(len(robots)) < SSYNC_P
            chosen = {r for r, p in zip(robots, picked.tolist(), strict=True) if p}
        chosen |= {r for r in robots if self._deadlines.due[r] <= round_no}
        out = sorted(chosen)
        self._deadlines.mark(round_no, out)
        return out


class Centralized:
    """One robot a round, uniformly at random among the live ones, unless that would break fairness.

    The bound is K' = max(K, number of live robots) (one activation a round cannot do better); when
    a random pick would make some deadline unmeetable, the robot with the earliest deadline goes.
    """

    name = "centralized"

    def __init__(self, seed: int, fairness: int) -> None:
        if fairness < 1:
            raise ScheduleError(f"the fairness bound must be >= 1 round, got {fairness}")
        self.fairness = fairness
        self._rng = np.random.default_rng([SCHEDULE_STREAM, seed & 0xFFFFFFFF, 2])
        self._deadlines = _Deadlines(fairness)

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        robots = _live_list(live)
        self._deadlines.fairness = max(self.fairness, len(robots))
        self._deadlines.sync(round_no, robots)
        due = self._deadlines.due
        pick = robots[int(self._rng.integers(len(robots)))]
        others = sorted(due[r] for r in robots if r != pick)
        # Unit jobs, one per round: the j-th earliest remaining deadline must be >= round_no + j.
        if any(d < round_no + j for j, d in enumerate(others, start=1)):
            pick = min(robots, key=lambda r: (due[r], r))
        self._deadlines.mark(round_no, [pick])
        return [pick]


class Scripted:
    """The active set of each round read from a file, to replay a schedule exactly.

    Round k uses entry k-1 of the script, restricted to the live robots. After the script ends it
    starts over ("repeat", the default) or activates every live robot ("fsync"). An entry naming
    no live robot activates every live robot, so a round is never empty. No fairness is enforced.
    """

    name = "scripted"

    def __init__(self, rounds: Sequence[Sequence[int]], after: str = "repeat") -> None:
        if not rounds:
            raise ScheduleError("a script needs at least one round")
        if after not in AFTER_SCRIPT:
            raise ScheduleError(f"'after' must be one of {AFTER_SCRIPT}, got {after!r}")
        self.rounds = [sorted(set(r)) for r in rounds]
        self.after = after

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        robots = _live_list(live)
        index = round_no - 1
        if index >= len(self.rounds):
            if self.after == "fsync":
                return robots
            index %= len(self.rounds)
        live_set = set(robots)
        chosen = [r for r in self.rounds[index] if r in live_set]
        return chosen or robots


def _script_from_record(path: str) -> list[Any]:
    """Active sets of a run record's committed rounds, to replay a recorded run exactly."""
    # the coordinator process imports this module but not world's record reader (which loads
    # physics): only a --schedule that is a run record needs it
    from fatswarm.world.record import RecordFormatError
    from fatswarm.world.record_read import read_record

    try:
        record = read_record(path, allow_torn_end=True)
    except RecordFormatError as exc:
        raise ScheduleFileError(f"schedule file {path}: {exc}") from None
    return [list(entry.active) for entry in record.rounds]


def load_script(path: str, n: int) -> Scripted:
    """Read `{"rounds": [[0, 2], [1], ...], "after": "repeat"|"fsync"}` (or a run record's rounds).

    Raises ScheduleFileError with a one-line message naming the file and what to fix.
    """
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except OSError as exc:
        raise ScheduleFileError(f"cannot read schedule file {path}: {exc.strerror}") from None
    rounds, after = _script_rounds(path, text)
    _check_rounds(path, rounds, n)
    return Scripted(rounds, after)


def _script_rounds(path: str, text: str) -> tuple[Any, str]:
    """The rounds a schedule file's `text` holds (unchecked), and what comes after them: the
    JSON object's, or a run record's committed rounds (then "repeat")."""
    data: Any
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        lines = text.splitlines()
        first = lines[0] if lines else ""
        if '"header"' not in first:
            raise ScheduleFileError(
                f"schedule file {path} is not JSON (line {exc.lineno}: {exc.msg})"
            ) from None
        return _script_from_record(path), "repeat"
    if not isinstance(data, dict) or "rounds" not in data:
        raise ScheduleFileError(
            f'schedule file {path} must hold an object {{"rounds": [[0, 2], [1], ...]}}'
        )
    rounds = data["rounds"]
    after = data.get("after", "repeat")
    if after not in AFTER_SCRIPT:
        raise ScheduleFileError(
            f"schedule file {path}: 'after' must be one of {AFTER_SCRIPT}, got {after!r}"
        )
    return rounds, after


def _check_rounds(path: str, rounds: Any, n: int) -> None:
    """Refuse rounds that are not a non-empty list of non-empty lists of robots 0..n-1."""
    if not isinstance(rounds, list) or not rounds:
        raise ScheduleFileError(f"schedule file {path}: 'rounds' must be a non-empty list of lists")
    for k, entry in enumerate(rounds, start=1):
        if not isinstance(entry, list) or not entry:
            raise ScheduleFileError(
                f"schedule file {path}: round {k} must be a non-empty list of robot numbers"
            )
        for robot in entry:
            if isinstance(robot, bool) or not isinstance(robot, int) or not 0 <= robot < n:
                raise ScheduleFileError(
                    f"schedule file {path}: round {k} names robot {robot!r}; robots are 0..{n - 1}"
                )


def make_scheduler(
    name: str, n: int, seed: int, schedule_path: str | None = None, fairness: int | None = None
) -> Scheduler:
    """Build 'fsync', 'ssync', 'centralized' or 'scripted' (the latter reads `schedule_path`), or
    an async model ('async', 'async-slowest': fatswarm/domain/adversary.py), which has no rounds.

    `fairness` is the bound K of ssync and centralized (default `default_fairness(n)`).
    """
    if fairness is not None and (isinstance(fairness, bool) or fairness < 1):
        raise ScheduleError(f"the fairness bound must be a whole number >= 1, got {fairness!r}")
    k = default_fairness(n) if fairness is None else int(fairness)
    if name == "fsync":
        return Fsync()
    if name == "ssync":
        return Ssync(seed, k)
    if name == "centralized":
        return Centralized(seed, k)
    if name == "scripted":
        if schedule_path is None:
            raise ScheduleError("the scripted scheduler needs a schedule file (--schedule PATH)")
        return load_script(schedule_path, n)
    if name in ASYNC_NAMES:
        return make_async(name, n, seed)
    raise ScheduleError(f"unknown scheduler {name!r}; choose one of {', '.join(NAMES)}")


__all__ = [
    "NAMES",
    "ROUND_NAMES",
    "Centralized",
    "Fsync",
    "ScheduleError",
    "ScheduleFileError",
    "Scheduler",
    "Scripted",
    "Ssync",
    "default_fairness",
    "load_script",
    "make_scheduler",
]
