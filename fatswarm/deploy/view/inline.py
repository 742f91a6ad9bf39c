"""Pictures in a notebook: a record (or a result that wrote one) animated inline, one round or one
robot's Look as a matplotlib Figure to restyle. The drawing is `fatswarm plot`'s (scene.py for the
frames, plot.py for the still pictures); nothing is printed, and no pyplot figure is left open.

    video = record.animate()          # Jupyter shows it: the GIF `fatswarm plot` would write
    fig = record.figure(round=5)      # the frame after round 5, a matplotlib Figure
    fig = record.look_figure(2, 5)    # robot 2's Look in round 5 (a record with --record-views)
"""

from __future__ import annotations

import base64
import html
import io
import numbers
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from fatswarm.deploy.view.animate import DEFAULT_MAX_FRAMES, Words, plan_video, write_gif
from fatswarm.deploy.view.lights import look_scene
from fatswarm.deploy.view.plot import look_figure as draw_look_figure
from fatswarm.deploy.view.plot import run_figure
from fatswarm.deploy.view.scene import Clip, Scene, still_clip, video_title
from fatswarm.world.record import RunRecord
from fatswarm.world.record_read import read_record
from fatswarm.world.timeline import Timeline

if TYPE_CHECKING:  # matplotlib is an optional extra, loaded only to draw
    from matplotlib.figure import Figure

KEYWORDS: Final = Words("fps", "speed", "rounds", "max_frames", "=", "a picture, figure(round=K)")
EXTRA: Final = "notebook"  # pip install 'fatswarm[notebook]' brings matplotlib


class PictureError(ValueError):
    """A picture that cannot be drawn as asked (a bad setting, a round or robot the record does
    not have, a result that wrote no record); its message is one line."""


