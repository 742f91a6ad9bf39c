"""What the Python API hands back, made for notebooks: a run's result and a run record that show
as one line of text and, in Jupyter, as a picture of their final frame; a record as a DataFrame.

The picture is drawn here, in plain SVG: the dashboard's drawing (deploy/view) sits above the
engine in the import contracts, and a notebook cell wants the discs themselves, not a terminal.
"""

from __future__ import annotations

import html
import math
from collections.abc import Iterable
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from fatswarm.agent import geometry
from fatswarm.deploy.engine.lockstep import RunResult as LockstepResult
from fatswarm.domain import figures
from fatswarm.domain.path import Points
from fatswarm.domain.robot_model import PAPER_MODEL, RobotModel
from fatswarm.domain.seam import ParamValue
from fatswarm.world.record import RoundEntry
from fatswarm.world.record import RunRecord as RecordLines

if TYPE_CHECKING:
    import pandas as pd

EXTRA: Final = "notebook"  # pip install 'fatswarm[notebook]': pandas (and matplotlib, to animate)
# One row per robot and round: these, then each round's figures of fatswarm.domain.figures shown
# in a DataFrame (`columns()`; min_gap...), the same on each row of the round.
COLUMNS: Final = ("round", "robot", "x", "y", "active", "moved", "distance", "collided")
PICTURE_PX: Final = 360  # the picture's width and height in pixels, the caption below it
CAPTION_PX: Final = 40  # two lines: how the run ended, which run it was
MIN_DISC_PX: Final = 2.0  # a unit disc drawn smaller than this is enlarged (a huge circle)
IDS_UP_TO: Final = 32  # robots numbered in their discs up to this many, if the discs are large
END_FILL: Final = "#009E73"  # Okabe and Ito's bluish green (the dashboard draws robots green)
START_STROKE: Final = "#999999"
SEC_STROKE: Final = "#0072B2"


@dataclass(frozen=True, slots=True, repr=False, eq=False, kw_only=True)
class RunResult(LockstepResult):
    """How a `fatswarm.run` ended: the lock step's `RunResult` and the run it was (n, seed,
    scheduler, algorithm and its parameters, the record written). Shown as one line, and in
    Jupyter as its final frame."""

    n: int
    seed: int
    scheduler: str
    algorithm: str
    params: dict[str, ParamValue] = field(default_factory=dict)
    record: str | None = None  # where its record was written, None if it was not
    # how the run is outside its algorithm's assumptions (the header's `assumption`), '' if within
    outside: str = ""
    robot_model: RobotModel = PAPER_MODEL  # the model it enforced (its repr: `RobotModel.short`)

    @classmethod
    def of(cls, result: LockstepResult, **run: Any) -> RunResult:
        """`result` with the run's description `run` (this class's own fields)."""
        return cls(**{f.name: getattr(result, f.name) for f in fields(LockstepResult)}, **run)

    def __repr__(self) -> str:
        time = "" if self.time is None else f", time={self.time:.3f}"
        record = "" if self.record is None else f", record={self.record!r}"
        record += f", outside={self.outside!r}" if self.outside else ""
        return (
            f"RunResult(status={str(self.status)!r}, rounds={self.rounds}, n={self.n}, "
            f"seed={self.seed}, scheduler={self.scheduler!r}, algorithm={self.algorithm!r}, "
            f"model={self.robot_model.short!r}, collisions={self.collisions}, moves={self.moves}, "
            f"total_distance={self.total_distance:.3f}{time}{record})"
        )

    def _repr_svg_(self) -> str:
        """Jupyter's picture: start and end discs and the end's smallest enclosing circle."""
        caption = (
            outcome_text(str(self.status), self.rounds, self.collisions),
            run_text(self.n, self.scheduler, self.seed),
        )
        return frame_svg(self.initial, self.positions, caption)


