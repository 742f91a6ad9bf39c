"""`fatswarm plot RECORD OUT.svg|OUT.png`: trajectories, start and end discs and the final circle;
`OUT.gif|OUT.mp4`: the run as a video (deploy/view/animate.py).

Drawn to scale (equal axes, unit discs; point robots as dots) with matplotlib, an optional extra
(`fatswarm[plot]`); without it the command says how to install it and exits with 2. `run_figure`
and `look_figure` return the matplotlib Figure (the notebook's `figure()` and `look_figure()`).
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import TYPE_CHECKING, Any

import numpy as np

from fatswarm.deploy.view.animate import (
    ANIMATIONS,
    add_animation_arguments,
    animation_flags_given,
    main_animation,
)
from fatswarm.deploy.view.dashboard import algorithm_text, enclosing_circle
from fatswarm.deploy.view.lights import (
    LookScene,
    body_radius,
    light_hex,
    lights_of,
    look_scene,
    record_palette,
)
from fatswarm.deploy.view.scene import new_figure
from fatswarm.deploy.view.summary import model_notes
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.path import Points, sample, truncate
from fatswarm.world.record import RecordFormatError, RunRecord, move_origin
from fatswarm.world.record_read import read_record, torn_end_note

if TYPE_CHECKING:  # matplotlib is an optional extra, loaded only to draw
    from matplotlib.figure import Figure

FORMATS = (".svg", ".png", *ANIMATIONS)
DESCRIPTION = (
    "draw a record to OUT.svg or OUT.png (trajectories, start and end discs, final circle), or "
    "animate it into OUT.gif or OUT.mp4 (robots moving along their paths within each round, "
    "ids on the discs, contacts marked in red, lights coloured); needs fatswarm[plot], and "
    "ffmpeg for MP4"
)
TRAIL_STEP = 0.1  # world units between samples of a drawn path
NO_LIGHT = "#808080"  # a robot whose colour the record does not say (the start)
FAILED_COLOUR = "#d62728"  # the ring of a robot whose compute failed at the Look drawn
PICTURE_INCHES = 7.0
POINT_SIZE = 30.0  # a point robot's dot (`--bodies points`), in points squared
MISSING_MATPLOTLIB = (
    "fatswarm plot needs matplotlib: install it with `pip install 'fatswarm[plot]'` "
    "(or `pip install matplotlib`)"
)


def trajectories(record: RunRecord) -> list[Points]:
    """Each robot's whole route through the run as a (k, 2) polyline, arcs sampled finely."""
    n = record.header.n
    here = np.array(record.header.initial, dtype=np.float64)
    routes: list[list[Points]] = [[here[i : i + 1].copy()] for i in range(n)]
    for rr in record.rounds:
        for move in rr.moves:
            start = move_origin(rr, move.robot, here)
            covered = truncate(start, move.path, move.traveled)
            if covered:
                routes[move.robot].append(sample(start, covered, TRAIL_STEP)[1:])
        here = np.array(rr.positions, dtype=np.float64)
    return [np.concatenate(parts) for parts in routes]


def final_positions(record: RunRecord) -> Points:
    """Where the robots ended (the result line, else the last round, else the start)."""
    if record.result is not None:
        return record.result.positions
    if record.rounds:
        return record.rounds[-1].positions
    return record.header.initial


def default_title(record: RunRecord, rc: float) -> str:
    """The run in one line: algorithm and parameters, n, scheduler, seed, outcome, final r_c."""
    header = record.header
    status = record.result.status if record.result is not None else "unfinished"
    rounds = record.rounds[-1].round if record.rounds else 0
    model, _ = model_notes(header.extra)
    return (
        f"{algorithm_text(header.algorithm, header.params)}, n={header.n}, {header.scheduler}, "
        f"seed {header.seed}: {status} after {rounds} rounds (final SEC r_c={rc:.3f})"
        + ("" if model is None else f"\nmodel: {model}")
    )


