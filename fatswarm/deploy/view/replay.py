"""`fatswarm replay RECORD`: play a run record in the dashboard, without Zenoh.

The record (JSON Lines, issue 2 item 8) becomes one `Frame` per round (round 0 is the start); a
small pure `Player` turns keys and elapsed time into the round shown; the terminal shell draws it.
The algorithm's figures are computed for the rounds shown, by loading the record's algorithm.
"""

from __future__ import annotations

import argparse
import math
import os
import select
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

from rich.console import Console

from fatswarm.deploy.view.dashboard import Frame, print_frame, render_frame, save_svg
from fatswarm.deploy.view.lights import (
    NO_VIEWS,
    focus_per_round,
    has_views,
    lights_of,
    record_palette,
)
from fatswarm.deploy.view.summary import model_notes
from fatswarm.domain.figures import RunFolder, known_numbers
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.path import Points, sample, truncate
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import short_of_header
from fatswarm.domain.seam import AlgorithmError, AlgorithmFailure, AlgorithmParamsError, Configured
from fatswarm.world.record import Header, RecordFormatError, RunRecord, move_origin
from fatswarm.world.record_read import read_record, torn_end_note

TRAIL_STEP = 0.25  # world units between samples of a drawn path (a quarter of a robot radius)

FiguresOf = Callable[[Points], dict[str, float]]  # (n, 2) positions -> the algorithm's figures


def build_frames(record: RunRecord, source: str = "replay") -> list[Frame]:
    """One frame per round, round 0 being the start; the last carries the result's status. No
    figures: `FrameFigures` adds them to the frames shown."""
    run = record.header
    n = run.n
    last_active = [-1] * n
    last_length = [0.0] * n
    collisions_total = 0
    positions = run.initial
    last_round = record.rounds[-1].round if record.rounds else 0
    palette = record_palette(record)
    model = short_of_header(run.extra.get("model"))  # the robot model in one word

    def frame(**fields: Any) -> Frame:
        return Frame(
            n=n, algorithm=run.algorithm, params=dict(run.params), scheduler=run.scheduler,
            seed=run.seed, source=source,
            last_active=tuple(last_active), last_path_length=tuple(last_length),
            last_round=last_round, palette=palette, model=model, **fields,
        )  # fmt: skip

    frames = [frame(round=0, positions=positions)]
    so_far = RunFolder()  # the run's derived figures so far (min_gap: the least yet)
    for rr in record.rounds:
        trails = []
        for move in rr.moves:
            robot, path, traveled = move.robot, move.path, move.traveled
            start = move_origin(rr, robot, positions)
            covered = truncate(start, path, traveled) if math.isfinite(traveled) else path
            if covered:
                trails.append(sample(start, covered, TRAIL_STEP))
            last_length[robot] = traveled if math.isfinite(traveled) else 0.0
        for robot in rr.active:
            last_active[robot] = rr.round
        collisions_total += len(rr.collisions)
        positions = rr.positions
        so_far.add(positions, rr.round, rr.extra)
        frames.append(
            frame(
                round=rr.round,
                positions=positions,
                active=rr.active,
                moved=tuple(sorted(m.robot for m in rr.moves if m.path)),
                stopped=tuple(sorted({c.robot for c in rr.collisions})),
                collisions_total=collisions_total,
                trails=tuple(trails),
                lights=lights_of(rr, n) or (),
                derived=known_numbers(so_far.snapshot()),
            )
        )
    if record.result is not None:
        frames[-1] = replace(frames[-1], status=record.result.status)
    else:  # the run stopped, or still runs, after its last round line: not "running" here
        frames[-1] = replace(frames[-1], unfinished=True)
    return frames


def focus_on(frames: Sequence[Frame], record: RunRecord, robot: int) -> list[Frame]:
    """The frames of `build_frames` with what `robot` saw in each round (`--robot`)."""
    return [
        replace(frame, focus=focus)
        for frame, focus in zip(frames, focus_per_round(record, robot), strict=True)
    ]


