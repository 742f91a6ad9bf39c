"""`fatswarm plot RECORD OUT.gif|OUT.mp4`: the run as a video, robots moving along their paths
within each round (world/timeline.py), their ids on the discs, contacts marked, lights coloured.

matplotlib (fatswarm[plot]) draws the frames; a GIF is written a frame at a time with Pillow
(which comes with matplotlib), an MP4 through ffmpeg. Nothing here imports matplotlib at load.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import shutil
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import IO, Any, Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.deploy.view.dashboard import algorithm_text, enclosing_circle
from fatswarm.deploy.view.lights import light_hex, lights_of, record_palette
from fatswarm.deploy.view.summary import model_notes
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.path import Points, sample, truncate
from fatswarm.domain.words import counted, plural
from fatswarm.world.record import RunRecord, move_origin
from fatswarm.world.timeline import Timeline

ANIMATIONS: Final = (".gif", ".mp4")
DEFAULT_FPS: Final = 20.0
DEFAULT_SPEED: Final = 2.0  # rounds (async: units of virtual time) per second of video
LONGEST_DEFAULT: Final = 60.0  # seconds: the default speed quickens so that a video is no longer
DEFAULT_MAX_FRAMES: Final = 3000
MAX_GIF_FPS: Final = 50.0  # GIF frame delays are in hundredths; viewers slow anything faster
MAX_FPS: Final = 120.0
FIGURE_INCHES: Final = 6.0
DPI: Final = 100  # 600 x 600 pixels: even sizes, as MP4's yuv420p wants
TRAIL_STEP: Final = 0.1
NO_LIGHT: Final = "#808080"  # a robot whose colour the record does not say (the start)
CONTACT_COLOUR: Final = "#d62728"
LABEL_MIN_POINTS: Final = 3.5  # a disc smaller than this (radius, in points) gets no id
MISSING_FFMPEG: Final = (
    "fatswarm plot: writing OUT.mp4 needs ffmpeg, which is not on the PATH: install it (e.g. "
    "`apt install ffmpeg`, `brew install ffmpeg` or `conda install -c conda-forge ffmpeg`), "
    "or write OUT.gif, which needs nothing more"
)
SPEED_HELP: Final = (
    "how fast the video plays: R rounds of the record per second of video (async records: R "
    "units of virtual time, i.e. robot radii at unit speed, per second); within a round robots "
    f"move at their relative speeds, the longest move filling the round (default "
    f"{DEFAULT_SPEED:g}, quicker for a long record so that the video lasts at most "
    f"{LONGEST_DEFAULT:g} s)"
)


# --- what to show: the clip ---------------------------------------------------------------------


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


def parse_rounds(text: str, count: int) -> tuple[int, int]:
    """`A..B` (also `A..`, `..B`, or one round `K`) as (first, last), 1-based and inclusive, within
    the record's `count` lines; ValueError with one line otherwise."""
    match = re.fullmatch(r"\s*(\d*)\s*(\.\.)?\s*(\d*)\s*", text)
    if match is None or (match.group(2) is None and not match.group(1)):
        raise ValueError(f"--rounds must be A..B (e.g. 3..10, 5.., ..20), got {text!r}")
    low = int(match.group(1)) if match.group(1) else 1
    high = int(match.group(3)) if match.group(3) else (count if match.group(2) else low)
    if count == 0:
        raise ValueError("--rounds: the record has no rounds to choose from")
    if not 1 <= low <= high <= count:
        raise ValueError(
            f"--rounds {text}: the record's rounds are 1..{count}, and A must be at most B"
        )
    return low, high


def plan_clip(
    timeline: Timeline, rounds: tuple[int, int] | None, fps: float, speed: float | None
) -> Clip:
    """The frames of a video of `rounds` (all of them: None) at `fps` frames and `speed` timeline
    units per second; `speed` None: DEFAULT_SPEED, or what keeps the video to LONGEST_DEFAULT."""
    count = len(timeline.ends)
    if count == 0:
        return Clip(0, 0, 0.0, 0.0, 1, fps, speed or DEFAULT_SPEED)
    first, last = rounds if rounds is not None else (1, count)
    t0, t1 = timeline.span(first, last)
    if speed is None:
        speed = max(DEFAULT_SPEED, (t1 - t0) / LONGEST_DEFAULT)
    frames = round((t1 - t0) / speed * fps) + 1
    return Clip(first, last, t0, t1, frames, fps, speed)


