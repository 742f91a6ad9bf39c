"""What the Python API hands back, made for notebooks: a run's result and a run record that show
as one line of text and, in Jupyter, as a picture of their final frame (each robot in its light's
colour for a luminous run, the robot model named); a record as a DataFrame, the run's settings
in its `attrs`.

The picture is drawn here, in plain SVG: the dashboard's drawing (deploy/view) sits above the
engine in the import contracts, and a notebook cell wants the discs themselves, not a terminal.
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from fatswarm.agent import geometry
from fatswarm.deploy.engine.lockstep import RunResult as LockstepResult
from fatswarm.domain import figures
from fatswarm.domain.adversary import ASYNC_NAMES
from fatswarm.domain.lights import LIGHT_HEX
from fatswarm.domain.path import Points
from fatswarm.domain.robot_model import AXES, PAPER_MODEL, RobotModel
from fatswarm.domain.seam import ParamValue
from fatswarm.world.record import RoundEntry
from fatswarm.world.record import RunRecord as RecordLines
from fatswarm.world.setup import WorldSetup
from fatswarm.world.timeline import is_async

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from fatswarm.deploy.view.inline import InlineVideo

# PICTURES: the records and results draw themselves through fatswarm.deploy.view.inline, imported
# in the methods: loaded on first use (matplotlib with it), and the one reach from the engine up to
# the view (pyproject.toml's contract names it).
EXTRA: Final = "notebook"  # pip install 'fatswarm[notebook]': pandas (and matplotlib, to animate)
# One row per robot and round: these, then each round's figures of fatswarm.domain.figures shown
# in a DataFrame (`columns()`; min_gap...), the same on each row of the round, then these:
COLUMNS: Final = ("round", "robot", "x", "y", "active", "moved", "distance", "collided")
# What the robot model adds to a row: why the robot's compute failed (the round line's `failed`;
# every record), its light (a luminous run's `lights`), what it saw (`--record-views`: `views`).
FAILED: Final = "failed"
LIGHT: Final = "light"
VIEW: Final = "view"
PICTURE_PX: Final = 360  # the picture's width and height in pixels, the caption below it
LINE_PX: Final = 17  # a caption line: how the run ended, which run it was, its model, its lights
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
    palette: tuple[str, ...] = ()  # the colour names the run's lines showed, sorted (`lights`)

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

    def animate(self, **settings: Any) -> InlineVideo:
        """The run's record (written with `record=`) as a video Jupyter shows inline: the frames
        of `fatswarm plot RECORD OUT.gif`; `settings` are fps, speed, rounds, max_frames, robot,
        title (fatswarm.deploy.view.inline.animate). Needs matplotlib."""
        from fatswarm.deploy.view import inline  # PICTURES

        return inline.animate(self, **settings)

    def _repr_svg_(self) -> str:
        """Jupyter's picture: start and end discs (each in its light's colour, a luminous run's)
        and the end's smallest enclosing circle; the caption names the model."""
        cycles = self.time is not None or self.scheduler in ASYNC_NAMES
        caption = (
            outcome_text(str(self.status), self.rounds, self.collisions, cycles=cycles),
            run_text(self.n, self.scheduler, self.seed),
            model_text(self.robot_model),
        )
        fills = light_fills(self.palette, self.lights) if self.lights else None
        return frame_svg(self.initial, self.positions, caption, fills, self.palette)


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
        """Jupyter's picture: start and end discs (each in its light's colour, a luminous run's)
        and the end's smallest enclosing circle; the caption names the model."""
        collisions = sum(len(entry.collisions) for entry in self.rounds)
        names = record_palette(self)
        last = _lights(self.rounds[-1], self.header.n) if self.rounds else None
        caption = (
            outcome_text(self.status, len(self.rounds), collisions, cycles=is_async(self)),
            run_text(self.header.n, self.header.scheduler, self.header.seed),
            model_text(settings_of(self).robot_model),
        )
        fills = None if last is None else light_fills(names, last)
        return frame_svg(self.header.initial, self.final, caption, fills, names)

    def animate(self, **settings: Any) -> InlineVideo:
        """The record as a video Jupyter shows inline: the frames of `fatswarm plot RECORD
        OUT.gif`; `settings` are fps, speed, rounds, max_frames, robot, title
        (fatswarm.deploy.view.inline.animate). Needs matplotlib."""
        from fatswarm.deploy.view import inline  # PICTURES

        return inline.animate(self, **settings)

    def figure(self, round: int | None = None, **settings: Any) -> Figure:
        """A matplotlib Figure to restyle (returned, not shown): the whole run as `fatswarm plot
        RECORD OUT.png` draws it, or with `round=k` the video's frame after round k; `settings`:
        robot, title (fatswarm.deploy.view.inline.figure). Needs matplotlib."""
        from fatswarm.deploy.view import inline  # PICTURES

        return inline.figure(self, round, **settings)

    def look_figure(self, robot: int, round: int, **settings: Any) -> Figure:
        """Robot `robot`'s Look in round `round` as a matplotlib Figure (`fatswarm plot RECORD
        OUT.png --robot I --round K`; a record made with record_views=True); `settings`: title
        (fatswarm.deploy.view.inline.look_figure). Needs matplotlib."""
        from fatswarm.deploy.view import inline  # PICTURES

        return inline.look_figure(self, robot, round, **settings)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per robot per round (record line; an async run's ended cycle): `round` (1,
        2, ...), `robot`, `x`, `y` (its centre after the round, world frame), `active`, `moved`
        (it asked for a non-empty path), `distance` (the arc length it covered), `collided` (it
        was stopped at contact), then the round's figures (fatswarm.domain.figures: `min_gap`,
        the smallest rim-to-rim distance after the round, NaN for one robot; `failures`, the
        round's failed computes), then `failed`: why the robot's compute failed in the round
        (`Type: message`), None where it did not. A luminous run adds `light`, the robot's colour
        name at the line (`lights`); a run recorded with `--record-views` adds `view`, the robots
        it was shown when it Looked in the round, a tuple of robot numbers (increasing, maybe
        empty), None where it did not Look (`df.explode("view")`: one row per robot seen).
        `df.attrs` holds the run's settings (`run_attrs`): algorithm, params, scheduler, seed,
        the robot model's axes (`model`) and the rest of the header's settings. The start is
        `header.initial`. Needs pandas (`fatswarm[notebook]`).
        """
        try:
            import pandas as pd  # optional (fatswarm[notebook]): only this method needs it
        except ImportError:
            raise ImportError(
                f"RunRecord.to_dataframe needs pandas: pip install 'fatswarm[{EXTRA}]'"
            ) from None
        data = record_columns(self)
        frame = pd.DataFrame(data, columns=list(data))
        frame.attrs.update(run_attrs(self))
        return frame


def settings_of(record: RecordLines) -> WorldSetup:
    """The run's settings as its header says them (`WorldSetup.from_header`)."""
    swarm = record.header.extra.get("swarm")
    return WorldSetup.from_header(record.header, swarm if isinstance(swarm, str) else "", None)