def figures_of(header: Header, warn: Callable[[str], None]) -> FiguresOf | None:
    """The record's algorithm's figures hook, for its n and parameters; None (and one line to
    `warn`) when the algorithm cannot be loaded here, e.g. a file of someone else's."""
    try:
        configured = Configured.of(load_algorithm(header.algorithm_ref), header.n, header.params)
    except (AlgorithmError, AlgorithmParamsError) as exc:
        reason = " ".join(str(exc).split())  # one line, whatever the message holds
        warn(f"replaying without the figures of {header.algorithm_ref!r}: {reason}")
        return None
    return configured.figures


class FrameFigures:
    """Adds the algorithm's figures to the frames shown, each computed once; if the hook raises,
    says so once to `warn` and shows no more figures."""

    def __init__(self, figures: FiguresOf | None, warn: Callable[[str], None]) -> None:
        self.figures, self.warn = figures, warn
        self._done: dict[int, dict[str, float]] = {}

    def __call__(self, frame: Frame) -> Frame:
        """`frame` with its figures (as it is, without a hook)."""
        if self.figures is None:
            return frame
        if frame.round not in self._done:
            try:
                self._done[frame.round] = self.figures(frame.positions)
            except Exception as exc:  # the algorithm's own code: a replay must not die of it
                self.figures = None
                said = (
                    str(exc)
                    if isinstance(exc, AlgorithmFailure)
                    else (f"the algorithm's figures hook raised {type(exc).__name__}: {exc}")
                )
                self.warn(f"replaying without figures: {' '.join(said.split())}")
                return frame
        return replace(frame, figures=self._done[frame.round])


# --- the player: pure state of what is shown ------------------------------------------------------

SPEEDS = (0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0)
_STEP_KEYS = {"right": 1, "l": 1, ".": 1, "left": -1, "h": -1, ",": -1}  # a round on, back
_SPEED_KEYS = {"up": 1, "+": 1, "=": 1, "down": -1, "-": -1, "_": -1}  # faster, slower


@dataclass(slots=True)
class Player:
    """Which frame is shown, whether it plays and how fast; keys and elapsed time move it."""

    count: int  # number of frames
    index: int = 0
    playing: bool = True
    speed: float = 10.0  # rounds per second while playing
    quit: bool = False
    marks: tuple[int, ...] = ()  # frames `[` and `]` jump between: the chosen robot's Looks
    _carry: float = 0.0  # fraction of a round accumulated between ticks

    def key(self, key: str) -> None:
        """Apply one key: space, left/right, up/down, +/-, home/end, g/G, [/], q."""
        if key in ("q", "Q", "esc"):
            self.quit = True
        elif key == " ":
            self.playing = not self.playing
            if self.playing and self.index >= self.count - 1:
                self.index = 0
        elif key in _STEP_KEYS:
            step = self.index + _STEP_KEYS[key]
            self.playing, self.index = False, min(self.count - 1, max(0, step))
        elif key in _SPEED_KEYS:
            self._change_speed(faster=_SPEED_KEYS[key] > 0)
        elif key in ("home", "g"):
            self.index = 0
        elif key in ("end", "G"):
            self.index = self.count - 1
        elif key in ("[", "]"):
            self._jump(forward=key == "]")

    def _change_speed(self, faster: bool) -> None:
        """One step up (down) the SPEEDS ladder, staying at its end."""
        if faster:
            self.speed = next((s for s in SPEEDS if s > self.speed), self.speed)
        else:
            self.speed = next((s for s in reversed(SPEEDS) if s < self.speed), self.speed)

    def _jump(self, forward: bool) -> None:
        """Pause at the next (previous) marked frame, if there is one."""
        after = [m for m in self.marks if m > self.index]
        before = [m for m in self.marks if m < self.index]
        if forward and after:
            self.playing, self.index = False, after[0]
        elif not forward and before:
            self.playing, self.index = False, before[-1]

    def tick(self, seconds: float) -> None:
        """Advance playback by `seconds` of wall time; stops at the last frame."""
        if not self.playing:
            self._carry = 0.0
            return
        self._carry += seconds * self.speed
        steps = int(self._carry)
        self._carry -= steps
        self.index = min(self.count - 1, self.index + steps)
        if self.index >= self.count - 1:
            self.playing = False

    def footer(self) -> str:
        """Key help and playback state for the bottom lines (wrapped there, never cut)."""
        state = "playing" if self.playing else "paused"
        return (
            f"[{state} x{self.speed:g} rounds/s]  space play/pause  ←/→ step  "
            "+/- speed  g/G first/last  " + ("[/] its Looks  " if self.marks else "") + "q quit"
        )


