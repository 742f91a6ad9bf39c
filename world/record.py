"""Run records: JSON Lines, one header, one line per committed round, one result line.

World frame, robots numbered by the world. The writer appends and flushes each line (optionally
fsyncs it, for the networked world's durable log); the reader validates every line.
Robots' private frames (X flips) are never recorded.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import TracebackType
from typing import IO, Any, Final

import numpy as np

from fatswarm.domain.path import Path, PathFormatError, Points, from_record, to_record
from fatswarm.domain.seam import ParamValue
from fatswarm.world.physics import Collision
from fatswarm.world.progress import STATUSES

VERSION: Final = 1
DEFAULT_ALGORITHM: Final = "uniform-circle"  # what a record without an algorithm ran
DEFAULT_SCALE: Final = 4.0


class RecordFormatError(ValueError):
    """A run record file is missing, unreadable or not of the documented schema."""


class RecordWriteError(RuntimeError):
    """A line could not be written to the run record (disk full, a permission, an I/O error)."""


@dataclass(frozen=True, slots=True)
class Header:
    """First line: the run's algorithm and parameters, scheduler, seed and start positions (n, 2);
    `extra` holds the rest (round cap, fairness, move timeout, start kind, version, command)."""

    n: int
    seed: int | None
    scheduler: str
    initial: Points
    algorithm: str = DEFAULT_ALGORITHM  # its registered name
    params: dict[str, ParamValue] = field(default_factory=dict)
    algorithm_ref: str = DEFAULT_ALGORITHM  # how to load it again: a name or module:attribute
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def a(self) -> float:
        """The paper's side `a`, if the algorithm has it (random starts are drawn at its scale);
        4, the default, otherwise."""
        value = self.params.get("a", DEFAULT_SCALE)
        return float(value) if isinstance(value, (int, float)) else DEFAULT_SCALE


@dataclass(frozen=True, slots=True)
class Move:
    """One robot's world-frame path of a round and the arc length it actually covered."""

    robot: int
    path: Path
    traveled: float


@dataclass(frozen=True, slots=True)
class RoundEntry:
    """One committed round: who was active, who moved how, positions after (n, 2), contacts."""

    round: int
    active: tuple[int, ...]
    moves: tuple[Move, ...]
    positions: Points
    collisions: tuple[Collision, ...]
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class Result:
    """Last line: how the run ended."""

    status: str
    rounds: int
    positions: Points
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class RunRecord:
    """A whole record; `result` is None when the run did not finish (e.g. the world crashed).

    `torn_line`: number of a torn last line left out (read with `allow_torn_end`), else None.
    """

    header: Header
    rounds: tuple[RoundEntry, ...]
    result: Result | None
    torn_line: int | None = None


def move_origin(entry: RoundEntry, robot: int, before: Points) -> tuple[float, float]:
    """Where robot `robot`'s move of `entry` starts: the positions `before` the round, or, in an
    async run's cycle line, its `origin` (the robot's position at its Look: docs/record.md)."""
    origin = entry.extra.get("origin")
    if isinstance(origin, list) and len(origin) == 2:
        return (float(origin[0]), float(origin[1]))
    return (float(before[robot][0]), float(before[robot][1]))


def _positions_list(positions: Points) -> list[list[float]]:
    arr = np.asarray(positions, dtype=np.float64)
    return [[float(x), float(y)] for x, y in arr]


def collision_to_record(c: Collision) -> dict[str, Any]:
    """`{"robot", "other", "t", "point": [x, y]}`."""
    return {
        "robot": int(c.robot),
        "other": int(c.other),
        "t": float(c.t),
        "point": [float(c.point[0]), float(c.point[1])],
    }