def clip_line(clip: Clip, is_async: bool, out: str) -> str:
    """`writing 171 frames (8.6 s of video at 20 fps, 2 rounds per second) to run.gif`."""
    unit = (
        f"{plural('unit', clip.speed)} of virtual time" if is_async else plural("round", clip.speed)
    )
    shown = f"{'cycle lines' if is_async else 'rounds'} {clip.first}..{clip.last}"
    return (
        f"writing {clip.frames:,} frames of {shown} ({clip.seconds:.1f} s of video at "
        f"{clip.fps:g} fps, {clip.speed:g} {unit} per second) to {out}"
    )


# --- the picture: one figure, its moving parts updated per frame ---------------------------------


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


class Scene:
    """The figure of a video and its moving parts: discs, ids, current SEC, contacts, clock.

    `update(frame)` moves them to the clip's time of that frame (`Timeline.at`); `positions` is
    what the discs show, for tests to compare with the timeline rather than with pixels.
    """

    def __init__(self, record: RunRecord, timeline: Timeline, clip: Clip, title: str | None):
        # matplotlib is an optional extra (fatswarm[plot]) and heavy: loaded only to draw
        import matplotlib

        matplotlib.use("Agg")
        # once the backend is chosen
        import matplotlib.pyplot as plt

        self.record, self.timeline, self.clip = record, timeline, clip
        self.palette = record_palette(record)
        self.fig, self.ax = plt.subplots(figsize=(FIGURE_INCHES, FIGURE_INCHES), dpi=DPI)
        self._static(title)
        self._moving()
        self.positions: Points = timeline.at(clip.t0)

    def _static(self, title: str | None) -> None:
        """Axes to scale, the clip's paths faint, the SEC of its last frame (as `plot` draws it)."""
        from matplotlib.collections import LineCollection
        from matplotlib.patches import Circle

        ax, clip = self.ax, self.clip
        ax.set_aspect("equal")
        routes = routes_between(self.record, clip.first, clip.last)
        if routes:
            ax.add_collection(LineCollection(routes, colors="#b0b0b0", lw=0.6, zorder=1))
        end = self.timeline.at(clip.t1)
        (cx, cy), rc = enclosing_circle(end)
        ax.add_patch(Circle((cx, cy), rc, fill=False, ec="black", lw=1.0, zorder=2))
        ax.plot([cx], [cy], "k+", markersize=6, zorder=2)
        reach = [self.timeline.at(clip.t0), end, *routes, [[cx - rc, cy - rc], [cx + rc, cy + rc]]]
        everything: Points = np.vstack([np.asarray(p, dtype=np.float64) for p in reach])
        lo, hi = everything.min(axis=0) - 1.5, everything.max(axis=0) + 1.5
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
        handles.append(Patch(color=NO_LIGHT, label="unknown"))
        self.ax.legend(handles=handles, fontsize=7, loc="upper right", title="lights")

    def _moving(self) -> None:
        """Discs (one collection), their ids, the current SEC, contact marks and the clock."""
        import matplotlib.pyplot as plt
        from matplotlib.collections import EllipseCollection
        from matplotlib.patches import Circle

        n, ax = self.timeline.n, self.ax
        cmap = plt.get_cmap("tab20")
        self.colours = [cmap(i % 20) for i in range(n)]
        self.discs = EllipseCollection(
            widths=2.0, heights=2.0, angles=0.0, units="xy", offsets=np.zeros((n, 2)),
            offset_transform=ax.transData, facecolors=self.colours, edgecolors="black",
            linewidths=0.5, alpha=0.8, zorder=4,
        )  # fmt: skip
        ax.add_collection(self.discs)
        size = _label_points(self.fig, ax)
        self.labels = [
            ax.text(0.0, 0.0, str(i), ha="center", va="center", fontsize=size, zorder=5)
            for i in range(n)
        ] if size else []  # fmt: skip
        self.sec = Circle((0.0, 0.0), 0.0, fill=False, ec="#7f7f7f", lw=0.8, ls="--", zorder=2)
        ax.add_patch(self.sec)
        self.contacts = ax.scatter(
            np.zeros(0), np.zeros(0), marker="x", s=60, c=CONTACT_COLOUR, linewidths=2, zorder=6
        )
        self._contact_points = _contact_points(self.timeline, self.clip)
        self.clock = ax.text(
            0.01, 0.99, "", transform=ax.transAxes, ha="left", va="top", fontsize=8, zorder=7
        )

    def update(self, frame: int) -> list[Any]:
        """Show frame `frame` of the clip; the artists that changed."""
        t = self.clip.time_of(frame)
        self.positions = self.timeline.at(t)
        self.discs.set_offsets(self.positions)
        lights = lights_at(self.timeline, t) if self.palette else None
        if lights is not None:
            self.discs.set_facecolor([light_hex(self.palette, c) or NO_LIGHT for c in lights])
        for label, (x, y) in zip(self.labels, self.positions, strict=True):
            label.set_position((float(x), float(y)))
        (cx, cy), rc = enclosing_circle(self.positions)
        self.sec.set_center((cx, cy))
        self.sec.set_radius(rc)
        shown = [p for tc, p in self._contact_points if tc <= t]
        self.contacts.set_offsets(np.array(shown).reshape(-1, 2))
        self.clock.set_text(self.clock_text(t, len(shown)))
        return [self.discs, *self.labels, self.sec, self.contacts, self.clock]

    def clock_text(self, t: float, contacts: int) -> str:
        """`round 5 of 17 (3 collisions)`, or async `t = 12.30, 45 of 80 cycles ended`."""
        touched = f" ({counted(contacts, 'collision')})" if contacts else ""
        count = len(self.timeline.ends)
        if self.timeline.is_async:
            done = self.timeline.lines_done(t)
            return f"t = {t:.2f}, {done} of {count} cycles ended{touched}"
        if t <= 0.0:
            return f"start, before round 1 of {count}"
        return f"round {min(math.ceil(t), count)} of {count}{touched}"

    def close(self) -> None:
        import matplotlib.pyplot as plt

        plt.close(self.fig)


