"""Run records: JSON Lines, one header, one line per committed round, one result line.

World frame, robots numbered by the world. The writer appends and flushes each line (optionally
fsyncs it, for the networked world's durable log); the reader (world/record_read.py) validates
every line. Robots' private frames (X flips) are never recorded.
"""

from __future__ import annotations

import functools
import json
import math
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields
from types import TracebackType
from typing import IO, Any, Final, overload

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain import figures, record_lines
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Arc, Line, Path, Points, float64_array, to_record
from fatswarm.domain.quick import quick_new
from fatswarm.domain.seam import ParamValue
from fatswarm.world.float_text import floats_text
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


class LazyMoves(Sequence[Move]):
    """A round's moves (increasing robot), each `Move` made only when one is read: the world
    builds a round line every round, and most are written (`round_text`, from what this holds)
    or handed on without anyone reading their moves. Equal to the tuple of its Moves."""

    __slots__ = ("_made",)

    def __init__(self) -> None:
        self._made: tuple[Move, ...] | None = None

    def _make(self) -> tuple[Move, ...]:
        raise NotImplementedError

    def made(self) -> tuple[Move, ...]:
        """The Moves, as a tuple (made once)."""
        if self._made is None:
            self._made = self._make()
        return self._made

    def text(self) -> str:
        """The record's JSON of the moves list (`round_text`'s), NaN or infinity included."""
        return _moves_text(self.made())

    def robots(self) -> list[int]:
        """The movers, increasing."""
        return [m.robot for m in self.made()]

    @overload
    def __getitem__(self, index: int) -> Move: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[Move, ...]: ...

    def __getitem__(self, index: int | slice) -> Move | tuple[Move, ...]:
        return self.made()[index]

    def __len__(self) -> int:
        return len(self.made())

    def __iter__(self) -> Iterator[Move]:
        return iter(self.made())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, LazyMoves):
            other = other.made()
        return isinstance(other, tuple) and self.made() == other

    __hash__ = None  # type: ignore[assignment]  # (equal to a tuple: not hashable as one)

    def __repr__(self) -> str:
        return repr(self.made())


class PathMoves(LazyMoves):
    """Moves of robots `robots` (increasing) along world-frame `paths`, having covered
    `traveled` (0 where absent): `round_entry`'s (the mappings copied: a caller may reuse
    them)."""

    __slots__ = ("_paths", "_robots", "_traveled")

    def __init__(
        self, robots: Sequence[int], paths: Mapping[int, Path], traveled: Mapping[int, float]
    ) -> None:
        super().__init__()
        self._robots, self._paths, self._traveled = list(robots), dict(paths), dict(traveled)

    def _make(self) -> tuple[Move, ...]:
        paths, get = self._paths, self._traveled.get
        return tuple(Move(r, paths[r], float(get(r, 0.0))) for r in self._robots)

    def __len__(self) -> int:
        return len(self._robots)

    def robots(self) -> list[int]:
        return list(self._robots)

    def text(self) -> str:
        if self._made is not None:
            return _moves_text(self._made)
        paths, get = self._paths, self._traveled.get
        return _moves_text_of((r, paths[r], float(get(r, 0.0))) for r in self._robots)


