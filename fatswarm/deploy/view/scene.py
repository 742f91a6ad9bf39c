"""The one drawing of a record's frames: robots where the timeline puts them at a time, the paths
they have travelled so far, contacts, lights, the clock. `fatswarm plot OUT.gif|OUT.mp4`, the
notebook's `animate()` and `figure(round=k)` all draw through `Scene.update`.

matplotlib (fatswarm[plot]) draws; nothing here imports it at load. The figure is a bare
`matplotlib.figure.Figure` on an Agg canvas: no pyplot, no backend chosen, nothing to close, so a
notebook's own backend and figures are left alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.deploy.view.dashboard import algorithm_text, enclosing_circle
from fatswarm.deploy.view.lights import (
    Focus,
    body_radius,
    focus_per_round,
    light_hex,
    lights_of,
    record_palette,
)
from fatswarm.deploy.view.summary import model_notes
from fatswarm.domain.path import Points, sample, truncate
from fatswarm.domain.words import counted
from fatswarm.world.record import RunRecord, move_origin
from fatswarm.world.timeline import Timeline

if TYPE_CHECKING:  # matplotlib is an optional extra, loaded only to draw
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

FIGURE_INCHES: Final = 6.0
DPI: Final = 100  # 600 x 600 pixels: even sizes, as MP4's yuv420p wants
TRAIL_STEP: Final = 0.1
TRAIL_COLOUR: Final = "#b0b0b0"
NO_LIGHT: Final = "#808080"  # a robot whose colour the record does not say (the start)
UNSEEN_FACE: Final = "#e8e8e8"  # robots the chosen robot did not see at its Look
UNSEEN_EDGE: Final = "#b0b0b0"
CONTACT_COLOUR: Final = "#d62728"
LABEL_MIN_POINTS: Final = 3.5  # a disc smaller than this (radius, in points) gets no id
POINT_MARKER: Final = 5.0  # diameter, in points, of a point robot (`--bodies points`)
POINT_IDS_UP_TO: Final = 40  # point robots numbered (beside them) up to this many


@dataclass(frozen=True, slots=True)
class Clip:
    """The video's frames on the record's timeline: frame i (0..frames-1) shows time
    t0 + (t1 - t0) i / (frames - 1), so the first frame is the positions before round `first`
    and the last exactly those after round `last`. `speed`: timeline units per second of video."""

    first: int
    last: int
    t0: float
    t1: float
    frames: int
    fps: float
    speed: float

    def time_of(self, frame: int) -> float:
        """The timeline time frame `frame` shows."""
        if self.frames <= 1:
            return self.t1
        if frame >= self.frames - 1:
            return self.t1  # exactly: the end of the last round, as its line says
        return self.t0 + (self.t1 - self.t0) * frame / (self.frames - 1)

    @property
    def seconds(self) -> float:
        """The video's length."""
        return self.frames / self.fps


def still_clip(timeline: Timeline, line: int) -> Clip:
    """One frame: the positions after record line `line` (0: the start), with everything
    travelled since the start."""
    t = timeline.ends[line - 1] if line > 0 else 0.0
    return Clip(1, line, 0.0, t, 1, 1.0, 1.0)


def routes_between(record: RunRecord, first: int, last: int) -> list[Points]:
    """The paths covered by the moves of lines first..last, each sampled as a (k, 2) polyline."""
    here = np.array(record.header.initial, dtype=np.float64)
    out: list[Points] = []
    for k, entry in enumerate(record.rounds, start=1):
        if first <= k <= last:
            for move in entry.moves:
                start = move_origin(entry, move.robot, here)
                covered = truncate(start, move.path, move.traveled)
                if covered:
                    out.append(sample(start, covered, TRAIL_STEP))
        here = np.array(entry.positions, dtype=np.float64)
    return out