def run_attrs(record: RecordLines) -> dict[str, Any]:
    """`to_dataframe`'s `attrs`: the run's settings (`WorldSetup`'s fields, read from the header,
    plain values) with `algorithm` the algorithm's name (`algorithm_ref`: how to load it),
    `params` every parameter's value, and `model` every axis of the robot model (`AXES`) by
    name; `initial` and the open header fields (`extra`) are left out."""
    setup = settings_of(record)
    header = record.header
    settings = {
        f.name: _plain(getattr(setup, f.name))
        for f in fields(WorldSetup)
        if f.name not in {"initial", "extra", "robot_model", "algorithm", "params"}
    }
    return {
        "algorithm": header.algorithm,
        "algorithm_ref": header.algorithm_ref,
        "params": dict(header.params),
        **settings,
        "seed": header.seed,  # None where the header says none (WorldSetup reads it as 0)
        "model": {a.name: _plain(setup.robot_model.value(a.name)) for a in AXES},
    }


def _plain(value: object) -> object:
    """A setting as JSON would hold it: a word for an enum member, a list for a tuple."""
    if isinstance(value, str):
        return str(value)
    return list(value) if isinstance(value, tuple) else value


def columns(*, lights: bool = False, views: bool = False) -> tuple[str, ...]:
    """`to_dataframe`'s columns: COLUMNS, the declared figures of a round it shows, FAILED, then
    LIGHT for a luminous run and VIEW for one recorded with its views."""
    return (
        COLUMNS
        + tuple(f.name for f in round_figures())
        + (FAILED,)
        + ((LIGHT,) if lights else ())
        + ((VIEW,) if views else ())
    )