class LineMoves(LazyMoves):
    """The common round's moves as arrays: robot `movers[i]` (increasing, (k,) ints) went along
    one straight line from its position before the round to `ends[i]` ((k, 2) float64, world
    frame), covering `traveled[i]` ((k,) float64). Move i is exactly
    `Move(movers[i], Path((Line((ends[i, 0], ends[i, 1])),)), traveled[i])` in Python numbers.
    The arrays are kept as given, not copied: they are not to be changed after. The movers'
    order is the caller's to keep (the world core's `held_lines` sorts them): not checked here,
    where a check cost a round more than the rest of this (about 14k instructions)."""

    __slots__ = ("ends", "movers", "traveled")

    def __init__(
        self, movers: NDArray[np.integer[Any]], ends: Points, traveled: NDArray[np.float64]
    ) -> None:
        super().__init__()
        assert movers.dtype.kind in "iu", f"movers must be integers, not {movers.dtype}"
        self.movers = movers
        self.ends = float64_array(ends)
        self.traveled = float64_array(traveled)
        assert self.ends.shape == (len(movers), 2) and self.traveled.shape == (len(movers),)

    def _make(self) -> tuple[Move, ...]:
        return tuple(
            Move(r, Path((Line((x, y)),)), t)
            for r, (x, y), t in zip(
                self.movers.tolist(),
                self.ends.tolist(),
                self.traveled.tolist(),
                strict=True,
            )
        )

    def __len__(self) -> int:
        return len(self.movers)

    def robots(self) -> list[int]:
        movers: list[int] = self.movers.tolist()  # Python ints (`movers` is of integers)
        return movers

    def every(self, n: int) -> bool:
        """Whether the movers are every robot of an n-robot run, 0..n-1 (increasing: the first 0
        and the last n - 1 say it)."""
        movers = self.movers
        return len(movers) == n and (n == 0 or (movers[0] == 0 and movers[-1] == n - 1))

    def lengths(self, before: Points) -> list[float]:
        """Each move's path length from its robot's position in `before` ((n, 2)), as
        `path_length` measures its one Line (the same floats: the differences are IEEE's in
        numpy as in Python, CPython's `math.hypot` each, and `0.0 + h` is h for h >= 0)."""
        starts = np.asarray(before, dtype=np.float64)[self.movers]
        with np.errstate(over="ignore", invalid="ignore"):  # (as Python's floats: no warning)
            delta = (self.ends - starts).T.tolist()
        return list(map(math.hypot, delta[0], delta[1]))

    def text(self) -> str:
        k = len(self.movers)
        ends, traveled = floats_text(self.ends), floats_text(self.traveled)
        if ends is None or traveled is None or k == 0:  # not proven repr's: repr it is
            values: list[Any] = [None] * (4 * k)
            values[0::4] = self.movers.tolist()
            values[1::4] = self.ends[:, 0].tolist()
            values[2::4] = self.ends[:, 1].tolist()
            values[3::4] = self.traveled.tolist()
            return "[" + _repeated(_LINE_MOVE, k) % tuple(values) + "]"
        points, lengths = ends[2:-2].split("],["), traveled[1:-1].split(",")  # "x,y" and "t"s
        if self.movers[0] == 0 and self.movers[-1] == k - 1:  # every robot (movers increase)
            texts: list[Any] = [None] * (2 * k)
            texts[0::2], texts[1::2] = points, lengths
            return _every_robot_moves(k) % tuple(texts)
        texts = [None] * (3 * k)
        texts[0::3], texts[1::3], texts[2::3] = self.movers.tolist(), points, lengths
        return "[" + _repeated(_LINE_MOVE_TEXT, k) % tuple(texts) + "]"


Moves = tuple[Move, ...] | LazyMoves  # a round's moves: read as a sequence of Move


