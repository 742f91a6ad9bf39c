"""Terminal dashboard: pure renderers from a `Frame` plus the thin shells that feed them.

`render_frame(frame)` builds a rich renderable (canvas to scale, counters, agents, outcome) from a
plain dataclass, so tests and replay need no network. `StateWatcher` follows the world's published
state (`fatswarm/<swarm>/world/state`) through a ring channel of one: it never slows the round.
It knows no algorithm: it shows the run's algorithm by name, its parameters and its figures.
"""

from __future__ import annotations

import argparse
import io
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np
from rich.console import Console, ConsoleOptions, RenderResult
from rich.layout import Layout
from rich.panel import Panel
from rich.progress_bar import ProgressBar
from rich.segment import Segment
from rich.style import Style
from rich.table import Table
from rich.text import Text

from fatswarm.agent import geometry
from fatswarm.deploy.view.canvas import Canvas, Mode, Viewport
from fatswarm.deploy.view.lights import (
    FOCUS_STYLE,
    LIGHT_HEX,
    SIGHT_STYLE,
    UNSEEN_STYLE,
    Focus,
    focus_legend,
    light_number,
    palette_legend,
)
from fatswarm.domain import tolerance
from fatswarm.domain.outcome import ENDED, Status
from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.seam import ParamValue

if TYPE_CHECKING:
    from fatswarm.world.protocol import WorldState

TARGET_RADIUS = "target radius"  # the figure that draws the paper's target points (see `Frame`)

# Canvas layers: where several meet in one cell, the highest number wins. A robot in a colour
# (lights) is drawn on LAYER_LIGHT + k, k its colour's number (`lights.light_number`).
LAYER_SEC, LAYER_TARGET_CIRCLE, LAYER_SIGHT, LAYER_TRAIL, LAYER_TARGET = 1, 2, 3, 4, 5
LAYER_UNSEEN, LAYER_ROBOT, LAYER_ACTIVE, LAYER_STOPPED = 6, 7, 8, 9
LAYER_LIGHT = 10
LAYER_FOCUS = LAYER_LIGHT + len(LIGHT_HEX)
LAYER_STYLES: dict[int, str] = {
    LAYER_SEC: "grey50",
    LAYER_TARGET_CIRCLE: "blue",
    LAYER_SIGHT: SIGHT_STYLE,
    LAYER_TRAIL: "magenta",
    LAYER_TARGET: "bold yellow",
    LAYER_UNSEEN: UNSEEN_STYLE,
    LAYER_ROBOT: "green",
    LAYER_ACTIVE: "bold cyan",
    LAYER_STOPPED: "bold red",
    **{LAYER_LIGHT + k: colour for k, colour in enumerate(LIGHT_HEX)},
    LAYER_FOCUS: FOCUS_STYLE,
}
_LAYER_STYLES = {layer: Style.parse(style) for layer, style in LAYER_STYLES.items()}
LEGEND_ROBOTS = "[green]idle[/] [bold cyan]active[/] [bold red]stopped[/] "  # without lights
LEGEND = LEGEND_ROBOTS + "[magenta]path[/] [grey50]SEC[/]"
LEGEND_TARGETS = " [blue]circle r[/] [bold yellow]targets[/]"
ROBOT_RADIUS = 1.0  # robots are unit discs
SIDE_WIDTH = 46  # columns of the counters and agents column
KEY_WIDTH = 14  # at most, of the counters' labels (an algorithm's figure may have a long one)
PROGRESS_EVERY = 50  # rounds between two progress lines when output is not a terminal
MAX_DUTY = 10  # the live view draws for at most a tenth of the wall time (one core)
MAX_FIGURE_ROWS = 8  # figures shown as rows; a line says how many more there are
BELOW_FINAL_FRAME = 6  # lines left under the final frame: the run's summary and the prompt