@dataclass(frozen=True, slots=True, repr=False, eq=False, kw_only=True)
class RunRecord(RecordLines):
    """A run record as `fatswarm.read_record` gives it: the world's `RunRecord` (header, rounds,
    result), the file it was read from, one row per robot and round as a DataFrame. Shown as one
    line, and in Jupyter as its final frame."""

    path: str | None = None

    @classmethod
    def of(cls, record: RecordLines, path: str | None) -> RunRecord:
        """`record`, read from `path`."""
        return cls(
            header=record.header,
            rounds=record.rounds,
            result=record.result,
            torn_line=record.torn_line,
            path=path,
        )

    @property
    def status(self) -> str:
        """How the run ended ("formed", "stalled", "max_rounds"), "unfinished" without a result."""
        return "unfinished" if self.result is None else str(self.result.status)

    @property
    def final(self) -> Points:
        """Every robot's centre at the end of the record (n, 2): the result's, else the last
        round's, else the start."""
        if self.result is not None:
            return self.result.positions
        return self.rounds[-1].positions if self.rounds else self.header.initial

    def __repr__(self) -> str:
        h = self.header
        torn = "" if self.torn_line is None else f", torn_line={self.torn_line}"
        return (
            f"RunRecord(path={self.path!r}, n={h.n}, algorithm={h.algorithm!r}, "
            f"scheduler={h.scheduler!r}, seed={h.seed}, rounds={len(self.rounds)}, "
            f"status={self.status!r}{torn})"
        )

    def _repr_svg_(self) -> str:
        """Jupyter's picture: start and end discs and the end's smallest enclosing circle."""
        collisions = sum(len(entry.collisions) for entry in self.rounds)
        caption = (
            outcome_text(self.status, len(self.rounds), collisions),
            run_text(self.header.n, self.header.scheduler, self.header.seed),
        )
        return frame_svg(self.header.initial, self.final, caption)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per robot per round (record line; an async run's ended cycle): `round` (1,
        2, ...), `robot`, `x`, `y` (its centre after the round, world frame), `active`, `moved`
        (it asked for a non-empty path), `distance` (the arc length it covered), `collided` (it
        was stopped at contact), then the round's figures that follow from the positions
        (fatswarm.domain.figures: `min_gap`, the smallest rim-to-rim distance after the round,
        NaN for one robot). The start is `header.initial`. Needs pandas (`fatswarm[notebook]`).
        """
        try:
            import pandas as pd  # optional (fatswarm[notebook]): only this method needs it
        except ImportError:
            raise ImportError(
                f"RunRecord.to_dataframe needs pandas: pip install 'fatswarm[{EXTRA}]'"
            ) from None
        return pd.DataFrame(record_columns(self), columns=list(columns()))


def columns() -> tuple[str, ...]:
    """`to_dataframe`'s columns: COLUMNS, then the declared figures of a round it shows."""
    return COLUMNS + tuple(f.name for f in round_figures())


def round_figures() -> tuple[figures.Figure, ...]:
    return tuple(f for f in figures.derived_figures() if figures.Place.DATAFRAME in f.places)


def record_columns(record: RecordLines) -> dict[str, np.ndarray[Any, Any]]:
    """`to_dataframe`'s columns as flat arrays, round by round and robot by robot within it."""
    rounds, n = len(record.rounds), record.header.n
    active = np.zeros((rounds, n), dtype=bool)
    moved = np.zeros((rounds, n), dtype=bool)
    distance = np.zeros((rounds, n), dtype=np.float64)
    collided = np.zeros((rounds, n), dtype=bool)
    positions = np.zeros((rounds, n, 2), dtype=np.float64)
    for k, entry in enumerate(record.rounds):
        active[k, list(entry.active)] = True
        for move in entry.moves:
            moved[k, move.robot] = True
            distance[k, move.robot] = move.traveled
        collided[k, [c.robot for c in entry.collisions]] = True
        positions[k] = entry.positions
    return {
        "round": np.repeat(np.array([e.round for e in record.rounds], dtype=np.int64), n),
        "robot": np.tile(np.arange(n, dtype=np.int64), rounds),
        "x": positions[:, :, 0].ravel(),
        "y": positions[:, :, 1].ravel(),
        "active": active.ravel(),
        "moved": moved.ravel(),
        "distance": distance.ravel(),
        "collided": collided.ravel(),
        **{
            f.name: np.repeat(np.array([_nan(f, e) for e in record.rounds], dtype=_dtype(f)), n)
            for f in round_figures()
        },
    }


def _dtype(figure: figures.Figure) -> type:
    """A figure's column type: a count that always applies is int64 (failures), else float64."""
    return np.int64 if figure.type is int and not figure.optional else np.float64


def _nan(figure: figures.Figure, entry: RoundEntry) -> float:
    """A round's value of a derived figure, NaN where it does not apply (pandas' missing)."""
    value = figures.round_value(figure, entry.positions, entry.round, entry.extra)
    return math.nan if value is None else float(value)