class RecordWriter:
    """Writes record lines to a file, flushing each (and fsyncing it if `fsync`).

    The file is truncated unless `append` (to continue a durable log after a restart); appending
    to a file whose last line has no newline starts with one, so that no line runs into another.
    """

    def __init__(
        self, path: str | os.PathLike[str], *, fsync: bool = False, append: bool = False
    ) -> None:
        self.path = os.fspath(path)
        self.fsync = fsync
        self._newline_first = append and _ends_without_newline(self.path)
        try:
            self._fh: IO[str] | None = open(  # noqa: SIM115
                self.path, "a" if append else "w", encoding="utf-8"
            )
        except OSError as exc:
            raise RecordFormatError(
                f"cannot write run record {self.path}: {exc.strerror}"
            ) from None

    def __enter__(self) -> RecordWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def write(self, entry: Mapping[str, Any]) -> None:
        """Append one JSON object as one line."""
        if self._fh is None:
            raise RuntimeError(f"run record {self.path} is closed")
        line = json.dumps(entry, separators=(",", ":"), allow_nan=False) + "\n"
        if self._newline_first:
            line, self._newline_first = "\n" + line, False
        try:
            self._fh.write(line)
            self._fh.flush()
            if self.fsync:
                os.fsync(self._fh.fileno())
        except OSError as exc:  # what was written of the line is a torn end: resume drops it
            raise RecordWriteError(
                f"cannot write the run record {self.path}: {exc.strerror or exc}"
            ) from exc

    def header(
        self,
        n: int,
        seed: int | None,
        scheduler: str,
        initial: Points,
        *,
        algorithm: str,
        params: Mapping[str, ParamValue],
        **extra: Any,
    ) -> None:
        """The first line. `params`: every parameter of the algorithm (an `a` among them is also
        written at the top level, where records before the algorithm seam had it)."""
        top = {"a": float(params["a"])} if isinstance(params.get("a"), (int, float)) else {}
        self.write(
            {
                "type": "header",
                "version": VERSION,
                "n": int(n),
                **top,
                "seed": seed,
                "scheduler": scheduler,
                "initial": _positions_list(initial),
                "algorithm": algorithm,
                "params": dict(params),
                **extra,
            }
        )

    def round(
        self,
        round_no: int,
        active: Sequence[int],
        moves: Mapping[int, tuple[Path, float]],
        positions: Points,
        collisions: Sequence[Collision] = (),
        **extra: Any,
    ) -> None:
        """`moves`: robot -> (world-frame path, arc length covered), movers with non-empty paths."""
        self.write(
            {
                "type": "round",
                "round": int(round_no),
                "active": [int(r) for r in active],
                "moves": [
                    {"robot": int(r), "path": to_record(p), "traveled": float(t)}
                    for r, (p, t) in sorted(moves.items())
                ],
                "positions": _positions_list(positions),
                "collisions": [collision_to_record(c) for c in collisions],
                **extra,
            }
        )

    def result(self, status: str, rounds: int, positions: Points, **extra: Any) -> None:
        self.write(
            {
                "type": "result",
                "status": status,
                "rounds": int(rounds),
                "positions": _positions_list(positions),
                **extra,
            }
        )

    def close(self) -> None:
        """Close the file; a failure to flush its last bytes is a RecordWriteError."""
        fh, self._fh = self._fh, None
        if fh is not None:
            try:
                fh.close()
            except OSError as exc:
                raise RecordWriteError(
                    f"cannot write the run record {self.path}: {exc.strerror or exc}"
                ) from exc