@dataclass(frozen=True, slots=True)
class Trails:
    """Where each robot went, in time: robot r's recorded moves, sampled at most TRAIL_STEP apart
    and joined in time order, pass `points[r][j]` at time `times[r][j]` (its moves follow one
    another: each starts where the one before stopped)."""

    points: tuple[NDArray[np.float64], ...]  # per robot (k, 2)
    times: tuple[NDArray[np.float64], ...]  # per robot (k,), non-decreasing

    @classmethod
    def of(cls, timeline: Timeline) -> Trails:
        """The samples of every move of the timeline."""
        points: list[list[NDArray[np.float64]]] = [[] for _ in range(timeline.n)]
        times: list[list[NDArray[np.float64]]] = [[] for _ in range(timeline.n)]
        for travel in sorted(timeline.travels(), key=lambda tr: tr.start):
            covered = truncate(travel.origin, travel.path, travel.traveled)
            if not covered:
                continue
            pts = sample(travel.origin, covered, TRAIL_STEP)
            arc = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))))
            scale = travel.traveled / arc[-1] if arc[-1] > 0.0 else 0.0
            points[travel.robot].append(pts)
            times[travel.robot].append(
                np.minimum(travel.start + arc * scale / travel.rate, travel.done)
            )
        return cls(
            tuple(np.concatenate(p) if p else np.zeros((0, 2)) for p in points),
            tuple(np.concatenate(t) if t else np.zeros(0) for t in times),
        )

    def until(self, since: float, t: float, positions: Points) -> list[NDArray[np.float64]]:
        """Each robot's way from time `since` to time `t` as a polyline (k, 2) ending where it
        is at t (`positions`, (n, 2)); robots that went nowhere in that time are left out."""
        out: list[NDArray[np.float64]] = []
        for robot, (points, times) in enumerate(zip(self.points, self.times, strict=True)):
            first = int(np.searchsorted(times, since, side="left"))
            last = int(np.searchsorted(times, t, side="left"))  # samples strictly before t
            if last > first:
                out.append(np.concatenate((points[first:last], positions[robot : robot + 1])))
        return out


def lights_at(timeline: Timeline, t: float) -> tuple[str, ...] | None:
    """Every robot's colour name at time t: under rounds those of the round in progress (a round
    line's lights hold from its moves' start); async, the last line ended by t. None: unknown."""
    rounds = timeline.record.rounds
    done = timeline.lines_done(t) if timeline.is_async else min(math.ceil(t), len(rounds))
    index = done - 1
    return lights_of(rounds[index], timeline.n) if index >= 0 else None


def video_title(record: RunRecord) -> str:
    """The run in one line (two with a model other than the paper's)."""
    header = record.header
    status = record.result.status if record.result is not None else "unfinished"
    model, _ = model_notes(header.extra)
    return (
        f"{algorithm_text(header.algorithm, header.params)}, n={header.n}, {header.scheduler}, "
        f"seed {header.seed}: {status}" + ("" if model is None else f"\nmodel: {model}")
    )


def new_figure(inches: float = FIGURE_INCHES, dpi: float = DPI) -> tuple[Figure, Axes]:
    """A bare matplotlib Figure on an Agg canvas and its one axes (no pyplot: nothing shown,
    nothing to close, the caller's backend untouched)."""
    # matplotlib is an optional extra (fatswarm[plot]) and heavy: loaded only to draw
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(inches, inches), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