def outcome_text(status: str, rounds: int, collisions: int) -> str:
    """`formed in 17 rounds, collision-free`, `stalled after 3 rounds, with 2 collisions`."""
    counted = f"{rounds} round{'' if rounds == 1 else 's'}"
    said = {
        "formed": f"formed in {counted}",
        "max_rounds": f"stopped at the round cap ({counted})",
    }.get(status, f"{status} after {counted}")
    if collisions == 0:
        return f"{said}, collision-free" if status == "formed" else said
    return f"{said}, with {collisions} collision{'' if collisions == 1 else 's'}"


def run_text(n: int, scheduler: str, seed: int | None) -> str:
    """`n=8 ssync seed 1`."""
    return f"n={n} {scheduler} seed {'?' if seed is None else seed}"


def frame_svg(initial: Points, final: Points, caption: tuple[str, str]) -> str:
    """An SVG picture, to scale (+Y up), of the start (grey rings) and the end (green discs,
    numbered when there is room) of a run, the end's smallest enclosing circle, and `caption`'s
    two lines under it."""
    start = np.asarray(initial, dtype=np.float64).reshape(-1, 2)
    end = np.asarray(final, dtype=np.float64).reshape(-1, 2)
    (cx, cy), rc = _enclosing_circle(end)
    both = np.vstack([start, end, [[cx - rc, cy - rc], [cx + rc, cy + rc]]])
    low, high = both.min(axis=0) - 2.0, both.max(axis=0) + 2.0  # a disc's radius and a margin
    side = float(max(high - low))
    centre = (low + high) / 2.0
    x0, y1 = float(centre[0]) - side / 2.0, float(centre[1]) + side / 2.0
    px = side / PICTURE_PX  # world units per pixel
    radius = max(1.0, MIN_DISC_PX * px)

    def at(points: Points) -> Iterable[tuple[float, float]]:  # world -> picture, +Y up
        return ((float(x) - x0, y1 - float(y)) for x, y in points)

    line = f'stroke-width="{px:.6g}"'  # one pixel, in world units (every renderer scales it)
    parts = [
        f'<circle cx="{cx - x0:.6g}" cy="{y1 - cy:.6g}" r="{rc:.6g}" fill="none" '
        f'stroke="{SEC_STROKE}" {line} stroke-dasharray="{4 * px:.6g} {3 * px:.6g}"/>'
    ]
    parts += [
        f'<circle cx="{x:.6g}" cy="{y:.6g}" r="{radius:.6g}" fill="none" '
        f'stroke="{START_STROKE}" {line}/>'
        for x, y in at(start)
    ]
    parts += [
        f'<circle cx="{x:.6g}" cy="{y:.6g}" r="{radius:.6g}" fill="{END_FILL}" '
        f'stroke="black" {line}/>'
        for x, y in at(end)
    ]
    if len(end) <= IDS_UP_TO and radius / px >= 6.0:
        parts += [
            f'<text x="{x:.6g}" y="{y:.6g}" font-size="{radius:.6g}" text-anchor="middle" '
            f'dominant-baseline="central" fill="white">{i}</text>'
            for i, (x, y) in enumerate(at(end))
        ]
    return _document(parts, side, caption)


def _document(parts: list[str], side: float, caption: tuple[str, str]) -> str:
    """The SVG document: the drawing in a square of `side` world units, the caption below."""
    height = PICTURE_PX + CAPTION_PX
    lines = "".join(
        f'<text x="{PICTURE_PX / 2:g}" y="{PICTURE_PX + 16 + 17 * k}" font-family="sans-serif" '
        f'font-size="13" text-anchor="middle">{html.escape(text)}</text>'
        for k, text in enumerate(caption)
    )
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{PICTURE_PX}" height="{height}" '
        f'viewBox="0 0 {PICTURE_PX} {height}">'
        f'<rect width="{PICTURE_PX}" height="{height}" fill="white"/>'
        f'<svg width="{PICTURE_PX}" height="{PICTURE_PX}" viewBox="0 0 {side:.6g} {side:.6g}">'
        + "".join(parts)
        + f"</svg>{lines}</svg>"
    )


def _enclosing_circle(points: Points) -> tuple[tuple[float, float], float]:
    """Centre and radius of the smallest circle enclosing the centres, computed relative to the
    first (its rounding slack is relative to its radius: far from the origin it would swamp it)."""
    if not len(points):
        return (0.0, 0.0), 0.0
    origin = points[0]
    circle = geometry.sec(points - origin)
    cx, cy = circle.center
    radius = float(circle.radius)
    return (float(cx + origin[0]), float(cy + origin[1])), radius if math.isfinite(radius) else 0.0


__all__ = ["COLUMNS", "EXTRA", "RunRecord", "RunResult", "frame_svg", "record_columns"]