def _ends_without_newline(path: str) -> bool:
    """True if `path` is a non-empty file whose last byte is not a newline."""
    try:
        with open(path, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            if fh.tell() == 0:
                return False
            fh.seek(-1, os.SEEK_END)
            return fh.read(1) != b"\n"
    except OSError:
        return False  # missing: opening it for appending says what is wrong


# ---------------------------------------------------------------------------------------------
# Reading


class _LineError(Exception):
    """Internal: what is wrong with one line (the reader adds file and line number)."""


def _int(entry: Mapping[str, Any], key: str, low: int = 0) -> int:
    value = entry.get(key)
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise _LineError(f"'{key}' must be a whole number >= {low}, got {value!r}")
    return value


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _LineError(f"{what} must be a finite number, got {value!r}")
    return float(value)


def _points(value: Any, n: int, what: str) -> Points:
    if not isinstance(value, list) or len(value) != n:
        raise _LineError(f"'{what}' must be a list of {n} [x, y] pairs")
    out = np.empty((n, 2), dtype=np.float64)
    for i, pair in enumerate(value):
        if not isinstance(pair, list) or len(pair) != 2:
            raise _LineError(f"'{what}'[{i}] must be an [x, y] pair, got {pair!r}")
        out[i, 0] = _number(pair[0], f"'{what}'[{i}]")
        out[i, 1] = _number(pair[1], f"'{what}'[{i}]")
    return out


def _robot(value: Any, n: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < n:
        raise _LineError(f"{what} must be a robot number in 0..{n - 1}, got {value!r}")
    return value


def _extra(entry: Mapping[str, Any], known: set[str]) -> dict[str, Any]:
    return {k: v for k, v in entry.items() if k not in known}


def _header(entry: Mapping[str, Any]) -> Header:
    if entry.get("type") != "header":
        raise _LineError(f"the first line must be the header, got type {entry.get('type')!r}")
    if entry.get("version") != VERSION:
        raise _LineError(f"unsupported record version {entry.get('version')!r} (expected 1)")
    n = _int(entry, "n", 1)
    algorithm = entry.get("algorithm", DEFAULT_ALGORITHM)
    if not isinstance(algorithm, str) or not algorithm:
        raise _LineError(f"'algorithm' must be a name, got {algorithm!r}")
    ref = entry.get("algorithm_ref", algorithm)
    if not isinstance(ref, str) or not ref:
        raise _LineError(f"'algorithm_ref' must be a name or module:attribute, got {ref!r}")
    if "params" in entry:
        params = entry["params"]
        if not isinstance(params, dict) or not all(
            isinstance(k, str) and isinstance(v, (bool, int, float, str)) for k, v in params.items()
        ):
            raise _LineError(f"'params' must map names to numbers or texts, got {params!r}")
    else:  # a record from before the algorithm seam: the paper's algorithm and its side a
        params = {"a": _number(entry.get("a"), "'a'")}
    seed = entry.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise _LineError(f"'seed' must be a whole number or null, got {seed!r}")
    scheduler = entry.get("scheduler")
    if not isinstance(scheduler, str):
        raise _LineError(f"'scheduler' must be a string, got {scheduler!r}")
    initial = _points(entry.get("initial"), n, "initial")
    known = {
        "type",
        "version",
        "n",
        "a",
        "seed",
        "scheduler",
        "initial",
        "algorithm",
        "algorithm_ref",
        "params",
    }
    return Header(n, seed, scheduler, initial, algorithm, dict(params), ref, _extra(entry, known))


def _collision(value: Any, n: int) -> Collision:
    if not isinstance(value, dict):
        raise _LineError(f"a collision must be an object, got {value!r}")
    point = value.get("point")
    if not isinstance(point, list) or len(point) != 2:
        raise _LineError(f"a collision's 'point' must be [x, y], got {point!r}")
    return Collision(
        robot=_robot(value.get("robot"), n, "a collision's 'robot'"),
        other=_robot(value.get("other"), n, "a collision's 'other'"),
        t=_number(value.get("t"), "a collision's 't'"),
        point=(_number(point[0], "collision point x"), _number(point[1], "collision point y")),
    )


def _move(value: Any, n: int) -> Move:
    if not isinstance(value, dict):
        raise _LineError(f"a move must be an object, got {value!r}")
    try:
        path = from_record(value.get("path"))
    except PathFormatError as exc:
        raise _LineError(f"bad path: {exc}") from None
    traveled = _number(value.get("traveled"), "a move's 'traveled'")
    if traveled < 0:
        raise _LineError(f"a move's 'traveled' must be >= 0, got {traveled}")
    return Move(_robot(value.get("robot"), n, "a move's 'robot'"), path, traveled)


def _round(entry: Mapping[str, Any], n: int, expected: int | None) -> RoundEntry:
    number = _int(entry, "round", 1)
    if expected is not None and number != expected:
        raise _LineError(f"round {number} follows round {expected - 1}; rounds must be consecutive")
    active = entry.get("active")
    if not isinstance(active, list):
        raise _LineError(f"'active' must be a list of robot numbers, got {active!r}")
    moves = entry.get("moves")
    if not isinstance(moves, list):
        raise _LineError(f"'moves' must be a list, got {moves!r}")
    collisions = entry.get("collisions", [])
    if not isinstance(collisions, list):
        raise _LineError(f"'collisions' must be a list, got {collisions!r}")
    known = {"type", "round", "active", "moves", "positions", "collisions"}
    return RoundEntry(
        round=number,
        active=tuple(_robot(r, n, "an 'active' entry") for r in active),
        moves=tuple(_move(m, n) for m in moves),
        positions=_points(entry.get("positions"), n, "positions"),
        collisions=tuple(_collision(c, n) for c in collisions),
        extra=_extra(entry, known),
    )


def _result(entry: Mapping[str, Any], n: int) -> Result:
    status = entry.get("status")
    if status not in STATUSES:
        raise _LineError(f"'status' must be one of {', '.join(STATUSES)}, got {status!r}")
    known = {"type", "status", "rounds", "positions"}
    return Result(
        str(status),
        _int(entry, "rounds", 0),
        _points(entry.get("positions"), n, "positions"),
        _extra(entry, known),
    )


Entry = Header | RoundEntry | Result


@dataclass(frozen=True, slots=True)
class _TornEnd:
    """Internal: the last line was torn (no newline, not JSON) and left out; its number."""

    line: int


def iter_record(path: str | os.PathLike[str], *, allow_torn_end: bool = False) -> Iterator[Entry]:
    """Validated entries of a record, one per line, in order (for streaming large records).

    Raises RecordFormatError("<file>:<line>: <reason>") at the first malformed line. With
    `allow_torn_end`, a torn last line (a crash mid-write: no newline, not JSON) is left out.
    """
    for entry in _entries(path, allow_torn_end):
        if not isinstance(entry, _TornEnd):
            yield entry


def _entries(path: str | os.PathLike[str], allow_torn_end: bool) -> Iterator[Entry | _TornEnd]:
    """iter_record's entries, then a _TornEnd if a torn last line was left out."""
    name = os.fspath(path)
    try:
        fh = open(name, encoding="utf-8")  # noqa: SIM115
    except OSError as exc:
        raise RecordFormatError(f"cannot read run record {name}: {exc.strerror}") from None
    with fh:
        header: Header | None = None
        finished = False
        expected: int | None = None
        number = 0
        try:
            for number, line in enumerate(fh, start=1):
                if not line.strip():
                    continue
                try:
                    entry = json.loads(line)
                except json.JSONDecodeError as exc:
                    if allow_torn_end and not line.endswith("\n"):  # only the last line can
                        if header is None:
                            raise _LineError("the header is torn (a crash mid-write)") from None
                        yield _TornEnd(number)
                        return
                    raise _LineError(f"not JSON ({exc.msg})") from None
                if not isinstance(entry, dict):
                    raise _LineError("a line must be a JSON object")
                if header is None:
                    header = _header(entry)
                    yield header
                    continue
                if finished:
                    raise _LineError("nothing may follow the result line")
                kind = entry.get("type")
                if kind == "round":
                    item = _round(entry, header.n, expected)
                    expected = item.round + 1
                    yield item
                elif kind == "result":
                    finished = True
                    yield _result(entry, header.n)
                else:
                    raise _LineError(f"unknown line type {kind!r} (expected 'round' or 'result')")
        except _LineError as exc:
            raise RecordFormatError(f"{name}:{number}: {exc}") from None
        except UnicodeDecodeError:
            raise RecordFormatError(f"{name}:{number + 1}: not UTF-8 text") from None
        if header is None:
            raise RecordFormatError(f"{name}: empty run record (no header line)")


def read_record(path: str | os.PathLike[str], *, allow_torn_end: bool = False) -> RunRecord:
    """The whole record, validated; raises RecordFormatError naming the file, line and reason.

    With `allow_torn_end`, a torn last line is left out and its number kept in `torn_line`.
    """
    entries = iter(_entries(path, allow_torn_end))
    header = next(entries)
    assert isinstance(header, Header)
    rounds: list[RoundEntry] = []
    result: Result | None = None
    torn_line: int | None = None
    for entry in entries:
        if isinstance(entry, RoundEntry):
            rounds.append(entry)
        elif isinstance(entry, Result):
            result = entry
        elif isinstance(entry, _TornEnd):
            torn_line = entry.line
    return RunRecord(header, tuple(rounds), result, torn_line)


def torn_end_note(path: str | os.PathLike[str], record: RunRecord) -> str | None:
    """One line telling that the record's torn last line was left out, or None if it had none."""
    if record.torn_line is None:
        return None
    count = len(record.rounds)
    shown = f"the {count} complete round{'s' if count != 1 else ''}" if count else "the start only"
    return (
        f"note: {os.fspath(path)} ends with a torn line (line {record.torn_line}, a crash "
        f"mid-write); showing {shown}"
    )


__all__ = [
    "VERSION",
    "Header",
    "Move",
    "RecordFormatError",
    "RecordWriter",
    "Result",
    "RoundEntry",
    "RunRecord",
    "collision_to_record",
    "iter_record",
    "move_origin",
    "read_record",
    "torn_end_note",
]