def _label_points(fig: Any, ax: Any) -> float:
    """The font size of the ids on the discs: about a robot's radius, in points; 0 (no ids) when
    the discs are too small to hold one."""
    fig.canvas.draw()  # the axes' final size, after tight_layout
    (x0, _), (x1, _) = ax.transData.transform([(0.0, 0.0), (1.0, 0.0)])
    radius = abs(x1 - x0) * 72.0 / fig.dpi
    return 0.0 if radius < LABEL_MIN_POINTS else min(10.0, 1.1 * radius)


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


# --- writing ----------------------------------------------------------------------------------


class GifStream:
    """A matplotlib movie writer that writes each GIF frame as it comes (Pillow's own keeps every
    frame in memory until the end: a gigabyte for a long video). Each frame has its own palette."""

    def __init__(self, fps: float) -> None:
        self.fps = fps
        self._fh: IO[bytes] | None = None
        self._previous: NDArray[np.uint8] | None = None  # the last frame's pixels (h, w, 3)
        self.frames = 0

    def setup(self, fig: Any, outfile: str, dpi: float | None = None) -> None:
        self.fig, self.outfile, self.dpi = fig, outfile, dpi or fig.dpi
        self._fh = open(outfile, "wb")  # noqa: SIM115  (closed by finish)

    def _supports_transparency(self) -> bool:
        return False  # matplotlib then paints the background opaque

    def grab_frame(self, **savefig_kwargs: Any) -> None:
        """Append the figure as it is drawn now as one frame (its own 256-colour palette)."""
        from PIL import GifImagePlugin, Image

        if self._fh is None:
            raise RuntimeError("GifStream.grab_frame before setup")
        self.fig.canvas.draw()
        pixels = np.ascontiguousarray(np.asarray(self.fig.canvas.buffer_rgba())[:, :, :3])
        delay = round(1000.0 / self.fps)
        if self._previous is None:  # the first frame, whole, with the file's header
            image = Image.fromarray(pixels).quantize(colors=256)
            header, _ = GifImagePlugin.getheader(image, info={"loop": 0, "duration": delay})
            self._fh.writelines(header)
            offset = (0, 0)
        else:  # only the box that changed: a frame is mostly the one before
            top, bottom, left, right = _changed_box(self._previous, pixels)
            image = Image.fromarray(pixels[top:bottom, left:right]).quantize(colors=256)
            offset = (left, top)
        self._fh.writelines(
            GifImagePlugin.getdata(
                image, offset=offset, duration=delay, disposal=1, include_color_table=True
            )
        )
        self._previous = pixels
        self.frames += 1

    def finish(self) -> None:
        if self._fh is not None:
            self._fh.write(b";")  # the GIF trailer
            self._fh.close()
            self._fh = None

    def saving(self, fig: Any, outfile: str, dpi: float | None, *args: Any, **kw: Any) -> Any:
        """What `Animation.save` enters around the frames (matplotlib's writer protocol)."""

        @contextlib.contextmanager
        def context() -> Any:
            self.setup(fig, outfile, dpi)
            try:
                yield self
            finally:
                self.finish()

        return context()


