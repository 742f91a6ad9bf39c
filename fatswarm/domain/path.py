"""Paths a robot asks to follow: straight segments and circular arcs, starting at the robot.

A path has no explicit start: it starts at the robot's centre (the origin in the robot's own
frame). Arcs turn about a centre by a signed sweep (counter-clockwise positive), so their radius is
the distance from where the arc starts to its centre. The same types travel in the world frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

Points = NDArray[np.float64]  # (n, 2)
_F64 = np.dtype(np.float64)


def float64_array(values: Any) -> NDArray[np.float64]:
    """`np.asarray(values, dtype=np.float64)`: the array itself when it is one of float64 (that
    test costs less than asarray's reading of its dtype argument, on a path taken every round)."""
    if type(values) is np.ndarray and values.dtype is _F64:
        return values
    return np.asarray(values, dtype=np.float64)


Point = tuple[float, float]


class PathFormatError(ValueError):
    """A path given as data (record or message) is not of the documented shape."""


@dataclass(frozen=True, slots=True)
class Line:
    """A straight segment from the current point to `end`."""

    end: Point


@dataclass(frozen=True, slots=True)
class Arc:
    """A circular arc about `center`, turning by `sweep` radians (counter-clockwise positive)."""

    center: Point
    sweep: float


Segment = Line | Arc


@dataclass(frozen=True, slots=True)
class Path:
    """A sequence of segments starting at the robot; empty when the robot stays."""

    segments: tuple[Segment, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.segments)

    def __len__(self) -> int:
        return len(self.segments)

    def __iter__(self) -> Iterator[Segment]:
        return iter(self.segments)


STAY = Path()


@dataclass(frozen=True, slots=True, eq=False)
class StraightMoves:
    """k robots' paths of one round as arrays (what the round hook may answer, as well as k
    Paths): robot i goes in a straight line to `ends[i]` (its own frame) where `goes[i]`, and
    stays elsewhere; row i is exactly `Path((Line((float(x), float(y))),))` or STAY (`paths`)."""

    ends: Points  # (k, 2) float64
    goes: NDArray[np.bool_]  # (k,)

    def __len__(self) -> int:
        return len(self.goes)

    def paths(self) -> list[Path]:
        """The same moves as k Paths (Python floats): the per-robot form."""
        return [
            Path((Line((x, y)),)) if go else STAY
            for (x, y), go in zip(self.ends.tolist(), self.goes.tolist(), strict=True)
        ]


def _arc_end(start: Point, arc: Arc) -> Point:
    cx, cy = arc.center
    dx, dy = start[0] - cx, start[1] - cy
    c, s = math.cos(arc.sweep), math.sin(arc.sweep)
    return (cx + c * dx - s * dy, cy + s * dx + c * dy)


def segment_end(start: Point, seg: Segment) -> Point:
    """Where `seg` ends when it starts at `start`."""
    if isinstance(seg, Line):
        return seg.end
    return _arc_end(start, seg)


def segment_length(start: Point, seg: Segment) -> float:
    """Arc length of `seg` when it starts at `start`."""
    if isinstance(seg, Line):
        return math.hypot(seg.end[0] - start[0], seg.end[1] - start[1])
    radius = math.hypot(start[0] - seg.center[0], start[1] - seg.center[1])
    return radius * abs(seg.sweep)


def vertices(start: Point, path: Path) -> list[Point]:
    """The start point followed by the end point of every segment."""
    pts = [start]
    for seg in path.segments:
        pts.append(segment_end(pts[-1], seg))
    return pts


def end_point(start: Point, path: Path) -> Point:
    """Where the robot is after following the whole path."""
    return vertices(start, path)[-1]


def path_length(start: Point, path: Path) -> float:
    """Total arc length of the path."""
    total = 0.0
    here = start
    for seg in path.segments:
        total += segment_length(here, seg)
        here = segment_end(here, seg)
    return total


def point_at(start: Point, path: Path, s: float) -> Point:
    """The point reached after travelling arc length `s` along the path (clamped to its ends)."""
    here = start
    remaining = max(0.0, s)
    for seg in path.segments:
        length = segment_length(here, seg)
        if remaining <= length and length > 0.0:
            f = remaining / length
            if isinstance(seg, Line):
                return (here[0] + f * (seg.end[0] - here[0]), here[1] + f * (seg.end[1] - here[1]))
            return _arc_end(here, Arc(seg.center, seg.sweep * f))
        remaining -= length
        here = segment_end(here, seg)
    return here


def truncate(start: Point, path: Path, s: float) -> Path:
    """The prefix of the path of arc length `s` (the path a robot stopped by contact covered)."""
    out: list[Segment] = []
    here = start
    remaining = max(0.0, s)
    for seg in path.segments:
        length = segment_length(here, seg)
        if remaining >= length:
            out.append(seg)
            remaining -= length
            here = segment_end(here, seg)
            continue
        if remaining > 0.0 and length > 0.0:
            f = remaining / length
            if isinstance(seg, Line):
                out.append(Line(point_at(here, Path((seg,)), remaining)))
            else:
                out.append(Arc(seg.center, seg.sweep * f))
        break
    return Path(tuple(out))


def remainder(start: Point, path: Path, s: float) -> Path:
    """What is left of the path after arc length `s` (from where `truncate` stops): the rest of
    a move that goes on, as an asynchronous robot's does between two instants."""
    here = start
    remaining = max(0.0, s)
    for k, seg in enumerate(path.segments):
        length = segment_length(here, seg)
        if remaining < length:
            first: Segment = seg
            if isinstance(seg, Arc) and remaining > 0.0:
                first = Arc(seg.center, seg.sweep * (1.0 - remaining / length))
            return Path((first, *path.segments[k + 1 :]))
        remaining -= length
        here = segment_end(here, seg)
    return Path()


def sample(start: Point, path: Path, step: float) -> Points:
    """Points along the path no more than `step` apart in arc length, both ends included."""
    pts: list[Point] = [start]
    here = start
    for seg in path.segments:
        length = segment_length(here, seg)
        k = max(1, math.ceil(length / step))
        for i in range(1, k + 1):
            pts.append(point_at(here, Path((seg,)), length * i / k))
        here = segment_end(here, seg)
    return np.asarray(pts, dtype=np.float64)


def transform(path: Path, offset: Point, flip_x: bool) -> Path:
    """Map a path from one frame to another: mirror x if `flip_x`, then translate by `offset`.

    Mirroring reverses the turning sense, so arc sweeps change sign with the flip.
    """
    sx = -1.0 if flip_x else 1.0
    ox, oy = offset
    segs: list[Segment] = [
        Line((sx * seg.end[0] + ox, seg.end[1] + oy))
        if isinstance(seg, Line)
        else Arc((sx * seg.center[0] + ox, seg.center[1] + oy), sx * seg.sweep)
        for seg in path.segments
    ]
    return Path(tuple(segs))


def mirror(path: Path) -> Path:
    """The path seen in a frame whose X axis is flipped (x -> -x)."""
    return transform(path, (0.0, 0.0), True)


def to_record(path: Path) -> list[dict[str, list[float]]]:
    """The run-record form: `{"line": [x, y]}` or `{"arc": [cx, cy, sweep]}` per segment."""
    out: list[dict[str, list[float]]] = []
    for seg in path.segments:
        if isinstance(seg, Line):
            out.append({"line": [float(seg.end[0]), float(seg.end[1])]})
        else:
            out.append({"arc": [float(seg.center[0]), float(seg.center[1]), float(seg.sweep)]})
    return out


def _finite(values: Sequence[Any], n: int, what: str) -> list[float]:
    if not isinstance(values, (list, tuple)) or len(values) != n:
        raise PathFormatError(f"{what} must be a list of {n} numbers, got {values!r}")
    out: list[float] = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise PathFormatError(f"{what} must hold finite numbers, got {values!r}")
        out.append(float(v))
    return out


MAX_SEGMENTS = 64  # far above what the algorithm emits (at most 3); bounds hostile input


def from_record(data: Any) -> Path:
    """Parse the run-record form back into a Path; raises PathFormatError on anything else."""
    if not isinstance(data, (list, tuple)):
        raise PathFormatError(f"a path must be a list of segments, got {type(data).__name__}")
    if len(data) > MAX_SEGMENTS:
        raise PathFormatError(f"a path has at most {MAX_SEGMENTS} segments, got {len(data)}")
    segs: list[Segment] = []
    for item in data:
        if not isinstance(item, dict) or len(item) != 1:
            raise PathFormatError(f"a segment must be {{'line': ...}} or {{'arc': ...}}: {item!r}")
        ((kind, values),) = item.items()
        if kind == "line":
            x, y = _finite(values, 2, "line")
            segs.append(Line((x, y)))
        elif kind == "arc":
            cx, cy, sweep = _finite(values, 3, "arc")
            segs.append(Arc((cx, cy), sweep))
        else:
            raise PathFormatError(f"unknown segment kind {kind!r} (expected 'line' or 'arc')")
    return Path(tuple(segs))
