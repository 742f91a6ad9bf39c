"""`fatswarm plot RECORD OUT.gif|OUT.mp4`: the run as a video, robots moving along their paths
within each round (world/timeline.py), their ids on the discs, contacts marked, lights coloured;
the frames are drawn by deploy/view/scene.py (the notebook's `animate()` draws the same).

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

from fatswarm.deploy.view.lights import NO_VIEWS, has_views
from fatswarm.deploy.view.scene import DPI, Clip, Scene, lights_at, routes_between
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.words import plural
from fatswarm.world.record import RunRecord
from fatswarm.world.timeline import Timeline

ANIMATIONS: Final = (".gif", ".mp4")
DEFAULT_FPS: Final = 20.0
DEFAULT_SPEED: Final = 2.0  # rounds (async: units of virtual time) per second of video
LONGEST_DEFAULT: Final = 60.0  # seconds: the default speed quickens so that a video is no longer
DEFAULT_MAX_FRAMES: Final = 3000
MAX_GIF_FPS: Final = 50.0  # GIF frame delays are in hundredths; viewers slow anything faster
MAX_FPS: Final = 120.0
SPEED_HELP: Final = (
    "how fast the video plays: R rounds of the record per second of video (async records: R "
    "units of virtual time, i.e. robot radii at unit speed, per second); within a round robots "
    f"move at their relative speeds, the longest move filling the round (default "
    f"{DEFAULT_SPEED:g}, quicker for a long record so that the video lasts at most "
    f"{LONGEST_DEFAULT:g} s)"
)


def missing_ffmpeg(out: str) -> str:
    """Why an MP4 cannot be written here, naming the file asked for."""
    gif = os.path.splitext(out)[0] + ".gif"
    return (
        f"fatswarm plot: writing {out} needs ffmpeg, which is not on the PATH: install it (e.g. "
        "`apt install ffmpeg`, `brew install ffmpeg` or `conda install -c conda-forge ffmpeg`), "
        f"or write {gif}, which needs nothing more"
    )


@dataclass(frozen=True, slots=True)
class Words:
    """How a refusal names the video's settings: the command's flags or the API's keywords."""

    fps: str
    speed: str
    rounds: str
    max_frames: str
    assign: str  # between a name and its value: " " for a flag, "=" for a keyword
    still: str  # what draws one instant

    def given(self, name: str, value: object) -> str:
        """`--speed 34` or `speed=34`."""
        return f"{getattr(self, name)}{self.assign}{value}"


FLAGS: Final = Words("--fps", "--speed", "--rounds", "--max-frames", " ", "a picture, OUT.png")


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


# --- writing ----------------------------------------------------------------------------------


class GifStream:
    """A GIF written a frame at a time into a binary stream (Pillow's own writer keeps every
    frame in memory until the end: a gigabyte for a long video). Each frame has its own palette
    and holds only the box that changed since the one before."""

    def __init__(self, fps: float, sink: IO[bytes]) -> None:
        self.fps, self.sink = fps, sink
        self._previous: NDArray[np.uint8] | None = None  # the last frame's pixels (h, w, 3)
        self.frames = 0

    def grab_frame(self, fig: Any) -> None:
        """Append the figure as it is drawn now as one frame (its own 256-colour palette)."""
        from PIL import GifImagePlugin, Image

        fig.canvas.draw()
        pixels = np.ascontiguousarray(np.asarray(fig.canvas.buffer_rgba())[:, :, :3])
        delay = round(1000.0 / self.fps)
        if self._previous is None:  # the first frame, whole, with the file's header
            image = Image.fromarray(pixels).quantize(colors=256)
            header, _ = GifImagePlugin.getheader(image, info={"loop": 0, "duration": delay})
            self.sink.writelines(header)
            offset = (0, 0)
        else:  # only the box that changed: a frame is mostly the one before
            top, bottom, left, right = _changed_box(self._previous, pixels)
            image = Image.fromarray(pixels[top:bottom, left:right]).quantize(colors=256)
            offset = (left, top)
        self.sink.writelines(
            GifImagePlugin.getdata(
                image, offset=offset, duration=delay, disposal=1, include_color_table=True
            )
        )
        self._previous = pixels
        self.frames += 1

    def finish(self) -> None:
        """The GIF trailer (the stream stays open: it is the caller's)."""
        self.sink.write(b";")


def _changed_box(before: NDArray[np.uint8], after: NDArray[np.uint8]) -> tuple[int, int, int, int]:
    """(top, bottom, left, right) of the pixels that differ; one pixel if none does (a frame
    must still be written, to keep the video's time)."""
    changed = np.any(before != after, axis=2)
    rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
    if not len(rows):
        return 0, 1, 0, 1
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


def say(line: str, stream: IO[str] | None = None) -> None:
    """Write one line of notes or progress to `stream` (standard error); once the reader has
    gone (`... 2>&1 | head -2`), drop this and every later line and go on with the work."""
    stream = sys.stderr if stream is None else stream
    try:
        stream.write(line)
        stream.flush()
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:  # the flush at exit must not fail again on what is left in the buffer
            with contextlib.suppress(OSError, ValueError):  # no descriptor: an in-process capture
                os.dup2(devnull, stream.fileno())
        finally:
            os.close(devnull)