def lit_routes(record: RunRecord, palette: tuple[str, ...]) -> list[tuple[Points, str]]:
    """Each move of the run as a finely sampled (k, 2) polyline and the colour it is drawn in: the
    light its robot showed during it (the round line's `lights`), NO_LIGHT where none is known."""
    n = record.header.n
    here = np.array(record.header.initial, dtype=np.float64)
    out: list[tuple[Points, str]] = []
    for rr in record.rounds:
        lights = lights_of(rr, n)
        for move in rr.moves:
            start = move_origin(rr, move.robot, here)
            covered = truncate(start, move.path, move.traveled)
            if covered:
                name = lights[move.robot] if lights is not None else None
                out.append(
                    (sample(start, covered, TRAIL_STEP), light_hex(palette, name) or NO_LIGHT)
                )
        here = np.array(rr.positions, dtype=np.float64)
    return out


def final_lights(record: RunRecord) -> tuple[str, ...] | None:
    """Every robot's colour at the end: the last round line's lights (None if it has none)."""
    return lights_of(record.rounds[-1], record.header.n) if record.rounds else None


def draw(record: RunRecord, out: str, title: str | None = None) -> None:
    """Render the record to `out` (format from its suffix); needs matplotlib."""
    run_figure(record, title).savefig(out)


def run_figure(record: RunRecord, title: str | None = None) -> Figure:
    """The record as one picture, a matplotlib Figure: each robot's route, its start (rings) and
    end (discs, numbered), the final smallest enclosing circle."""
    from matplotlib import colormaps
    from matplotlib.patches import Circle

    header = record.header
    end = final_positions(record)
    fig, ax = new_figure(PICTURE_INCHES)
    ax.set_aspect("equal")
    palette = record_palette(record)
    radius = body_radius(header)
    if palette:
        _draw_lit(ax, record, end, palette)
    else:
        cmap = colormaps["tab20"]
        for i, route in enumerate(trajectories(record)):
            color = cmap(i % 20)
            ax.plot(route[:, 0], route[:, 1], "-", color=color, linewidth=0.8, alpha=0.9)
            _robot(ax, header.initial[i], radius, fill=False, ls="--", ec=color, lw=0.7)
            _robot(ax, end[i], radius, fc=color, ec="black", lw=0.5, alpha=0.6)
    (cx, cy), rc = enclosing_circle(end)
    ax.add_patch(Circle((cx, cy), rc, fill=False, ec="black", lw=1.0, label="final SEC"))
    ax.plot([cx], [cy], "k+", markersize=6)
    everything = np.vstack([header.initial, end, [[cx - rc, cy - rc], [cx + rc, cy + rc]]])
    lo, hi = everything.min(axis=0) - 1.5, everything.max(axis=0) + 1.5
    _ids(ax, end, radius)
    _finish(fig, ax, (lo, hi), title or default_title(record, rc))
    return fig


def _robot(ax: Any, centre: Any, radius: float, **style: Any) -> None:
    """One robot: a disc of `radius`, or a dot for a point robot (radius 0), in `style` (a
    patch's: fc, ec, lw, ls, fill, alpha)."""
    from matplotlib.patches import Circle

    x, y = float(centre[0]), float(centre[1])
    if radius > 0.0:
        ax.add_patch(Circle((x, y), radius, **style))
        return
    hollow = style.get("fill") is False
    ax.scatter(
        [x], [y], s=POINT_SIZE, marker="o", zorder=3,
        facecolors="none" if hollow else style.get("fc", NO_LIGHT),
        edgecolors=style.get("ec", "black"), linewidths=max(style.get("lw", 0.5), 0.6),
        alpha=style.get("alpha"),
    )  # fmt: skip


def _ids(ax: Any, centres: Any, radius: float) -> None:
    """Each robot's number: on its disc, or just beside a point robot's dot."""
    shift = (0.0, 0.0) if radius > 0.0 else (5.0, 5.0)  # points
    for i, (x, y) in enumerate(centres):
        ax.annotate(
            str(i), (x, y), xytext=shift, textcoords="offset points",
            ha="center" if radius > 0.0 else "left", va="center" if radius > 0.0 else "bottom",
            fontsize=7,
        )  # fmt: skip


def _finish(fig: Any, ax: Any, box: tuple[Points, Points], title: str) -> None:
    """Limits, title, axis labels and grid."""
    lo, hi = box
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x (robot radii)")
    ax.set_ylabel("y (robot radii)")
    ax.grid(True, lw=0.3, alpha=0.5)
    fig.tight_layout()