def _changed_box(before: NDArray[np.uint8], after: NDArray[np.uint8]) -> tuple[int, int, int, int]:
    """(top, bottom, left, right) of the pixels that differ; one pixel if none does (a frame
    must still be written, to keep the video's time)."""
    changed = np.any(before != after, axis=2)
    rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
    if not len(rows):
        return 0, 1, 0, 1
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


class Progress:
    """`frame 120/340 (35%), about 12 s left` on stderr: rewritten in place on a terminal, else a
    line every tenth of the frames."""

    def __init__(self, stream: IO[str], clock: Callable[[], float] = time.monotonic) -> None:
        self.stream, self.clock = stream, clock
        self.tty = stream.isatty()
        self.started = clock()
        self.said = -1

    def __call__(self, done: int, total: int) -> None:
        done, total = done + 1, max(total, 1)  # matplotlib counts from 0, before the frame
        step = 100 * done // total if self.tty else 10 * done // total  # percent, or tenths
        if step == self.said or (step == 0 and not self.tty):
            return
        self.said = step
        left = (self.clock() - self.started) / done * (total - done)
        percent = 100 * done // total
        line = f"fatswarm plot: frame {done}/{total} ({percent}%), about {left:.0f} s left"
        if self.tty:
            line = "\r" + line + ("\n" if done >= total else "")
        else:
            line += "\n"
        self.stream.write(line)
        self.stream.flush()


def write_video(scene: Scene, out: str, progress: Callable[[int, int], None] | None) -> None:
    """Draw every frame of the scene's clip into `out` (.gif or .mp4)."""
    from matplotlib.animation import FFMpegWriter, FuncAnimation

    clip = scene.clip
    anim = FuncAnimation(
        scene.fig, scene.update, frames=clip.frames, interval=1000.0 / clip.fps, blit=False,
        repeat=False, cache_frame_data=False,
    )  # fmt: skip
    if out.lower().endswith(".gif"):
        writer: Any = GifStream(clip.fps)
    else:
        writer = FFMpegWriter(fps=int(clip.fps), codec="h264", extra_args=["-pix_fmt", "yuv420p"])
    anim.save(out, writer=writer, dpi=DPI, progress_callback=progress)


# --- the command ------------------------------------------------------------------------------