class Scene:
    """The figure of a video and its moving parts: robots, ids, trails, current SEC, contacts,
    clock; with `robot`, that robot ringed and, while it Looks, the robots it did not see pale.

    `update(frame)` moves them to the clip's time of that frame (`Timeline.at`); `positions` is
    what the robots show, for tests to compare with the timeline rather than with pixels.
    """

    def __init__(
        self,
        record: RunRecord,
        timeline: Timeline,
        clip: Clip,
        title: str | None,
        robot: int | None = None,
    ) -> None:
        self.record, self.timeline, self.clip = record, timeline, clip
        self.palette = record_palette(record)
        self.radius = body_radius(record.header)
        self.robot = robot
        self._focus = None if robot is None else _focus_lines(record, timeline, robot)
        self.unknown = bool(self.palette) and any(
            lights_at(timeline, clip.time_of(i)) is None for i in range(clip.frames)
        )
        self.fig, self.ax = new_figure()
        self._trails = Trails.of(timeline)
        self._static(title)
        self._moving()
        self.positions: Points = timeline.at(clip.t0)
        self.update(0)

    def _static(self, title: str | None) -> None:
        """Axes to scale, the SEC of the clip's last frame (as `plot` draws it), the legend."""
        from matplotlib.patches import Circle

        ax, clip = self.ax, self.clip
        ax.set_aspect("equal")
        routes = routes_between(self.record, clip.first, clip.last)
        end = self.timeline.at(clip.t1)
        (cx, cy), rc = enclosing_circle(end)
        ax.add_patch(Circle((cx, cy), rc, fill=False, ec="black", lw=1.0, zorder=2))
        ax.plot([cx], [cy], "k+", markersize=6, zorder=2)
        reach = [self.timeline.at(clip.t0), end, *routes, [[cx - rc, cy - rc], [cx + rc, cy + rc]]]
        everything: Points = np.vstack([np.asarray(p, dtype=np.float64) for p in reach])
        margin = 0.5 + max(self.radius, 0.5)  # a point robot's id sits beside it
        lo, hi = everything.min(axis=0) - margin, everything.max(axis=0) + margin
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_title(title or video_title(self.record), fontsize=9)
        ax.set_xlabel("x (robot radii)")
        ax.set_ylabel("y (robot radii)")
        ax.grid(True, lw=0.3, alpha=0.5)
        if self.palette:
            self._legend()
        self.fig.tight_layout()

    def _legend(self) -> None:
        from matplotlib.patches import Patch

        handles = [Patch(color=light_hex(self.palette, name), label=name) for name in self.palette]
        if self.unknown:  # only when some frame draws a robot whose colour no line says
            handles.append(Patch(color=NO_LIGHT, label="unknown"))
        self.ax.legend(handles=handles, fontsize=7, loc="upper right", title="lights")

    def _moving(self) -> None:
        """Robots (one collection: unit discs, or dots for point robots), their ids, the trails,
        the current SEC, contact marks, the chosen robot's sight and the clock."""
        from matplotlib import colormaps
        from matplotlib.collections import EllipseCollection, LineCollection
        from matplotlib.patches import Circle

        n, ax = self.timeline.n, self.ax
        cmap = colormaps["tab20"]
        self.colours = [cmap(i % 20) for i in range(n)]
        self.trails = LineCollection([], colors=TRAIL_COLOUR, lw=0.6, zorder=1)
        ax.add_collection(self.trails)
        if self.radius > 0.0:
            self.discs: Any = EllipseCollection(
                widths=2.0 * self.radius, heights=2.0 * self.radius, angles=0.0, units="xy",
                offsets=np.zeros((n, 2)), offset_transform=ax.transData, facecolors=self.colours,
                edgecolors="black", linewidths=0.5, alpha=0.8, zorder=4,
            )  # fmt: skip
            ax.add_collection(self.discs)
        else:  # point robots: a dot each, whatever the scale
            self.discs = ax.scatter(
                np.zeros(n), np.zeros(n), s=POINT_MARKER**2, c=self.colours, edgecolors="black",
                linewidths=0.4, zorder=4,
            )  # fmt: skip
        size, self._label_shift = self._label_style()
        self.labels = [
            ax.text(0.0, 0.0, str(i), ha="center", va="center", fontsize=size, zorder=5)
            for i in range(n)
        ] if size else []  # fmt: skip
        self.sec = Circle((0.0, 0.0), 0.0, fill=False, ec="#7f7f7f", lw=0.8, ls="--", zorder=2)
        ax.add_patch(self.sec)
        self.sight = Circle((0.0, 0.0), 0.0, fill=False, ec="black", lw=0.8, ls=":", zorder=3)
        self.sight.set_visible(False)
        ax.add_patch(self.sight)
        self.contacts = ax.scatter(
            np.zeros(0), np.zeros(0), marker="x", s=60, c=CONTACT_COLOUR, linewidths=2, zorder=6
        )
        self._contact_points = _contact_points(self.timeline, self.clip)
        self.clock = ax.text(
            0.01, 0.99, "", transform=ax.transAxes, ha="left", va="top", fontsize=8, zorder=7
        )

    def _label_style(self) -> tuple[float, tuple[float, float]]:
        """The font size of the ids (0: none) and where an id sits from its robot's centre, in
        world units: on a disc, or beside a point."""
        if self.radius > 0.0:
            return _label_points(self.fig, self.ax, self.radius), (0.0, 0.0)
        if self.timeline.n > POINT_IDS_UP_TO:
            return 0.0, (0.0, 0.0)
        self.fig.canvas.draw()  # the axes' final size, after tight_layout
        (x0, _), (x1, _) = self.ax.transData.transform([(0.0, 0.0), (1.0, 0.0)])
        per_point = self.fig.dpi / 72.0 / max(abs(x1 - x0), 1e-12)  # world units per point
        return 7.0, (4.0 * per_point, 4.0 * per_point)

    def update(self, frame: int) -> list[Any]:
        """Show frame `frame` of the clip; the artists that changed."""
        t = self.clip.time_of(frame)
        self.positions = self.timeline.at(t)
        self.discs.set_offsets(self.positions)
        self.trails.set_segments(self._trails.until(self.clip.t0, t, self.positions))
        faces: list[Any] = list(self.colours)
        if self.palette:
            lights = lights_at(self.timeline, t)
            faces = [light_hex(self.palette, c) or NO_LIGHT for c in lights or ()] or [NO_LIGHT]
        self._focus_on(t, faces)
        dx, dy = self._label_shift
        for label, (x, y) in zip(self.labels, self.positions, strict=True):
            label.set_position((float(x) + dx, float(y) + dy))
        (cx, cy), rc = enclosing_circle(self.positions)
        self.sec.set_center((cx, cy))
        self.sec.set_radius(rc)
        shown = [p for tc, p in self._contact_points if tc <= t]
        self.contacts.set_offsets(np.array(shown).reshape(-1, 2))
        self.clock.set_text(self.clock_text(t, len(shown)))
        return [self.discs, self.trails, *self.labels, self.sec, self.contacts, self.clock]

    def _focus_on(self, t: float, faces: list[Any]) -> None:
        """Colour the robots (`faces`, one colour or n), the chosen robot ringed and, while it
        Looks, those it did not see pale, its sight drawn about where it Looked from."""
        n = self.timeline.n
        focus = None if self._focus is None else self._focus(t)
        if self.robot is None:
            self.discs.set_facecolor(faces)
            return
        faces = faces if len(faces) == n else faces * n
        edges: list[Any] = ["black"] * n
        widths = [0.5] * n
        widths[self.robot] = 2.5
        for other in range(n):
            if focus is not None and focus.dims(other):
                faces[other], edges[other] = UNSEEN_FACE, UNSEEN_EDGE
        self.discs.set_facecolor(faces)
        self.discs.set_edgecolor(edges)
        self.discs.set_linewidth(widths)
        looked = focus is not None and focus.origin is not None and focus.sight is not None
        self.sight.set_visible(looked)
        if looked and focus is not None and focus.origin is not None:
            self.sight.set_center(focus.origin)
            self.sight.set_radius(focus.sight or 0.0)

    def clock_text(self, t: float, contacts: int) -> str:
        """`round 5 of 17 (3 collisions)`, or async `t = 12.30, 45 of 80 cycles ended`; with a
        chosen robot, what it saw then."""
        touched = f" ({counted(contacts, 'collision')})" if contacts else ""
        count = len(self.timeline.ends)
        focus = None if self._focus is None else self._focus(t)
        saw = "" if focus is None or self.robot is None else f"\nrobot {self.robot}: {focus.line()}"
        if self.timeline.is_async:
            done = self.timeline.lines_done(t)
            return f"t = {t:.2f}, {done} of {count} cycles ended{touched}{saw}"
        if t <= 0.0:
            return f"start, before round 1 of {count}"
        return f"round {min(math.ceil(t), count)} of {count}{touched}{saw}"

    def close(self) -> None:
        """Nothing to release (the figure is no pyplot figure); kept for the callers' `finally`."""