def _draw_lit(ax: Any, record: RunRecord, end: Points, palette: tuple[str, ...]) -> None:
    """Moves in the colour each robot showed during them, start discs dashed grey (no line
    records the start's colours), end discs in the final colours, a legend naming the colours."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Patch

    routes = lit_routes(record, palette)
    if routes:
        lines = LineCollection([r for r, _ in routes], colors=[c for _, c in routes], lw=0.9)
        ax.add_collection(lines)
    lights = final_lights(record)
    radius = body_radius(record.header)
    for i, start in enumerate(record.header.initial):
        _robot(ax, start, radius, fill=False, ls="--", ec=NO_LIGHT, lw=0.7)
        name = lights[i] if lights is not None else None
        fc = light_hex(palette, name) or NO_LIGHT
        _robot(ax, end[i], radius, fc=fc, ec="black", lw=0.5, alpha=0.6)
    handles = [Patch(color=light_hex(palette, name), label=name) for name in palette]
    handles.append(Patch(fill=False, ls="--", ec=NO_LIGHT, label="start"))
    ax.legend(handles=handles, fontsize=7, loc="best", title="lights", title_fontsize=7)


def draw_look(record: RunRecord, scene: LookScene, out: str, title: str | None = None) -> None:
    """Render one Look to `out` (format from its suffix); needs matplotlib."""
    look_figure(record, scene, title).savefig(out)


def look_figure(record: RunRecord, scene: LookScene, title: str | None = None) -> Figure:
    """One Look as a matplotlib Figure: every robot where it was then, the looker ringed with its
    sight circle and the move it made (ringed red, its compute having failed, when it did), the
    robots it saw in their colours, the others pale."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch

    palette, robot = record_palette(record), scene.robot
    fig, ax = new_figure(PICTURE_INCHES)
    ax.set_aspect("equal")
    _look_discs(ax, scene, palette, body_radius(record.header))
    x0, y0 = scene.positions[robot]
    reach = scene.sight or 0.0
    if scene.sight is not None:
        ax.add_patch(Circle((x0, y0), scene.sight, fill=False, ls="--", ec="black", lw=0.8))
    if scene.move is not None:
        origin, path, traveled = scene.move
        route = sample(origin, truncate(origin, path, traveled), TRAIL_STEP)
        ax.plot(route[:, 0], route[:, 1], "-", color="black", lw=1.2)
    lo = np.minimum(scene.positions.min(axis=0), [x0 - reach, y0 - reach]) - 1.5
    hi = np.maximum(scene.positions.max(axis=0), [x0 + reach, y0 + reach]) + 1.5
    shown = sorted({n for n in scene.lights or () if n in palette})
    handles: list[Any] = [Patch(color=light_hex(palette, n), label=n) for n in shown]
    handles.append(Patch(fc="#e8e8e8", ec="#b0b0b0", ls=":", label="not seen"))
    if scene.sight is not None:
        handles.append(Line2D([], [], ls="--", color="black", lw=0.8, label="sight"))
    if scene.failed is not None:
        handles.append(Patch(fill=False, ec=FAILED_COLOUR, lw=2.0, label="compute failed"))
    ax.legend(handles=handles, fontsize=7, loc="best")
    _finish(fig, ax, (lo, hi), title or look_title(record, scene))
    return fig


def _look_discs(ax: Any, scene: LookScene, palette: tuple[str, ...], radius: float) -> None:
    """Every robot at the Look, numbered: the looker ringed (red if its compute failed), the
    unseen pale and dotted."""
    for i, centre in enumerate(scene.positions):
        name = scene.lights[i] if scene.lights is not None else None
        fc = light_hex(palette, name) or NO_LIGHT
        if i != scene.robot and i not in scene.seen:
            _robot(ax, centre, radius, fc="#e8e8e8", ec="#b0b0b0", lw=0.5, ls=":")
        elif i == scene.robot:
            ec = "black" if scene.failed is None else FAILED_COLOUR
            _robot(ax, centre, radius, fc=fc, ec=ec, lw=2.0)
        else:
            _robot(ax, centre, radius, fc=fc, ec="black", lw=0.5)
    _ids(ax, scene.positions, radius)