@dataclass(frozen=True, slots=True)
class RoundEntry:
    """One committed round: who was active, who moved how, positions after (n, 2), contacts;
    `extra`: the line's other fields (record_lines.ROUND_FIELDS), in the line's order.

    `derived`: the figures that follow from the positions (fatswarm.domain.figures: computed when
    asked, never written, so that every record, old ones too, has them).
    """

    round: int
    active: tuple[int, ...]
    moves: Moves  # a tuple, or made only when read (`LazyMoves`)
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
    paths: Mapping[int, Path] | LineMoves,
    covered: Mapping[int, float] | None,
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
    length each covered (0 where absent). Or, the common round (every path one straight line)
    as arrays: `paths` a `LineMoves` (movers, their lines' ends, traveled) and `covered` None;
    the entry and its line are the same as from the Paths. The other fields in the line's
    order: an async cycle's `times` (look, start, end, origin), the robot lists
    (`ROBOT_LISTS`, each written only when not empty, in the order given), then the model's
    (lights, views), then `failed` (robot -> why its compute raised, written only when some
    did). The moves are made only when read (`LazyMoves`).
    """
    extra: dict[str, Any] = dict(times) if times else {}
    for key, listed in robots:
        if len(listed):
            assert key in record_lines.ROBOT_LISTS, f"{key!r} is no robot list of the round line"
            extra[key] = list(listed)
    if model:
        extra.update(model)
    if failed:
        extra["failed"] = {str(r): text for r, text in sorted(failed.items())}
    if isinstance(paths, LineMoves):
        assert covered is None, "a LineMoves carries what each covered"
        moves: LazyMoves = paths
    else:
        moves = PathMoves(sorted(paths), paths, covered or {})
    return _new_entry(
        round=round_no,
        active=active if type(active) is tuple else tuple(active),
        moves=moves,
        positions=positions,
        collisions=tuple(collisions),
        extra=extra,
    )


_new_entry: Final = quick_new(RoundEntry)  # (built every round: no __init__ of 6 setattrs)


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


_ENCODER: Final = json.JSONEncoder(separators=(",", ":"), allow_nan=False)
"""What `json.dumps(value, separators=(",", ":"), allow_nan=False)` makes anew at every call."""


def _dumps(value: Any) -> str:
    """JSON as every record line is written: compact, ASCII, no NaN or infinity (ValueError)."""
    return _ENCODER.encode(value)


# The record's round line written piece by piece: the very text `_dumps` gives of the line as a
# dict (`round_fields`), made faster where a round has many robots. JSON writes a float as its
# `repr` and an int as its `str`, and so does `%r` (of a float) and `%d` (of an int), which
# format a whole list of numbers in one call; NaN and infinity are the only numbers whose text
# holds an `n`, and they go the dict's way, to be refused as `_dumps` refuses them.
_LINE_MOVE: Final = '{"robot":%d,"path":[{"line":[%r,%r]}],"traveled":%r}'
_LINE_MOVE_TEXT: Final = '{"robot":%d,"path":[{"line":[%s]}],"traveled":%s}'  # floats as text
_POINT: Final = "[%r,%r]"
_ROW: Final = "%r,%r"  # a point without its brackets (PointsMemo)
_ROUND_HEAD: Final = frozenset(("type", "round", "active", "moves", "positions", "collisions"))


@functools.lru_cache(maxsize=64)
def _repeated(item: str, k: int, between: str = ",") -> str:
    """`k` copies of the format `item`, `between` each two."""
    return between.join([item] * k)


@functools.lru_cache(maxsize=16)
def _every_robot_moves(k: int) -> str:
    """The format of the moves of robots 0..k-1 in order, each a straight line: their ids
    written in, each line's end and distance left as `%s`."""
    return "[" + ",".join([_LINE_MOVE_TEXT % (r, "%s", "%s") for r in range(k)]) + "]"


def _path_text(path: Path) -> str:
    """`_dumps(to_record(path))`."""
    segments = []
    for seg in path.segments:
        if isinstance(seg, Line):
            x, y = float(seg.end[0]), float(seg.end[1])
            segments.append(f'{{"line":[{x!r},{y!r}]}}')
        else:
            assert isinstance(seg, Arc)
            cx, cy, sweep = float(seg.center[0]), float(seg.center[1]), float(seg.sweep)
            segments.append(f'{{"arc":[{cx!r},{cy!r},{sweep!r}]}}')
    return "[" + ",".join(segments) + "]"


def _moves_text_of(moves: Iterable[tuple[int, Path, float]]) -> str:
    """The JSON of a round line's moves list, of (robot, path, traveled) in its order."""
    return (
        "["
        + ",".join(
            f'{{"robot":{int(r)},"path":{_path_text(p)},"traveled":{float(t)!r}}}'
            for r, p, t in moves
        )
        + "]"
    )


def _moves_text(moves: Iterable[Move]) -> str:
    return _moves_text_of((m.robot, m.path, m.traveled) for m in moves)


def _by_robot(moves: Moves) -> Sequence[Move]:
    """A line's moves in the order the record writes them: by robot, one each (the last given);
    a `LazyMoves` is so already."""
    if isinstance(moves, LazyMoves):
        return moves
    return [m for _, m in sorted({m.robot: m for m in moves}.items(), key=lambda rm: rm[0])]


def _points_text(positions: Points, memo: PointsMemo | None = None) -> str:
    """`_dumps(_positions_list(positions))` of (n, 2) positions (NaN, infinity included);
    `memo`: the text of the positions written before, of which rows equal to the bit are kept."""
    arr = np.asarray(positions, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 2:
        return _dumps(_positions_list(positions))  # refused there as before
    if memo is not None:
        return memo.text(arr)
    made = floats_text(arr)
    if made is not None:
        return made
    return "[" + _repeated(_POINT, len(arr)) % tuple(arr.ravel().tolist()) + "]"


class PointsMemo:
    """The text of the positions of the round line written last, row by row: a row whose two
    floats are the same bits (so the same `repr`) is not formatted again. A writer's: most
    rounds of ssync and async leave most robots where they were, and `repr` of a float is
    costly; where more than n / 16 rows changed, `floats_text` writes them all instead."""

    def __init__(self) -> None:
        self._bits: NDArray[np.int64] | None = None  # the positions' bits, (n, 2)
        self._inner = ""  # the text less its outer brackets: "x,y],[x,y],[..."
        self._rows: list[str] | None = None  # the same, row by row ("x,y"), once split

    def text(self, arr: Points) -> str:
        """The JSON text of the (n, 2) float64 positions `arr`."""
        n = len(arr)
        if n == 0:
            return "[]"
        bits = arr.view(np.int64) if arr.flags.c_contiguous else arr.copy().view(np.int64)
        last = self._bits
        changed = None if last is None or last.shape != bits.shape else (last != bits).any(1)
        count = n if changed is None else int(np.count_nonzero(changed))
        # orjson writes every row anew for about what `repr` takes for n / 16 of them
        made = floats_text(arr) if 16 * count > n else None
        if made is not None:
            self._inner, self._rows = made[2:-2], None  # "[[x,y],[x,y]]" less its brackets
        elif changed is None or 2 * count > n:
            self._inner, self._rows = _repeated(_ROW, n, "],[") % tuple(arr.ravel().tolist()), None
        else:
            rows = self._rows if self._rows is not None else self._inner.split("],[")
            for i in np.flatnonzero(changed).tolist():
                rows[i] = _ROW % (float(arr[i, 0]), float(arr[i, 1]))
            self._rows, self._inner = rows, "],[".join(rows)
        self._bits = bits.copy()
        return "[[" + self._inner + "]]"


def round_fields(entry: RoundEntry) -> dict[str, Any]:
    """A round line as the JSON object the record holds (its fields in the line's order)."""
    return {
        "type": "round",
        "round": int(entry.round),
        "active": [int(r) for r in entry.active],
        "moves": [
            {"robot": int(m.robot), "path": to_record(m.path), "traveled": float(m.traveled)}
            for m in _by_robot(entry.moves)
        ],
        "positions": _positions_list(entry.positions),
        "collisions": [collision_to_record(c) for c in entry.collisions],
        **entry.extra,
    }


def _active_text(active: Sequence[int]) -> str:
    """The active robots' ids, "0,1,2": one `%d` format; what it refuses (a str, say) as
    `int` reads it, as the line's dict does."""
    if type(active) is not tuple:
        active = tuple(active)
    try:
        return _repeated("%d", len(active)) % active
    except TypeError:
        return ",".join([str(int(r)) for r in active])


def round_text(entry: RoundEntry, memo: PointsMemo | None = None) -> str:
    """The round line's text in the record, without its newline: exactly `_dumps(round_fields(
    entry))` (a test holds the two together), built faster. `memo`: the positions' text of the
    line written before (a writer's `PointsMemo`). Raises ValueError for NaN or infinity,
    TypeError for a value JSON has no form of, as `json.dumps` does."""
    extra = entry.extra
    moves = entry.moves
    moved = moves.text() if isinstance(moves, LazyMoves) else _moves_text(_by_robot(moves))
    points = _points_text(entry.positions, memo)
    if not all(isinstance(key, str) for key in extra):
        raise TypeError("keywords must be strings")  # as the writer's `round(**extra)` raised
    if "n" in points or "inf" in moved or "nan" in moved or not _ROUND_HEAD.isdisjoint(extra):
        return _dumps(round_fields(entry))  # refused (NaN), or an odd line: as the dict says
    parts = [
        '{"type":"round","round":',
        str(int(entry.round)),
        ',"active":[',
        _active_text(entry.active),
        '],"moves":',
        moved,
        ',"positions":',
        points,
        ',"collisions":',
        _dumps([collision_to_record(c) for c in entry.collisions]) if entry.collisions else "[]",
    ]
    if extra:  # its keys are str (above): the dict's text less its braces is theirs in order
        parts += (",", _dumps(extra)[1:-1])
    parts.append("}")
    return "".join(parts)


def line_text(line: Header | RoundEntry | Result) -> str:
    """A record line as the record holds it (without its newline)."""
    if isinstance(line, RoundEntry):
        return round_text(line)
    out = _LineText()
    out.append(line)
    return out.text


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
        self._points = PointsMemo()  # the positions' text of the round line written last
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
        self.put(_dumps(entry))

    def put(self, text: str) -> None:
        """Append one line of JSON text (`line_text`'s, without its newline)."""
        if self._fh is None:
            raise RuntimeError(f"run record {self.path} is closed")
        line = text + "\n"
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
            self.put(round_text(line, self._points))
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


class _LineText(RecordWriter):
    """The text RecordWriter writes a line as, kept instead of written (no file)."""

    def __init__(self) -> None:  # (RecordWriter's opens the file: not called)
        self.text = ""

    def put(self, text: str) -> None:
        self.text = text


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
    "LazyMoves",
    "LineMoves",
    "Move",
    "Moves",
    "PathMoves",
    "PointsMemo",
    "RecordFormatError",
    "RecordWriter",
    "Result",
    "RoundEntry",
    "RunRecord",
    "collision_to_record",
    "line_text",
    "move_origin",
    "result_figures",
    "round_entry",
    "round_fields",
    "round_text",
]