@dataclass(frozen=True, slots=True, repr=False)
class InlineVideo:
    """A record's video, shown inline by Jupyter (`_repr_html_`: the GIF in an <img>): the same
    frames as `fatswarm plot RECORD OUT.gif` with the same settings. `gif`: the file's bytes."""

    gif: bytes
    frames: int
    fps: float
    title: str

    @property
    def seconds(self) -> float:
        """How long it plays."""
        return self.frames / self.fps

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the GIF to `path`."""
        with open(path, "wb") as out:
            out.write(self.gif)

    def _repr_html_(self) -> str:
        data = base64.b64encode(self.gif).decode("ascii")
        alt = html.escape(self.title.replace("\n", "; "), quote=True)
        return f'<img src="data:image/gif;base64,{data}" alt="{alt}"/>'

    def __repr__(self) -> str:
        return (
            f"InlineVideo(frames={self.frames}, fps={self.fps:g}, seconds={self.seconds:.1f}, "
            f"bytes={len(self.gif):,})"
        )


def record_of(source: object) -> RunRecord:
    """The record to draw: `source` itself, the record file it names (a path), or a result's
    `record` (the file `fatswarm.run(record=...)` wrote, or a record it holds)."""
    if isinstance(source, RunRecord):
        return source
    if isinstance(source, (str, os.PathLike)):
        return read_record(source, allow_torn_end=True)  # a crashed run draws too, as plot's
    if hasattr(source, "record"):
        held = source.record
        if held is None:
            raise PictureError(
                "this result wrote no record to draw: run it with record='run.jsonl'"
            )
        return record_of(held)
    raise PictureError(f"draws a record, a record's path or a result, got {type(source).__name__}")


def animate(
    source: object,
    *,
    fps: float | None = None,
    speed: float | None = None,
    rounds: str | tuple[int, int] | None = None,
    max_frames: int = DEFAULT_MAX_FRAMES,
    robot: int | None = None,
    title: str | None = None,
) -> InlineVideo:
    """The record of `source` as a video Jupyter shows inline: `fatswarm plot RECORD OUT.gif`'s
    frames, with its settings as keywords: `fps` (default 20, at most 50), `speed` (rounds, or
    async units of virtual time, per second of video; default 2, quicker for a long record),
    `rounds` ("A..B" or (A, B): those record lines only), `max_frames` (refuse a longer video),
    `robot` (ring it and, while it Looks, pale the robots it did not see), `title`. Raises
    PictureError (a ValueError) for a setting it cannot use, in one line."""
    record = record_of(source)
    timeline = Timeline(record)
    clip = plan_video(
        timeline, ".gif", _number("fps", fps), _number("speed", speed), _rounds(rounds),
        _whole("max_frames", max_frames), KEYWORDS,
    )  # fmt: skip
    if isinstance(clip, str):
        raise PictureError(clip)
    scene = _scene(record, timeline, clip, title, robot)
    sink = io.BytesIO()
    frames = write_gif(scene, sink)
    return InlineVideo(sink.getvalue(), frames, clip.fps, title or video_title(record))


def figure(
    source: object, round: int | None = None, *, robot: int | None = None, title: str | None = None
) -> Figure:
    """A matplotlib Figure of the record of `source`, returned (not shown, not closed) for the
    caller to restyle: `round` None, the whole run as `fatswarm plot RECORD OUT.png` draws it
    (routes, start and end, the final circle); `round` k, the video's frame after record line k
    (0: the start), with the paths travelled so far, and `robot` ringed as in `animate`."""
    record = record_of(source)
    _matplotlib()
    if round is None:
        if robot is not None:
            raise PictureError("robot= goes with round=K (the frame after round K)")
        return run_figure(record, title)
    timeline = Timeline(record)
    count = len(timeline.ends)
    line = _whole("round", round)
    if not 0 <= line <= count:
        raise PictureError(f"round must be between 0 (the start) and {count}, got {round!r}")
    return _scene(record, timeline, still_clip(timeline, line), title, robot).fig


def look_figure(source: object, robot: int, round: int, *, title: str | None = None) -> Figure:
    """Robot `robot`'s Look in record line `round` as a matplotlib Figure (`fatswarm plot RECORD
    OUT.png --robot I --round K`): every robot where it was then, what it saw, its sight, the
    move it made or why its compute failed. Needs a record made with `record_views=True`."""
    record = record_of(source)
    _matplotlib()
    who, line = _whole("robot", robot), _whole("round", round)
    if not 0 <= who < record.header.n:
        raise PictureError(f"robot must be between 0 and {record.header.n - 1}, got {robot!r}")
    scene = look_scene(record, who, line)
    if isinstance(scene, str):
        raise PictureError(scene)
    return draw_look_figure(record, scene, title)


def _scene(
    record: RunRecord, timeline: Timeline, clip: Clip, title: str | None, robot: int | None
) -> Scene:
    """The frames' scene, once the settings are checked and matplotlib is there."""
    _matplotlib()
    if robot is not None:
        robot = _whole("robot", robot)
        if not 0 <= robot < record.header.n:
            raise PictureError(f"robot must be between 0 and {record.header.n - 1}, got {robot}")
    return Scene(record, timeline, clip, title, robot)


def _matplotlib() -> None:
    """ImportError in one line, naming the extra, when matplotlib is not installed."""
    try:
        import matplotlib  # noqa: F401  (an optional extra: only the pictures need it)
    except ImportError:
        raise ImportError(
            f"pictures need matplotlib: pip install 'fatswarm[{EXTRA}]' (or matplotlib)"
        ) from None


def _number(name: str, value: object) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise PictureError(f"{name} must be a number, got {value!r}")
    return float(value)


def _whole(name: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise PictureError(f"{name} must be an int, got {value!r}")
    return int(value)


def _rounds(value: object) -> str | None:
    """`rounds` as the command's `A..B`."""
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, tuple) and len(value) == 2:
        first, last = (_whole("rounds", v) for v in value)
        return f"{first}..{last}"
    raise PictureError(f"rounds must be 'A..B' or (A, B), got {value!r}")


__all__ = ["InlineVideo", "PictureError", "animate", "figure", "look_figure", "record_of"]