KEYS_HELP = (
    "Keys while it plays: space play/pause; → or l or . one round on, ← or h or , one round "
    "back; + or ↑ faster, - or ↓ slower; g or Home the start, G or End the last round; [ and ] "
    "robot I's previous and next Look (with --robot); q or Esc quit. Off a terminal (standard "
    "input or output not one) it prints one frame, as --no-play does."
)


_SEQUENCES = {
    "\x1b[C": "right",
    "\x1b[D": "left",
    "\x1b[A": "up",
    "\x1b[B": "down",
    "\x1b[H": "home",
    "\x1b[F": "end",
    "\x1b[1~": "home",
    "\x1b[4~": "end",
    "\x1bOC": "right",
    "\x1bOD": "left",
    "\x1bOA": "up",
    "\x1bOB": "down",
}


def parse_keys(data: str) -> list[str]:
    """Split raw terminal input into key names (arrows and home/end by name, else the character)."""
    keys: list[str] = []
    i = 0
    while i < len(data):
        if data[i] == "\x1b":
            for seq, name in _SEQUENCES.items():
                if data.startswith(seq, i):
                    keys.append(name)
                    i += len(seq)
                    break
            else:
                keys.append("esc")
                i += 1
            continue
        keys.append(data[i])
        i += 1
    return keys


@contextmanager
def _cbreak(fd: int) -> Iterator[None]:
    # POSIX only, and only to play interactively: the CLI imports this module on any system to
    # build its parser, and --no-play needs neither
    import termios
    import tty

    saved = termios.tcgetattr(fd)
    try:
        tty.setcbreak(fd)
        yield
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)


def _read_keys(fd: int, timeout: float) -> list[str]:
    ready, _, _ = select.select([fd], [], [], timeout)
    if not ready:
        return []
    data = os.read(fd, 64)
    if not data:
        return ["q"]  # end of input
    return parse_keys(data.decode("utf-8", errors="ignore"))