def round_figures() -> tuple[figures.Figure, ...]:
    return tuple(f for f in figures.derived_figures() if figures.Place.DATAFRAME in f.places)


def record_columns(record: RecordLines) -> dict[str, np.ndarray[Any, Any]]:
    """`to_dataframe`'s columns (`columns()`) as flat arrays, round by round and robot by robot
    within it."""
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
        FAILED: _cells(record, _failed),
        **({LIGHT: _cells(record, _light)} if has_lights(record) else {}),
        **({VIEW: _cells(record, _view)} if has_views(record) else {}),
    }


def has_lights(record: RecordLines) -> bool:
    """Whether the record's lines name the robots' colours (a luminous run's)."""
    return any("lights" in entry.extra for entry in record.rounds)


def has_views(record: RecordLines) -> bool:
    """Whether the record says what each robot saw (`--record-views`)."""
    if record.header.extra.get("record_views") is True:
        return True
    return any("views" in entry.extra for entry in record.rounds)


def _cells(
    record: RecordLines, cell: Callable[[Mapping[str, Any], int], object]
) -> np.ndarray[Any, Any]:
    """An object column: `cell(line's fields, robot)` for each round and robot, in row order."""
    n = record.header.n
    out = np.empty(len(record.rounds) * n, dtype=object)
    out[:] = [cell(entry.extra, robot) for entry in record.rounds for robot in range(n)]
    return out


def _failed(line: Mapping[str, Any], robot: int) -> str | None:
    failed = line.get("failed")
    text: object = failed.get(str(robot)) if isinstance(failed, Mapping) else None
    return text if isinstance(text, str) else None


def _light(line: Mapping[str, Any], robot: int) -> str | None:
    lights = line.get("lights")
    name: object = lights[robot] if isinstance(lights, list) and robot < len(lights) else None
    return name if isinstance(name, str) else None


def _view(line: Mapping[str, Any], robot: int) -> tuple[int, ...] | None:
    views = line.get("views")
    seen = views.get(str(robot)) if isinstance(views, Mapping) else None
    return tuple(int(r) for r in seen) if isinstance(seen, list) else None


def _lights(entry: RoundEntry, n: int) -> tuple[str, ...] | None:
    """Every robot's colour name at this line, None if it names none (or not n names)."""
    lights = entry.extra.get("lights")
    if not isinstance(lights, list) or len(lights) != n:
        return None
    return tuple(lights) if all(isinstance(name, str) for name in lights) else None


def record_palette(record: RecordLines) -> tuple[str, ...]:
    """The colour names the record's lines show, sorted: colour k of every picture is name k
    (replay's and plot's, deploy/view/lights.py, so one record looks the same in each)."""
    names: set[str] = set()
    for entry in record.rounds:
        names.update(_lights(entry, record.header.n) or ())
    return tuple(sorted(names))


def light_fills(names: Sequence[str], lights: Sequence[str]) -> list[str]:
    """Each robot's fill: its colour name's, name k of the sorted `names` drawn in LIGHT_HEX[k]
    (END_FILL for a name not among them)."""
    return [
        LIGHT_HEX[list(names).index(name) % len(LIGHT_HEX)] if name in names else END_FILL
        for name in lights
    ]


def _dtype(figure: figures.Figure) -> type:
    """A figure's column type: a count that always applies is int64 (failures), else float64."""
    return np.int64 if figure.type is int and not figure.optional else np.float64