@dataclass(frozen=True, slots=True, eq=False)
class Frame:
    """One dashboard frame, from a live `WorldState` or a record. Each of `figures` is a row; only
    a "target radius" figure (the paper's algorithm's) draws and counts its target points."""

    round: int
    n: int
    scheduler: str
    positions: Points  # (n, 2) world frame
    algorithm: str = DEFAULT_ALGORITHM  # its registered name
    params: dict[str, ParamValue] = field(default_factory=dict)  # its parameters
    figures: dict[str, float] = field(default_factory=dict)  # its `figures` hook, label -> value
    a: float | None = None  # the paper's side, as before `params`: the same as params["a"]
    active: tuple[int, ...] = ()  # robots active in `round`
    moved: tuple[int, ...] = ()
    stopped: tuple[int, ...] = ()  # stopped by contact in `round`
    collisions_total: int = 0
    status: Status = Status.RUNNING
    swarm: str = ""
    seed: int | None = None
    alive: tuple[bool, ...] | None = None  # None when unknown (a record holds no liveliness)
    last_active: tuple[int, ...] = ()  # round each robot was last active in, -1 if never
    last_path_length: tuple[float, ...] = ()  # length covered by its last applied move
    timeouts: tuple[int, ...] = ()  # rounds active without a move in time; empty when unknown
    rounds_per_second: float | None = None
    max_rounds: int | None = None
    last_round: int | None = None  # replay: the record's last round
    trails: tuple[Points, ...] = ()  # replay: sampled world paths (k, 2) of this round's moves
    lights: tuple[str, ...] = ()  # replay: each robot's colour name (empty: none known)
    palette: tuple[str, ...] = ()  # replay: the record's colour names, in the order drawn
    focus: Focus | None = None  # replay --robot: what the chosen robot saw in this round
    source: str = "live"

    def __post_init__(self) -> None:
        side = self.params.get("a")
        if self.a is None and isinstance(side, (int, float)) and not isinstance(side, bool):
            object.__setattr__(self, "a", float(side))
        elif self.a is not None and "a" not in self.params:
            object.__setattr__(self, "params", {**self.params, "a": self.a})


@dataclass(frozen=True, slots=True)
class Derived:
    """What a frame derives from its positions: the SEC and, with a target radius, the targets."""

    sec_center: tuple[float, float]
    sec_radius: float  # r_c
    target_radius: float | None  # r, the "target radius" figure; None: no target points
    targets: Points  # (n, 2) target points on the current SEC, (0, 2) without a target radius
    filled: int | None  # target points with a robot centre on them; None without targets


def enclosing_circle(points: Points) -> tuple[tuple[float, float], float]:
    """Centre and radius of the smallest circle enclosing the centres.

    Computed relative to the first robot: the circle's rounding slack is relative to its radius,
    so world coordinates far from the origin (1e5 and more) would swamp it.
    """
    if not len(points):
        return (0.0, 0.0), 0.0
    origin = points[0]
    circle = geometry.sec(points - origin)
    cx, cy = circle.center
    return (float(cx + origin[0]), float(cy + origin[1])), float(circle.radius)