FocusAt = Callable[[float], Focus | None]  # a chosen robot's Focus at a time of the timeline


def _focus_lines(record: RunRecord, timeline: Timeline, robot: int) -> FocusAt:
    """`robot`'s Focus at any time t: under rounds, that of the round in progress; async, that of
    its cycle whose Look is at or before t and whose line has not ended; None otherwise."""
    per_line: list[Focus] = focus_per_round(record, robot)[1:]
    if not timeline.is_async:

        def in_round(t: float) -> Focus | None:
            return per_line[min(math.ceil(t), len(per_line)) - 1] if t > 0.0 else None

        return in_round
    spans = [
        (float(look), timeline.ends[k], per_line[k])
        for k, entry in enumerate(record.rounds)
        if robot in entry.active
        and isinstance(look := entry.extra.get("look"), (int, float))
        and not isinstance(look, bool)
    ]

    def in_cycle(t: float) -> Focus | None:
        return next((f for look, end, f in spans if look <= t < end), None)

    return in_cycle


def _label_points(fig: Any, ax: Any, radius: float) -> float:
    """The font size of the ids on the discs: about a robot's radius, in points; 0 (no ids) when
    the discs are too small to hold one."""
    fig.canvas.draw()  # the axes' final size, after tight_layout
    (x0, _), (x1, _) = ax.transData.transform([(0.0, 0.0), (radius, 0.0)])
    size = abs(x1 - x0) * 72.0 / fig.dpi
    return 0.0 if size < LABEL_MIN_POINTS else min(10.0, 1.1 * size)


def _contact_points(timeline: Timeline, clip: Clip) -> list[tuple[float, tuple[float, float]]]:
    """Each collision of the clip's range at its time and where the two discs touched (halfway
    between the two centres at that time)."""
    out: list[tuple[float, tuple[float, float]]] = []
    for c in timeline.contacts:
        if clip.first <= c.line <= clip.last:
            here = timeline.at(min(max(c.t, 0.0), timeline.end))
            other = here[c.other] if 0 <= c.other < timeline.n else np.array(c.point)
            mid = (np.array(c.point) + other) / 2.0
            out.append((c.t, (float(mid[0]), float(mid[1]))))
    return out


__all__ = [
    "DPI",
    "Clip",
    "Scene",
    "Trails",
    "lights_at",
    "new_figure",
    "routes_between",
    "still_clip",
    "video_title",
]