class Progress:
    """`frame 120/340 (35%), about 12 s left` on stderr: rewritten in place on a terminal, else a
    line every tenth of the frames."""

    def __init__(self, stream: IO[str], clock: Callable[[], float] = time.monotonic) -> None:
        self.stream, self.clock = stream, clock
        self.tty = stream.isatty()
        self.started = clock()
        self.said = -1

    def __call__(self, done: int, total: int) -> None:
        done, total = done + 1, max(total, 1)  # counted from 0, before the frame
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
        say(line, self.stream)


def write_gif(
    scene: Scene, sink: IO[bytes], progress: Callable[[int, int], None] | None = None
) -> int:
    """Draw every frame of the scene's clip into `sink` as a GIF; the frames written."""
    gif = GifStream(scene.clip.fps, sink)
    for frame in range(scene.clip.frames):
        scene.update(frame)
        gif.grab_frame(scene.fig)
        if progress is not None:
            progress(frame, scene.clip.frames)
    gif.finish()
    return gif.frames


def write_video(scene: Scene, out: str, progress: Callable[[int, int], None] | None) -> None:
    """Draw every frame of the scene's clip into `out` (.gif or .mp4)."""
    if out.lower().endswith(".gif"):
        with open(out, "wb") as sink:
            write_gif(scene, sink, progress)
        return
    from matplotlib.animation import FFMpegWriter, FuncAnimation

    clip = scene.clip
    anim = FuncAnimation(
        scene.fig, scene.update, frames=clip.frames, interval=1000.0 / clip.fps, blit=False,
        repeat=False, cache_frame_data=False,
    )  # fmt: skip
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
    return plan_video(timeline, suffix, args.fps, args.speed, args.rounds, args.max_frames, FLAGS)


def plan_video(
    timeline: Timeline,
    suffix: str,
    fps: float | None,
    speed: float | None,
    rounds: str | None,
    max_frames: int,
    words: Words,
) -> Clip | str:
    """The clip of a video of kind `suffix` (.gif, .mp4, .html) at `fps` (None: DEFAULT_FPS)
    and `speed` (None: the default) of `rounds` (`A..B`, None: all), or one line saying why these
    settings cannot be used, naming them in `words`."""
    fps = DEFAULT_FPS if fps is None else fps
    top = MAX_GIF_FPS if suffix == ".gif" else MAX_FPS
    if not (math.isfinite(fps) and 1.0 <= fps <= top):
        return f"{words.fps} must be a whole number between 1 and {top:g} for {suffix}, got {fps:g}"
    if speed is not None and not (math.isfinite(speed) and speed > 0):
        return f"{words.speed} must be a positive number, got {speed:g}"
    if max_frames < 1:
        return f"{words.max_frames} must be at least 1, got {max_frames}"
    try:
        span = None if rounds is None else parse_rounds(rounds, len(timeline.ends))
    except ValueError as exc:
        return str(exc).replace("--rounds", words.rounds)
    clip = plan_clip(timeline, span, fps, speed)
    if clip.frames <= max_frames:
        return clip
    over = (
        f"that video would take {clip.frames:,} frames ({clip.seconds:,.1f} s at {fps:g} fps), "
        f"over {words.given('max_frames', f'{max_frames:,}')}"
    )
    if max_frames == 1:  # one frame is one instant, whatever the speed
        return f"{over}: one frame shows one instant ({words.still}); allow 2 or more"
    need = math.ceil((clip.t1 - clip.t0) * fps / (max_frames - 1))
    return (
        f"{over}: pass {words.given('speed', need)} or more, fewer {words.rounds} A..B, a lower "
        f"{words.fps}, or a higher {words.max_frames}"
    )


def main_animation(args: argparse.Namespace, record: RunRecord) -> int:
    """Write the video `args.out` of `record`: exit 0, or 2 with one line on a bad flag, a place
    that cannot be written, or no ffmpeg for an MP4. Notes and progress go to standard error
    while someone reads it; a reader that goes away stops them, not the video."""
    if getattr(args, "round", None) is not None:
        say(
            "fatswarm plot: --round draws one Look (with --robot): write it to OUT.svg or OUT.png\n"
        )
        return ExitCode.BAD_INPUT
    timeline = Timeline(record)
    clip = plan(args, timeline)
    if isinstance(clip, str):
        say(f"fatswarm plot: {clip}\n")
        return ExitCode.BAD_INPUT
    robot = getattr(args, "robot", None)
    if robot is not None and not 0 <= robot < record.header.n:
        say(f"fatswarm plot: --robot must be between 0 and {record.header.n - 1}, got {robot}\n")
        return ExitCode.BAD_INPUT
    if args.out.lower().endswith(".mp4") and not ffmpeg_available():
        say(missing_ffmpeg(args.out) + "\n")
        return ExitCode.BAD_INPUT
    if robot is not None and not has_views(record):
        say(f"fatswarm plot: {NO_VIEWS}; robot {robot} is ringed, nobody is paled\n")
    say(f"fatswarm plot: {clip_line(clip, timeline.is_async, args.out)}\n")
    scene = Scene(record, timeline, clip, args.title, robot)
    written = False
    try:
        write_video(scene, args.out, Progress(sys.stderr))
        written = True
    except OSError as exc:
        say(f"fatswarm plot: cannot write {args.out}: {exc.strerror or exc}\n")
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
    "FLAGS",
    "Clip",
    "GifStream",
    "Scene",
    "Words",
    "add_animation_arguments",
    "lights_at",
    "main_animation",
    "missing_ffmpeg",
    "parse_rounds",
    "plan",
    "plan_clip",
    "plan_video",
    "routes_between",
    "say",
    "write_gif",
]