def play(
    frames: Sequence[Frame], player: Player, shown_as: Callable[[Frame], Frame] = lambda f: f
) -> Frame:
    """Show the frames (each through `shown_as`) interactively until q; returns the last shown."""
    # rich's Live machinery loads only when a replay plays: the CLI imports this module to build
    # its parser
    from rich.live import Live

    console = Console()
    fd = sys.stdin.fileno()
    shown = -1
    with _cbreak(fd), Live(console=console, screen=True, auto_refresh=False) as live:
        last = time.monotonic()
        while not player.quit:
            if shown != player.index or player.playing:
                size = console.size  # as it is now: the terminal may have been resized
                shown_frame = shown_as(frames[player.index])
                live.update(
                    render_frame(
                        shown_frame, footer=player.footer(), screen=(size.width, size.height)
                    )
                )
                live.refresh()
                shown = player.index
            wait = 0.05 if player.playing else 0.5
            for key in _read_keys(fd, wait):
                player.key(key)
                shown = -1
            now = time.monotonic()
            player.tick(now - last)
            last = now
    frame = shown_as(frames[player.index])
    print_frame(frame, console)
    return frame


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm replay`."""
    p.description = "play a run record in the dashboard, a frame per round. " + KEYS_HELP
    p.add_argument("record", metavar="RECORD", help="run record (JSON Lines) to play")
    p.add_argument("--round", type=int, metavar="K", help="start at round K (0 is the start)")
    p.add_argument(
        "--speed", type=float, default=10.0, metavar="R", help="rounds per second (default 10)"
    )
    p.add_argument(
        "--svg",
        metavar="PATH",
        help="save the frame shown at the end as SVG (PATH.svg, in a folder that exists)",
    )
    p.add_argument(
        "--no-play",
        action="store_true",
        help="print one frame (round K, else the last) instead of playing",
    )
    p.add_argument(
        "--robot",
        type=int,
        metavar="I",
        help="highlight robot I and, in each round it Looked, the robots it saw (others dimmed; "
        "needs a record made with --record-views); keys [ and ] jump between its Looks",
    )


def main(args: argparse.Namespace) -> int:
    """`fatswarm replay`: interactive on a terminal, otherwise one frame printed."""
    try:
        record = read_record(args.record, allow_torn_end=True)  # a crashed run shows too
    except RecordFormatError as exc:
        print(f"fatswarm replay: {exc}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    note = torn_end_note(args.record, record)
    if note is not None:
        print(f"fatswarm replay: {note}", file=sys.stderr)
    frames = build_frames(record, source=f"replay {os.path.basename(args.record)}")

    def warn(line: str) -> None:
        print(f"fatswarm replay: {line}", file=sys.stderr)

    refused = _refused(args, frames)
    if refused is not None:
        print(f"fatswarm replay: {refused}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    for line in _notes(args, record):
        warn(line)
    if record.result is None and note is None:  # a torn end's note said why already
        last = record.rounds[-1].round if record.rounds else 0
        warn(
            f"the record has no result line: the run stopped after round {last} without "
            "finishing (interrupted, killed, or still being written)"
        )
    if args.robot is not None:
        frames = focus_on(frames, record, args.robot)
    index = len(frames) - 1
    if args.round is not None:
        index = next(i for i, f in enumerate(frames) if f.round >= args.round)
    frame = _show(args, frames, index, FrameFigures(figures_of(record.header, warn), warn))
    if args.svg:
        try:
            save_svg(frame, args.svg)
        except OSError as exc:
            print(f"fatswarm replay: cannot write {args.svg}: {exc.strerror}", file=sys.stderr)
            return ExitCode.BAD_INPUT
    return ExitCode.OK


def _notes(args: argparse.Namespace, record: RunRecord) -> list[str]:
    """Lines to say before the record shows: its robot model when it is not the paper's, the
    header's `assumption`, and that --robot needs views the record does not hold."""
    model, assumption = model_notes(record.header.extra)
    notes = [f"model: {model}"] if model else []
    notes += [assumption] if assumption else []
    if args.robot is not None and not has_views(record):
        notes.append(NO_VIEWS)
    return notes


def _refused(args: argparse.Namespace, frames: Sequence[Frame]) -> str | None:
    """Why --round or --speed cannot be used with these frames (None: they can)."""
    if args.round is not None and not 0 <= args.round <= frames[-1].round:
        return f"--round must be between 0 and {frames[-1].round}, got {args.round}"
    if not (args.speed > 0 and math.isfinite(args.speed)):
        return "--speed must be a positive number"
    n = frames[0].n
    if args.robot is not None and not 0 <= args.robot < n:
        return f"--robot must be a robot number between 0 and {n - 1}, got {args.robot}"
    return None if args.svg is None else svg_refused(args.svg)


def svg_refused(path: str) -> str | None:
    """Why --svg PATH cannot be written, said before the replay rather than after it."""
    if not path.lower().endswith(".svg"):
        return f"--svg writes SVG: PATH must end in .svg, got {path!r}"
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        return f"--svg: cannot write {path}: no folder {folder}"
    if os.path.isdir(path):
        return f"--svg: cannot write {path}: it is a folder"
    if not os.access(folder, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        return f"--svg: cannot write {path}: permission denied"
    return None


def _show(
    args: argparse.Namespace, frames: Sequence[Frame], index: int, shown_as: FrameFigures
) -> Frame:
    """Play the frames on a terminal (from `index` with --round, else from the start), or print
    the frame at `index`; the frame shown at the end."""
    interactive = not args.no_play and sys.stdin.isatty() and sys.stdout.isatty()
    if interactive:
        start = index if args.round is not None else 0
        marks = tuple(i for i, f in enumerate(frames) if f.focus is not None and f.focus.looked)
        player = Player(
            count=len(frames),
            index=start,
            playing=args.round is None,
            speed=args.speed,
            marks=marks,
        )
        return play(frames, player, shown_as)
    frame = shown_as(frames[index])
    print_frame(frame, Console(width=None if sys.stdout.isatty() else 120), height=40)
    return frame