def add_animation_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm plot` for OUT.gif and OUT.mp4."""
    p.add_argument(
        "--fps", type=int, metavar="F",
        help=f"frames per second of the video (default {DEFAULT_FPS:g}; GIF at most "
        f"{MAX_GIF_FPS:g})",
    )  # fmt: skip
    p.add_argument("--speed", type=float, metavar="R", help=SPEED_HELP)
    p.add_argument(
        "--rounds", metavar="A..B",
        help="only rounds A to B (1-based, inclusive; A.. or ..B leave an end open): the video "
        "starts from the positions before round A and ends on those after round B (async "
        "records: the cycle lines A..B)",
    )  # fmt: skip
    p.add_argument(
        "--max-frames", type=int, metavar="N", default=DEFAULT_MAX_FRAMES,
        help="refuse a video of more than N frames, saying how many it would take, rather than "
        f"render for an hour (default {DEFAULT_MAX_FRAMES})",
    )  # fmt: skip


def animation_flags_given(args: argparse.Namespace) -> list[str]:
    """The animation flags given (for a still picture, which refuses them)."""
    given = [f"--{name}" for name in ("fps", "speed", "rounds") if getattr(args, name, None)]
    if getattr(args, "max_frames", DEFAULT_MAX_FRAMES) != DEFAULT_MAX_FRAMES:
        given.append("--max-frames")
    return given


def plan(args: argparse.Namespace, timeline: Timeline) -> Clip | str:
    """The clip the flags ask for, or one line saying why they cannot be used."""
    suffix = os.path.splitext(args.out)[1].lower()
    fps = DEFAULT_FPS if args.fps is None else args.fps
    top = MAX_GIF_FPS if suffix == ".gif" else MAX_FPS
    if not (math.isfinite(fps) and 1.0 <= fps <= top):
        return f"--fps must be a whole number between 1 and {top:g} for {suffix}, got {fps:g}"
    if args.speed is not None and not (math.isfinite(args.speed) and args.speed > 0):
        return f"--speed must be a positive number, got {args.speed:g}"
    if args.max_frames < 1:
        return f"--max-frames must be at least 1, got {args.max_frames}"
    try:
        rounds = None if args.rounds is None else parse_rounds(args.rounds, len(timeline.ends))
    except ValueError as exc:
        return str(exc)
    clip = plan_clip(timeline, rounds, fps, args.speed)
    if clip.frames > args.max_frames:
        need = (clip.t1 - clip.t0) * fps / (args.max_frames - 1) if args.max_frames > 1 else 0.0
        return (
            f"that video would take {clip.frames:,} frames ({clip.seconds:,.1f} s at {fps:g} "
            f"fps), over --max-frames {args.max_frames:,}: pass --speed {math.ceil(need)} or "
            "more, fewer --rounds A..B, a lower --fps, or a higher --max-frames"
        )
    return clip


def main_animation(args: argparse.Namespace, record: RunRecord) -> int:
    """Write the video `args.out` of `record`: exit 0, or 2 with one line on a bad flag, a place
    that cannot be written, or no ffmpeg for an MP4."""
    if getattr(args, "robot", None) is not None or getattr(args, "round", None) is not None:
        print(
            "fatswarm plot: --robot and --round draw one Look: write it to OUT.svg or OUT.png",
            file=sys.stderr,
        )
        return ExitCode.BAD_INPUT
    timeline = Timeline(record)
    clip = plan(args, timeline)
    if isinstance(clip, str):
        print(f"fatswarm plot: {clip}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    if args.out.lower().endswith(".mp4") and not ffmpeg_available():
        print(MISSING_FFMPEG, file=sys.stderr)
        return ExitCode.BAD_INPUT
    print(f"fatswarm plot: {clip_line(clip, timeline.is_async, args.out)}", file=sys.stderr)
    scene = Scene(record, timeline, clip, args.title)
    written = False
    try:
        write_video(scene, args.out, Progress(sys.stderr))
        written = True
    except OSError as exc:
        print(f"fatswarm plot: cannot write {args.out}: {exc.strerror or exc}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    finally:
        scene.close()
        if not written:  # interrupted or failed: no half video is left behind
            with contextlib.suppress(OSError):
                os.remove(args.out)
    return ExitCode.OK


def ffmpeg_available() -> bool:
    """Whether matplotlib can find ffmpeg (its `animation.ffmpeg_path`, else the PATH)."""
    import matplotlib

    path = str(matplotlib.rcParams.get("animation.ffmpeg_path", "ffmpeg"))
    return shutil.which(path) is not None


__all__ = [
    "ANIMATIONS",
    "Clip",
    "GifStream",
    "Scene",
    "add_animation_arguments",
    "lights_at",
    "main_animation",
    "parse_rounds",
    "plan",
    "plan_clip",
    "routes_between",
]