def look_title(record: RunRecord, scene: LookScene) -> str:
    """`robot 2's Look in round 5: saw 3 of 5 (--visibility opaque --sight 6)` ("cycle" under
    async), why its compute failed if it did, and the run."""
    header = record.header
    model = model_notes(header.extra)[0] or "paper model"
    failed = "" if scene.failed is None else f"\nits compute failed: {scene.failed}"
    return (
        f"robot {scene.robot}'s Look in {scene.word} {scene.round}: saw {len(scene.seen)} of "
        f"{header.n - 1} ({model}){failed}\n{algorithm_text(header.algorithm, header.params)}, "
        f"n={header.n}, {header.scheduler}, seed {header.seed}"
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm plot`."""
    p.description = DESCRIPTION
    p.add_argument("record", metavar="RECORD", help="run record (JSON Lines)")
    p.add_argument(
        "out",
        metavar="OUT",
        help="what to write: a picture OUT.svg or OUT.png, or a video OUT.gif or OUT.mp4",
    )
    p.add_argument("--title", help="title instead of the run's parameters")
    p.add_argument(
        "--robot",
        type=int,
        metavar="I",
        help="with --round K: draw robot I's Look in round K instead (what it saw, where all "
        "robots were then, its move, whether its compute failed; needs a record made with "
        "--record-views); in a video: ring robot I and, while it Looks, pale the robots it "
        "did not see",
    )
    p.add_argument(
        "--round", type=int, metavar="K",
        help="the round of --robot's Look (async records: the cycle line)",
    )  # fmt: skip
    add_animation_arguments(p)


def main(args: argparse.Namespace) -> int:
    """`fatswarm plot`: exit 0 on success, 2 on bad input or without matplotlib."""
    refused = _refused(args)
    if refused is not None:
        print(f"fatswarm plot: {refused}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    try:
        record = read_record(args.record, allow_torn_end=True)  # a crashed run shows too
    except RecordFormatError as exc:
        print(f"fatswarm plot: {exc}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    note = torn_end_note(args.record, record)
    if note is not None:
        print(f"fatswarm plot: {note}", file=sys.stderr)
    try:  # matplotlib is an optional extra (fatswarm[plot]): without it, say how to install it
        import matplotlib  # noqa: F401
    except ImportError:
        print(MISSING_MATPLOTLIB, file=sys.stderr)
        return ExitCode.BAD_INPUT
    if os.path.splitext(args.out)[1].lower() in ANIMATIONS:
        return main_animation(args, record)
    scene = _look_of(args, record)
    if isinstance(scene, str):
        print(f"fatswarm plot: {scene}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    try:
        if scene is None:
            draw(record, args.out, args.title)
        else:
            draw_look(record, scene, args.out, args.title)
    except OSError as exc:
        print(f"fatswarm plot: cannot write {args.out}: {exc.strerror or exc}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    return ExitCode.OK


def _refused(args: argparse.Namespace) -> str | None:
    """Why OUT cannot be written, before any work: its kind, its folder, or flags it does not
    take (None: go ahead)."""
    suffix = os.path.splitext(args.out)[1].lower()
    if suffix not in FORMATS:
        return f"OUT must end in .svg, .png, .gif or .mp4, got {args.out!r}"
    folder = os.path.dirname(os.path.abspath(args.out))
    if not os.path.isdir(folder):
        return f"cannot write {args.out}: no folder {folder}"
    if os.path.isdir(args.out):
        return f"cannot write {args.out}: it is a folder"
    if not os.access(folder, os.W_OK):
        return f"cannot write {args.out}: {folder} is not writable"
    given = animation_flags_given(args)
    if suffix not in ANIMATIONS and given:
        applies = "applies" if len(given) == 1 else "apply"
        return f"{_listed(given)} only {applies} to a video: write OUT.gif or OUT.mp4"
    return None


def _listed(flags: list[str]) -> str:
    """`--fps`, `--fps and --rounds`, `--fps, --speed and --rounds`."""
    return flags[0] if len(flags) == 1 else f"{', '.join(flags[:-1])} and {flags[-1]}"


def _look_of(args: argparse.Namespace, record: RunRecord) -> LookScene | str | None:
    """The Look that --robot and --round ask for (None: neither is given), or why it cannot be
    drawn."""
    robot, round_no = getattr(args, "robot", None), getattr(args, "round", None)
    if robot is None and round_no is None:
        return None
    if robot is None or round_no is None:
        return "--robot I and --round K go together: robot I's Look in round K"
    if not 0 <= robot < record.header.n:
        return f"--robot must be a robot number between 0 and {record.header.n - 1}, got {robot}"
    return look_scene(record, robot, round_no)
