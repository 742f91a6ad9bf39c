"""Run records: JSON Lines, one header, one line per committed round, one result line.

World frame, robots numbered by the world. The writer appends and flushes each line (optionally
fsyncs it, for the networked world's durable log); the reader (world/record_read.py) validates
every line. Robots' private frames (X flips) are never recorded.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from types import TracebackType
from typing import IO, Any, Final

import numpy as np

from fatswarm.domain import figures, record_lines
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Path, Points, to_record
from fatswarm.domain.seam import ParamValue
from fatswarm.world.physics import Collision

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
    """One committed round: who was active, who moved how, positions after (n, 2), contacts;
    `extra`: the line's other fields (record_lines.ROUND_FIELDS), in the line's order.

    `derived`: the figures that follow from the positions (fatswarm.domain.figures: computed when
    asked, never written, so that every record, old ones too, has them).
    """

    round: int
    active: tuple[int, ...]
    moves: tuple[Move, ...]
    positions: Points
    collisions: tuple[Collision, ...]
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def derived(self) -> dict[str, figures.FigureValue]:
        """The declared figures of this round (of the positions after it, of its line), by
        name."""
        return figures.derived(self.positions, self.round, self.extra)


def round_entry(
    round_no: int,
    active: Sequence[int],
    paths: Mapping[int, Path],
    covered: Mapping[int, float],
    positions: Points,
    collisions: Iterable[Collision] = (),
    *,
    times: Mapping[str, Any] | None = None,
    robots: Sequence[tuple[str, Sequence[int]]] = (),
    model: Mapping[str, Any] | None = None,
    failed: Mapping[int, str] | None = None,
) -> RoundEntry:
    """The one builder of a round line, for the round models and the async ones (a cycle).

    `paths`: each mover's world-frame path (a robot that stays has none); `covered`: the arc
    length each covered (0 where absent). The other fields in the line's order: an async cycle's
    `times` (look, start, end, origin), the robot lists (`ROBOT_LISTS`, each written only when
    not empty, in the order given), then the model's (lights, views), then `failed` (robot ->
    why its compute raised, written only when some did).
    """
    extra: dict[str, Any] = dict(times or {})
    for key, listed in robots:
        assert key in record_lines.ROBOT_LISTS, f"{key!r} is no robot list of the round line"
        if listed:
            extra[key] = list(listed)
    extra.update(model or {})
    if failed:
        extra["failed"] = {str(r): text for r, text in sorted(failed.items())}
    return RoundEntry(
        round_no,
        tuple(active),
        tuple(Move(r, p, float(covered.get(r, 0.0))) for r, p in sorted(paths.items())),
        positions,
        tuple(collisions),
        extra,
    )


@dataclass(frozen=True, slots=True)
class Result:
    """Last line: how the run ended, and the run's figures the world counts (those of
    fatswarm.domain.figures on the RESULT_LINE, in this class's order: the line's); None: not
    on the line (an early record's, or `time` of a round model). `extra`: unknown fields."""

    status: Status
    rounds: int
    positions: Points
    epochs: int | None = None
    moves: int | None = None
    total_distance: float | None = None
    collisions: int | None = None
    time: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def result_figures() -> tuple[str, ...]:
    """The names of `Result`'s figure fields, in the line's order."""
    head = {f.name for f in record_lines.RESULT_HEAD}
    return tuple(f.name for f in fields(Result) if f.name not in head and f.name != "extra")


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
        """The last line; `extra`: its figures (`Result`'s order) and any other field."""
        self.write(
            {
                "type": "result",
                "status": status,
                "rounds": int(rounds),
                "positions": _positions_list(positions),
                **extra,
            }
        )

    def append(self, line: Header | RoundEntry | Result) -> None:
        """Append one record line given as the record's own type (what the world core emits)."""
        if isinstance(line, Header):
            self.header(
                line.n,
                line.seed,
                line.scheduler,
                line.initial,
                algorithm=line.algorithm,
                params=line.params,
                algorithm_ref=line.algorithm_ref,
                **line.extra,
            )
        elif isinstance(line, RoundEntry):
            moves = {m.robot: (m.path, m.traveled) for m in line.moves}
            self.round(
                line.round, line.active, moves, line.positions, line.collisions, **line.extra
            )
        else:
            counted = {k: getattr(line, k) for k in result_figures()}
            kept = {k: v for k, v in counted.items() if v is not None}
            self.result(line.status, line.rounds, line.positions, **kept, **line.extra)

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
    "move_origin",
    "result_figures",
    "round_entry",
]