def derive(frame: Frame) -> Derived:
    """The SEC of the positions (any algorithm); the paper's target points and how many are filled
    only when the frame's figures give a "target radius"."""
    pts = np.asarray(frame.positions, dtype=np.float64).reshape(-1, 2)
    center, rc = enclosing_circle(pts)
    radius = frame.figures.get(TARGET_RADIUS)
    if radius is None or not len(pts):
        return Derived(center, rc, radius, np.zeros((0, 2)), None)
    targets = geometry.target_points(pts - pts[0], frame.n) + pts[0]
    tol = tolerance.EPS_AT_REL * tolerance.scale(rc)  # "a robot at the point", as the algorithm
    dist = np.hypot(*(targets[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
    filled = int(np.count_nonzero(dist.min(axis=1) <= tol)) if len(targets) else 0
    return Derived(center, rc, radius, targets, filled)


def algorithm_text(algorithm: str, params: dict[str, ParamValue]) -> str:
    """`uniform-circle a=4`: the algorithm's name and its parameters."""
    shown = " ".join(
        f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.items()
    )
    return f"{algorithm} {shown}".strip()


def figure_text(value: float) -> str:
    """A figure as the counters show it: three decimals, or four significant digits far from 1."""
    if value != 0 and not 1e-3 <= abs(value) < 1e6:
        return f"{value:.4g}"
    return f"{value:.3f}"


# --- canvas ---------------------------------------------------------------------------------------


def build_canvas(
    frame: Frame, derived: Derived, cols: int, rows: int, mode: Mode = "braille"
) -> Canvas:
    """Draw the frame to scale: SEC, paths and discs (and the paper's circle r and targets)."""
    pts = np.asarray(frame.positions, dtype=np.float64).reshape(-1, 2)
    (cx, cy), rc = derived.sec_center, derived.sec_radius
    r = derived.target_radius if derived.target_radius is not None else 0.0
    reach = max(rc, r) + ROBOT_RADIUS
    xmin, xmax = cx - reach, cx + reach
    ymin, ymax = cy - reach, cy + reach
    if len(pts):
        xmin, xmax = min(xmin, float(pts[:, 0].min()) - 1), max(xmax, float(pts[:, 0].max()) + 1)
        ymin, ymax = min(ymin, float(pts[:, 1].min()) - 1), max(ymax, float(pts[:, 1].max()) + 1)
    pad = 0.03 * max(xmax - xmin, ymax - ymin)
    canvas = Canvas(Viewport.fit(xmin - pad, xmax + pad, ymin - pad, ymax + pad, cols, rows, mode))
    canvas.circle(cx, cy, rc, LAYER_SEC)
    if r > 0:
        canvas.circle(cx, cy, r, LAYER_TARGET_CIRCLE)
    for trail in frame.trails:
        canvas.polyline(trail, LAYER_TRAIL)
    for x, y in derived.targets:
        canvas.marker(float(x), float(y), LAYER_TARGET)
    for (x, y), layer in zip(pts, robot_layers(frame, len(pts)), strict=True):
        canvas.disc(float(x), float(y), ROBOT_RADIUS, layer)
    focus = frame.focus
    if focus is not None and focus.looked and focus.origin is not None and focus.sight:
        canvas.circle(*focus.origin, focus.sight, LAYER_SIGHT)
    if focus is not None and 0 <= focus.robot < len(pts):
        x, y = pts[focus.robot]
        canvas.circle(float(x), float(y), 1.6 * ROBOT_RADIUS, LAYER_FOCUS)
    return canvas


def robot_layers(frame: Frame, count: int) -> list[int]:
    """The layer of each robot's disc: its colour when the frame has lights, else stopped, active
    or idle; the unseen layer when the chosen robot Looked this round and did not see it."""
    active, stopped = set(frame.active), set(frame.stopped)
    layers = []
    for i in range(count):
        colour = light_number(frame.palette, frame.lights[i] if i < len(frame.lights) else None)
        if frame.focus is not None and frame.focus.dims(i):
            layers.append(LAYER_UNSEEN)
        elif colour is not None:
            layers.append(LAYER_LIGHT + colour)
        else:
            idle = LAYER_ACTIVE if i in active else LAYER_ROBOT
            layers.append(LAYER_STOPPED if i in stopped else idle)
    return layers


class CanvasView:
    """Renders the frame's canvas at whatever size rich gives it (braille by default)."""

    def __init__(self, frame: Frame, derived: Derived, mode: Mode = "braille") -> None:
        self.frame, self.derived, self.mode = frame, derived, mode
        self._cache: dict[tuple[int, int], list[Segment]] = {}

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        cols = max(1, options.max_width)
        rows = max(1, (options.height or options.size.height or 20))
        if (cols, rows) not in self._cache:  # rich may render a panel's content twice
            canvas = build_canvas(self.frame, self.derived, cols, rows, self.mode)
            self._cache[(cols, rows)] = list(canvas.segments(_LAYER_STYLES))
        yield from self._cache[(cols, rows)]


# --- counters, agents, outcome -------------------------------------------------------------------


def _fmt_rate(rate: float | None) -> str:
    return "-" if rate is None else f"{rate:,.1f}"


def outcome_text(frame: Frame) -> str:
    """One line saying how the run ended, or that it still runs."""
    k = frame.collisions_total
    reached = f"{frame.algorithm} goal reached by {frame.n} robots after {frame.round} rounds"
    if frame.status == Status.FORMED and k:
        return f"FORMED WITH {k} COLLISION{'' if k == 1 else 'S'}: {reached}, not collision-free"
    if frame.status == Status.FORMED:
        head = f"FORMED: {reached}"
    elif frame.status == Status.STALLED:
        head = f"STALLED after {frame.round} rounds: no robot can make progress"
    elif frame.status == Status.MAX_ROUNDS:
        head = f"NOT FORMED: stopped at the round limit ({frame.round} rounds)"
    else:
        return f"running: round {frame.round}"
    return f"{head}, {frame.collisions_total} collisions"


def run_lines(frame: Frame, width: int) -> list[str]:
    """`n=8  uniform-circle a=4`, parameters going on to further lines of at most `width`."""
    lines = [f"n={frame.n}  {frame.algorithm}"]
    for word in algorithm_text("", frame.params).split(" ") if frame.params else ():
        if len(lines[-1]) + 1 + len(word) <= width:
            lines[-1] += " " + word
        else:
            lines.append(word)
    return lines


def counters_table(frame: Frame, derived: Derived) -> Table:
    """Round, status, scheduler, algorithm, r_c (versus r, targets filled), figures, collisions."""
    grid = Table.grid(padding=(0, 1))
    grid.add_column("key", style="bold", no_wrap=True, max_width=KEY_WIDTH, overflow="ellipsis")
    grid.add_column("value", no_wrap=True, overflow="ellipsis")
    round_text = f"{frame.round}"
    if frame.last_round is not None:
        round_text += f" / {frame.last_round}"
    elif frame.max_rounds is not None:
        round_text += f" (limit {frame.max_rounds})"
    grid.add_row("round", round_text)
    grid.add_row("status", frame.status)
    grid.add_row(
        "scheduler", frame.scheduler + (f"  seed {frame.seed}" if frame.seed is not None else "")
    )
    keys = min(KEY_WIDTH, max([len("this round"), *(len(k) for k in frame.figures)]))
    for i, line in enumerate(run_lines(frame, SIDE_WIDTH - 4 - keys - 1)):  # borders, padding
        grid.add_row("" if i else "robots", Text(line))  # Text: a user's name is no markup
    r, rc = derived.target_radius, derived.sec_radius
    if r is None or derived.filled is None:
        grid.add_row("r_c", f"{rc:.3f}")
    else:
        grid.add_row("r_c / r", f"{rc:.3f} / {r:.3f}")
        grid.add_row("", ProgressBar(total=max(r, 1e-9), completed=min(rc, r), width=22))
        grid.add_row("targets", f"{derived.filled} / {frame.n} filled")
        grid.add_row("", ProgressBar(total=max(frame.n, 1), completed=derived.filled, width=22))
    shown = list(frame.figures.items())
    if len(shown) > MAX_FIGURE_ROWS:  # the counters must leave the agents panel some room
        shown = shown[: MAX_FIGURE_ROWS - 1]
    for label, value in shown:
        grid.add_row(Text(label), figure_text(value))  # Text: a label is no markup
    if len(shown) < len(frame.figures):
        grid.add_row("", Text(f"… {len(frame.figures) - len(shown)} more figures", style="dim"))
    counts = f"{len(frame.active)} active  {len(frame.moved)} moved  {len(frame.stopped)} stopped"
    grid.add_row("this round", counts)
    grid.add_row("collisions", str(frame.collisions_total))
    if frame.focus is not None:
        grid.add_row(f"robot {frame.focus.robot}", frame.focus.line())
    grid.add_row("rounds/s", _fmt_rate(frame.rounds_per_second))
    if frame.alive is not None:
        grid.add_row("alive", f"{sum(frame.alive)} / {frame.n}")
    if frame.timeouts:
        grid.add_row("timeouts", str(sum(frame.timeouts)))
    return grid


def agent_rows(frame: Frame) -> list[int]:
    """Robots in the order the agents panel lists them: this round's active, the gone, the rest."""
    first = [i for i in frame.active if 0 <= i < frame.n]
    seen = set(first)
    gone = [i for i in range(frame.n) if i not in seen and frame.alive and not frame.alive[i]]
    seen.update(gone)
    return first + gone + [i for i in range(frame.n) if i not in seen]


class AgentsView:
    """The agents list, cut to the rows that fit (with a line saying how many are left out).

    Fixed-width text rather than a rich Table: a Table of a few hundred cells costs tens of
    milliseconds a frame, and the dashboard must stay cheap next to the swarm it watches.
    """

    HEADER = f"{'robot':>5}  {'alive':<5}  {'last':>6}  {'path':>8}  {'t/o':>4}"

    def __init__(self, frame: Frame) -> None:
        self.frame = frame

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        f = self.frame
        height = options.height or 12
        fit = max(0, height - 2)  # header row and the "more" line
        order = agent_rows(f)
        shown = order if len(order) <= fit + 1 else order[:fit]
        active, stopped = set(f.active), set(f.stopped)
        text = Text(self.HEADER, style="bold", no_wrap=True, overflow="crop")
        for i in shown:
            alive = "-" if f.alive is None else ("yes" if f.alive[i] else "NO")
            last = f.last_active[i] if i < len(f.last_active) else -1
            length = f.last_path_length[i] if i < len(f.last_path_length) else 0.0
            timeouts = str(f.timeouts[i]) if i < len(f.timeouts) else "-"
            last_text = "never" if last < 0 else str(last)
            row = f"\n{i:>5}  {alive:<5}  {last_text:>6}  {length:>8.3f}  {timeouts:>4}"
            text.append(
                row, style="bold red" if i in stopped else "bold cyan" if i in active else ""
            )
        if len(shown) < len(order):
            text.append(f"\n… {len(order) - len(shown)} more robots", style="dim")
        yield text


def render_frame(frame: Frame, *, footer: str | None = None, mode: Mode = "braille") -> Layout:
    """The whole dashboard for one frame: header, canvas, counters, agents, outcome or key help."""
    derived = derive(frame)
    title = f"fatswarm · {frame.source}"
    if frame.swarm:
        title += f" · swarm {frame.swarm}"
    layout = Layout(name="root")
    bottom = outcome_text(frame)
    if footer:
        bottom = f"{bottom}    {footer}"
    if frame.status == Status.FORMED:
        style = "bold green" if frame.collisions_total == 0 else "bold yellow"
    else:
        style = "bold" if frame.status in ENDED else ""
    layout.split_column(
        Layout(Text(title, style="bold", no_wrap=True, overflow="ellipsis"), name="header", size=1),
        Layout(name="body"),
        Layout(
            Panel(Text(bottom, no_wrap=True, overflow="ellipsis"), style=style),
            name="footer",
            size=3,
        ),
    )
    legend = Text.from_markup(LEGEND)
    if frame.lights:  # the colours instead of idle, active and stopped
        legend = palette_legend(frame.palette) + Text.from_markup(LEGEND[len(LEGEND_ROBOTS) :])
    legend += focus_legend(frame.focus)
    if len(derived.targets):
        legend += Text.from_markup(LEGEND_TARGETS)
    canvas = Panel(
        CanvasView(frame, derived, mode), title="swarm, to scale", subtitle=legend, padding=0
    )
    counters = counters_table(frame, derived)
    layout["body"].split_row(
        Layout(canvas, name="canvas"),
        Layout(name="side", size=SIDE_WIDTH),
    )
    layout["side"].split_column(
        Layout(Panel(counters, title="run"), name="counters", size=counters.row_count + 2),
        Layout(Panel(AgentsView(frame), title="agents"), name="agents"),
    )
    return layout


def progress_line(frame: Frame) -> str:
    """The one-line progress report printed when standard output is not a terminal."""
    derived = derive(frame)
    r, rc = derived.target_radius, derived.sec_radius
    if r is None or derived.filled is None:
        parts = [f"r_c {rc:.3f}"]
    else:
        parts = [f"targets {derived.filled}/{frame.n}", f"r_c {rc:.3f} / r {r:.3f}"]
    parts += [f"{k} {figure_text(v)}" for k, v in frame.figures.items() if k != TARGET_RADIUS]
    return (
        f"round {frame.round} {frame.status}: {', '.join(parts)}, "
        f"active {len(frame.active)}, collisions {frame.collisions_total}, "
        f"{_fmt_rate(frame.rounds_per_second)} rounds/s"
    )


def print_frame(
    frame: Frame, console: Console, height: int | None = None, footer: str | None = None
) -> None:
    """Print one frame at a fixed height (the final frame left on a terminal, or a test render)."""
    h = height or min(console.size.height, 40)
    console.print(render_frame(frame, footer=footer), height=h)


def save_svg(
    frame: Frame, path: str, width: int = 120, height: int = 40, footer: str | None = None
) -> None:
    """Save one frame as SVG through rich's recording console."""
    console = Console(
        record=True, width=width, height=height, file=io.StringIO(), color_system="truecolor"
    )
    console.print(render_frame(frame, footer=footer), height=height)
    console.save_svg(path, title="fatswarm")


# --- live state -> frames ------------------------------------------------------------------------


def frame_from_state(
    state: WorldState, rounds_per_second: float | None = None, max_rounds: int | None = None
) -> Frame:
    """The frame showing a world's published state."""
    return Frame(
        round=state.round,
        n=state.n,
        scheduler=state.scheduler,
        positions=state.positions,
        algorithm=state.algorithm,
        params=dict(state.params),
        figures=dict(state.figures),
        active=tuple(state.active),
        moved=tuple(state.moved),
        stopped=tuple(state.stopped),
        collisions_total=state.collisions_total,
        status=state.status,
        swarm=state.swarm,
        alive=tuple(g.alive for g in state.agents),
        last_active=tuple(g.last_active for g in state.agents),
        last_path_length=tuple(g.last_path_length for g in state.agents),
        timeouts=tuple(g.timeouts for g in state.agents),
        rounds_per_second=rounds_per_second,
        max_rounds=max_rounds,
        source="live",
        lights=state.lights,
        palette=tuple(sorted(state.palette)),  # names sorted, as replay and plot colour them
    )


class RateMeter:
    """Rounds per second over a sliding window of (time, round) observations; time passed in."""

    def __init__(self, window: float = 2.0) -> None:
        self.window = window
        self.samples: deque[tuple[float, int]] = deque()

    def add(self, now: float, round_no: int) -> float | None:
        """Record that `round_no` was seen at `now`; the rate over the window, None until known."""
        if self.samples and round_no < self.samples[-1][1]:
            self.samples.clear()  # a new run (or a restarted world) on the same key
        self.samples.append((now, round_no))
        while len(self.samples) > 2 and now - self.samples[0][0] > self.window:
            self.samples.popleft()
        (t0, r0), (t1, r1) = self.samples[0], self.samples[-1]
        return (r1 - r0) / (t1 - t0) if t1 > t0 else None


class FrameSink(Protocol):
    """Something that shows frames: the live view or the plain progress log."""

    def show(self, frame: Frame) -> None: ...

    def close(self, final: Frame | None) -> None: ...


class ProgressLog:
    """Plain progress for a non-terminal: one line every `every` rounds and one at the end."""

    def __init__(self, out: Callable[[str], None] | None = None, every: int = 50) -> None:
        self.out = out or (lambda line: print(line, flush=True))
        self.every = max(1, every)
        self.next_round = 0
        self.last: Frame | None = None

    def show(self, frame: Frame) -> None:
        self.last = frame
        if frame.status in ENDED:
            return
        if frame.round >= self.next_round:
            self.out(progress_line(frame))
            self.next_round = (frame.round // self.every + 1) * self.every

    def close(self, final: Frame | None) -> None:
        frame = final or self.last
        if frame is not None:
            self.out(progress_line(frame))
            if frame.status in ENDED:
                self.out(outcome_text(frame))


class LiveView:
    """A rich Live view of the frames on the alternate screen; the last frame stays on exit."""

    def __init__(self, console: Console | None = None) -> None:
        # rich's Live machinery loads only when a live view starts: the CLI imports this module
        # to build its parser
        from rich.live import Live

        self.console = console or Console()
        self.last: Frame | None = None
        self.live = Live(
            Text("waiting for the swarm's state…"),
            console=self.console,
            screen=True,
            auto_refresh=False,
            redirect_stdout=False,
            redirect_stderr=False,
        )
        self.live.start(refresh=True)

    def show(self, frame: Frame) -> None:
        self.last = frame
        self.live.update(render_frame(frame), refresh=True)

    def close(self, final: Frame | None) -> None:
        self.live.stop()  # leaves the alternate screen, whose content the terminal drops
        frame = final or self.last
        if frame is not None:  # so print it on the main screen, leaving room for the summary
            height = min(self.console.size.height, 40)
            height = max(min(height, 16), height - BELOW_FINAL_FRAME)
            print_frame(frame, self.console, height)


# --- command line --------------------------------------------------------------------------------


def add_run_arguments(p: argparse.ArgumentParser) -> None:
    """Flags `fatswarm run` takes for its display (`--no-dashboard`, `--svg`).

    Not named `add_dashboard_arguments`: the CLI takes `add_<command>_arguments` of a module
    first, so that name would give `fatswarm dashboard` the flags of `fatswarm run`.
    """
    p.add_argument(
        "--no-dashboard",
        action="store_true",
        help="print a progress line every few rounds instead of the live dashboard",
    )
    p.add_argument("--svg", metavar="PATH", help="save the final dashboard frame as SVG")