def _nan(figure: figures.Figure, entry: RoundEntry) -> float:
    """A round's value of a derived figure, NaN where it does not apply (pandas' missing)."""
    value = figures.round_value(figure, entry.positions, entry.round, entry.extra)
    return math.nan if value is None else float(value)


def outcome_text(status: str, rounds: int, collisions: int, *, cycles: bool = False) -> str:
    """`formed in 17 rounds, collision-free`, `stalled after 3 rounds, with 2 collisions`; an
    async run counts `cycles` (`formed in 58 cycles`)."""
    word = "cycle" if cycles else "round"
    counted = f"{rounds} {word}{'' if rounds == 1 else 's'}"
    said = {
        "formed": f"formed in {counted}",
        "max_rounds": f"stopped at the {word} cap ({counted})",
    }.get(status, f"{status} after {counted}")
    if collisions == 0:
        return f"{said}, collision-free" if status == "formed" else said
    return f"{said}, with {collisions} collision{'' if collisions == 1 else 's'}"


def run_text(n: int, scheduler: str, seed: int | None) -> str:
    """`n=8 ssync seed 1`."""
    return f"n={n} {scheduler} seed {'?' if seed is None else seed}"


def model_text(robot_model: RobotModel) -> str:
    """`robot model: paper's` or `robot model: --visibility opaque --sight 5.0` (its flags)."""
    return "robot model: " + ("paper's" if robot_model.is_paper else robot_model.describe())


def frame_svg(
    initial: Points,
    final: Points,
    caption: Sequence[str],
    fills: Sequence[str] | None = None,
    palette: Sequence[str] = (),
) -> str:
    """An SVG picture, to scale (+Y up), of the start (grey rings) and the end (discs numbered
    when there is room: robot i filled `fills[i]`, its light's colour, else green) of a run, the
    end's smallest enclosing circle, and `caption`'s lines under it, then a luminous run's
    colours (`palette`, the names sorted: `lights: ● moving, ● still`, each dot in its colour)."""
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
    colours = list(fills) if fills is not None and len(fills) == len(end) else None
    parts += [
        f'<circle cx="{x:.6g}" cy="{y:.6g}" r="{radius:.6g}" '
        f'fill="{END_FILL if colours is None else colours[i]}" stroke="black" {line}/>'
        for i, (x, y) in enumerate(at(end))
    ]
    if len(end) <= IDS_UP_TO and radius / px >= 6.0:
        parts += [
            f'<text x="{x:.6g}" y="{y:.6g}" font-size="{radius:.6g}" text-anchor="middle" '
            f'dominant-baseline="central" fill="white">{i}</text>'
            for i, (x, y) in enumerate(at(end))
        ]
    shown = [html.escape(text) for text in caption] + _legend(palette)
    return _document(parts, side, shown)


def _legend(palette: Sequence[str]) -> list[str]:
    """The caption's line of a luminous run's colours, each name after a dot in its colour (SVG
    text); none for a run without lights."""
    if not palette:
        return []
    dots = (
        f'<tspan fill="{fill}">\u25cf</tspan> {html.escape(name)}'
        for name, fill in zip(palette, light_fills(palette, palette), strict=True)
    )
    return ["lights: " + ", ".join(dots)]


def _document(parts: list[str], side: float, caption: Sequence[str]) -> str:
    """The SVG document: the drawing in a square of `side` world units, the caption's lines
    (SVG text) below."""
    height = PICTURE_PX + 6 + LINE_PX * len(caption)
    lines = "".join(
        f'<text x="{PICTURE_PX / 2:g}" y="{PICTURE_PX + 16 + LINE_PX * k}" '
        f'font-family="sans-serif" font-size="13" text-anchor="middle">{text}</text>'
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


__all__ = [
    "COLUMNS",
    "EXTRA",
    "FAILED",
    "LIGHT",
    "VIEW",
    "RunRecord",
    "RunResult",
    "frame_svg",
    "light_fills",
    "record_columns",
    "record_palette",
    "run_attrs",
]
