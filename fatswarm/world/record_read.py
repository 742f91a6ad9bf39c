"""Reading run records: every line validated against the schema (docs/record.md), in order, as
the record's own types (world/record.py); a torn last line (a crash mid-write) left out on request.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from fatswarm.domain import figures, record_lines
from fatswarm.domain.outcome import ENDED, Status
from fatswarm.domain.path import PathFormatError, Points, from_record
from fatswarm.domain.robot_model import ModelError, RobotModel
from fatswarm.world.physics import Collision
from fatswarm.world.record import (
    DEFAULT_ALGORITHM,
    VERSION,
    Header,
    Move,
    RecordFormatError,
    Result,
    RoundEntry,
    RunRecord,
    result_figures,
)


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
    algorithm, ref, params = _algorithm(entry)
    seed = entry.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise _LineError(f"'seed' must be a whole number or null, got {seed!r}")
    scheduler = entry.get("scheduler")
    if not isinstance(scheduler, str):
        raise _LineError(f"'scheduler' must be a string, got {scheduler!r}")
    initial = _points(entry.get("initial"), n, "initial")
    _model(entry)
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


def _model(entry: Mapping[str, Any]) -> None:
    """Refuse a header whose `model` this fatswarm cannot read (an axis value not among its
    choices, a key it does not know): its run cannot be drawn, replayed or resumed as the run it
    was, as a record of another version cannot."""
    if "model" not in entry:
        return
    try:
        RobotModel.from_header(entry["model"])
    except ModelError as exc:
        raise _LineError(f"unreadable robot 'model' ({exc})") from None


def _algorithm(entry: Mapping[str, Any]) -> tuple[str, str, dict[str, Any]]:
    """The header's algorithm: its name, how to load it again, and its parameters."""
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
    return algorithm, ref, params


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
    known = {f.name for f in record_lines.ROUND_FIELDS if f.required}
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
    if status not in ENDED:
        raise _LineError(f"'status' must be one of {', '.join(ENDED)}, got {status!r}")
    counted = {name: _figure(entry, name) for name in result_figures()}
    known = {f.name for f in record_lines.RESULT_HEAD} | set(counted)
    return Result(
        Status(status),
        _int(entry, "rounds", 0),
        _points(entry.get("positions"), n, "positions"),
        **counted,  # type: ignore[arg-type]
        extra=_extra(entry, known),
    )


_RESULT_FIGURES = {f.name: f for f in figures.FIGURES}


def _figure(entry: Mapping[str, Any], name: str) -> int | float | None:
    """A result line's figure as its declaration types it; None if the line has none."""
    if name not in entry:
        return None
    if _RESULT_FIGURES[name].type is int:
        return _int(entry, name, 0)
    value = _number(entry[name], f"'{name}'")
    if value < 0:
        raise _LineError(f"'{name}' must be >= 0, got {value}")
    return value


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
                entry = _json_object(line, allow_torn_end)
                if entry is None:  # a torn last line
                    if header is None:
                        raise _LineError("the header is torn (a crash mid-write)")
                    yield _TornEnd(number)
                    return
                if header is None:
                    header = _header(entry)
                    yield header
                    continue
                if finished:
                    raise _LineError("nothing may follow the result line")
                item = _after_header(entry, header.n, expected)
                if isinstance(item, RoundEntry):
                    expected = item.round + 1
                else:
                    finished = True
                yield item
        except _LineError as exc:
            raise RecordFormatError(f"{name}:{number}: {exc}") from None
        except UnicodeDecodeError:
            raise RecordFormatError(f"{name}:{number + 1}: not UTF-8 text") from None
        if header is None:
            raise RecordFormatError(f"{name}: empty run record (no header line)")


def _json_object(line: str, allow_torn_end: bool) -> dict[str, Any] | None:
    """The JSON object of one line; None if, `allow_torn_end`, it is a torn last line."""
    try:
        entry = json.loads(line)
    except json.JSONDecodeError as exc:
        if allow_torn_end and not line.endswith("\n"):  # only the last line can
            return None
        raise _LineError(f"not JSON ({exc.msg})") from None
    if not isinstance(entry, dict):
        raise _LineError("a line must be a JSON object")
    return entry


def _after_header(entry: Mapping[str, Any], n: int, expected: int | None) -> RoundEntry | Result:
    """A round line (numbered `expected`, if given) or the result line."""
    kind = entry.get("type")
    if kind == "round":
        return _round(entry, n, expected)
    if kind == "result":
        return _result(entry, n)
    raise _LineError(f"unknown line type {kind!r} (expected 'round' or 'result')")


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


__all__ = ["iter_record", "read_record", "torn_end_note"]
