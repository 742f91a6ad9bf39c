"""Terminal dashboard: pure renderers from a `Frame` plus the thin shells that feed them.

`render_frame(frame)` builds a rich renderable (canvas to scale, counters, agents, outcome) from a
plain dataclass, so tests and replay need no network; the text around the canvas (and the `Frame`
itself) lives in deploy/view/panels.py, and is taken from here as well. `StateWatcher` follows
the world's published state (`fatswarm/<swarm>/world/state`) through a ring channel of one: it
never slows the round. It knows no algorithm: it shows the run's algorithm by name, its
parameters and its figures."""

from __future__ import annotations

import argparse
import io
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

import numpy as np
from rich.console import Console, ConsoleOptions, RenderableType, RenderResult
from rich.layout import Layout
from rich.panel import Panel
from rich.segment import Segment
from rich.style import Style
from rich.text import Text

from fatswarm.deploy.view.canvas import Canvas, Mode, Viewport
from fatswarm.deploy.view.lights import (
    FOCUS_STYLE,
    LIGHT_HEX,
    SIGHT_STYLE,
    UNSEEN_STYLE,
    focus_legend,
    light_number,
    palette_legend,
)
from fatswarm.deploy.view.panels import (
    MAX_FIGURE_ROWS,
    MIN_SIZE,
    SIDE_WIDTH,
    TARGET_RADIUS,
    Derived,
    Frame,
    SideView,
    agent_rows,
    agents_height,
    algorithm_text,
    derive,
    enclosing_circle,
    essentials,
    essentials_line,
    figure_text,
    fmt_rate,
    footer_lines,
    outcome_text,
    run_lines,
    too_small,
)
from fatswarm.domain.outcome import ENDED, Status
from fatswarm.domain.words import unit, units

if TYPE_CHECKING:
    from fatswarm.world.observers import WorldState

# Canvas layers: where several meet in one cell, the highest number wins. A robot in a colour
# (lights) is drawn on LAYER_LIGHT + k, k its colour's number (`lights.light_number`).
LAYER_SEC, LAYER_TARGET_CIRCLE, LAYER_SIGHT, LAYER_TRAIL, LAYER_TARGET = 1, 2, 3, 4, 5
LAYER_UNSEEN, LAYER_ROBOT, LAYER_ACTIVE, LAYER_STOPPED = 6, 7, 8, 9
LAYER_LIGHT = 10
LAYER_FOCUS = LAYER_LIGHT + len(LIGHT_HEX)
LAYER_STYLES: dict[int, str] = {
    LAYER_SEC: "grey50",
    LAYER_TARGET_CIRCLE: "bright_blue",  # plain blue is too dim on a dark terminal
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
LEGEND_TARGETS = " [bright_blue]circle r[/] [bold yellow]targets[/]"
ROBOT_RADIUS = 1.0  # robots are unit discs
GAP_DOTS = 1.5  # dots kept clear of circles and paths around each disc, so robots stand out
PROGRESS_EVERY = 50  # rounds between two progress lines when output is not a terminal
MAX_DUTY = 10  # the live view draws for at most a tenth of the wall time (one core)
BELOW_FINAL_FRAME = 6  # lines left under the final frame: the run's summary and the prompt


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
    layers = robot_layers(frame, len(pts))
    gap = ROBOT_RADIUS + GAP_DOTS * canvas.viewport.units_per_dot
    canvas.clear_discs(pts, gap, below=LAYER_TARGET)  # a margin: circles and paths stop short
    for (x, y), layer in zip(pts, layers, strict=True):
        canvas.disc(float(x), float(y), ROBOT_RADIUS, layer)
    focus = frame.focus
    if focus is not None and focus.looked and focus.origin is not None and focus.sight:
        canvas.circle(*focus.origin, focus.sight, LAYER_SIGHT)
    if focus is not None and 0 <= focus.robot < len(pts):
        x, y = pts[focus.robot]
        canvas.circle(float(x), float(y), 1.6 * ROBOT_RADIUS, LAYER_FOCUS)
    for i, ((x, y), layer) in enumerate(zip(pts, layers, strict=True)):  # ids where they fit
        canvas.label(float(x), float(y), ROBOT_RADIUS, str(i), layer)
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


# --- the whole frame ------------------------------------------------------------------------------


def render_frame(
    frame: Frame,
    *,
    footer: str | None = None,
    mode: Mode = "braille",
    screen: tuple[int, int] | None = None,
    height: int | None = None,
) -> RenderableType:
    """The whole dashboard for one frame: header, canvas, counters, agents, then the outcome and
    the key help (`footer`), wrapped to the terminal's width. `screen`: the terminal's (columns,
    rows); below MIN_SIZE the frame is a few lines saying so (`panels.too_small`). `height`: the
    rows it is printed in, if fewer than the screen's (the final frame left above the summary):
    too few for the essential counters beside the agents, the header line says them first."""
    title = f"fatswarm · {frame.source}"
    if frame.swarm:
        title += f" · swarm {frame.swarm}"
    cols, rows = screen or (120, 40)
    if cols < MIN_SIZE[0] or rows < MIN_SIZE[1]:
        return too_small(frame, title, footer, (cols, rows))
    derived = derive(frame)
    if frame.status == Status.FORMED:
        style = "bold green" if frame.collisions_total == 0 else "bold yellow"
    else:
        style = "bold" if frame.status in ENDED else ""
    bottom = footer_lines(frame, footer, cols)
    body = (height or rows) - 1 - (len(bottom) + 2)
    counters = body - agents_height(frame.n) - 2 >= essentials(frame)
    if not counters:  # the essential counters first: the title is what may be cut
        title = f"{essentials_line(frame)} · {title}"
    layout = Layout(name="root")
    layout.split_column(
        Layout(Text(title, style="bold", no_wrap=True, overflow="ellipsis"), name="header", size=1),
        Layout(name="body"),
        Layout(Panel(Text("\n").join(bottom), style=style), name="footer", size=len(bottom) + 2),
    )
    layout["body"].split_row(
        Layout(canvas_panel(frame, derived, mode, cols - SIDE_WIDTH), name="canvas"),
        Layout(SideView(frame, derived, counters), name="side", size=SIDE_WIDTH),
    )
    return layout


def canvas_panel(frame: Frame, derived: Derived, mode: Mode, width: int | None = None) -> Panel:
    """The canvas in its panel, with a legend of what its colours mean: on the bottom border
    where it fits in the panel's `width` (columns, None: it does), else whole on lines of its
    own under the canvas (a border would cut it mid-word)."""
    legend = canvas_legend(frame, derived)
    if width is None or legend.cell_len <= width - 4:  # the corners and a space each side
        return Panel(
            CanvasView(frame, derived, mode), title="swarm, to scale", subtitle=legend, padding=0
        )
    return Panel(CanvasLegend(CanvasView(frame, derived, mode), legend), title="swarm, to scale")


def canvas_legend(frame: Frame, derived: Derived) -> Text:
    """What the canvas's colours mean, in one line of words."""
    legend = Text.from_markup(LEGEND)
    if frame.lights:  # the colours instead of idle, active and stopped
        legend = palette_legend(frame.palette) + Text.from_markup(LEGEND[len(LEGEND_ROBOTS) :])
    legend += focus_legend(frame.focus)
    if len(derived.targets):
        legend += Text.from_markup(LEGEND_TARGETS)
    return legend


class CanvasLegend:
    """The canvas above its legend, the legend's words on as many whole lines as it takes."""

    def __init__(self, canvas: CanvasView, legend: Text) -> None:
        self.canvas, self.legend = canvas, legend

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        width = max(1, options.max_width)
        lines = legend_lines(self.legend, width)
        height = options.height or options.size.height or 20
        rows = max(1, height - len(lines))
        yield from console.render(self.canvas, options.update(height=rows))
        for line in lines[: max(0, height - rows)]:
            line.align("center", width)
            yield from console.render(line, options.update(height=1, no_wrap=True))


def legend_lines(legend: Text, width: int) -> list[Text]:
    """The legend's words (each keeps its style) packed on lines of at most `width` columns."""
    lines: list[Text] = []
    for word in legend.split(" "):
        if not word.plain:
            continue
        if lines and lines[-1].cell_len + 1 + word.cell_len <= width:
            lines[-1].append(" ")
            lines[-1].append_text(word)
        else:
            lines.append(word.copy())
    return lines


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
        f"{unit(frame.scheduler)} {frame.round} {frame.status}: {', '.join(parts)}, "
        f"active {len(frame.active)}, collisions {frame.collisions_total}, "
        f"{fmt_rate(frame.rounds_per_second)} {units(frame.scheduler)}/s"
    )


def print_frame(
    frame: Frame, console: Console, height: int | None = None, footer: str | None = None
) -> None:
    """Print one frame at a fixed height (the final frame left on a terminal, or a test render);
    laid out for the console's width and, when it is a terminal, its size."""
    h = height or min(console.size.height, 40)
    screen = (console.width, console.size.height if console.is_terminal else h)
    console.print(render_frame(frame, footer=footer, screen=screen, height=h), height=h)


def save_svg(
    frame: Frame, path: str, width: int = 120, height: int = 40, footer: str | None = None
) -> None:
    """Save one frame as SVG through rich's recording console."""
    console = Console(
        record=True, width=width, height=height, file=io.StringIO(), color_system="truecolor"
    )
    console.print(render_frame(frame, footer=footer, screen=(width, height)), height=height)
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
        derived=dict(state.derived),
        outside=state.outside,
        model=state.model.short,
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
        size = self.console.size  # the terminal's, as it is now: it may have been resized
        self.live.update(render_frame(frame, screen=(size.width, size.height)), refresh=True)

    def close(self, final: Frame | None) -> None:
        self.live.stop()  # leaves the alternate screen, whose content the terminal drops
        frame = final or self.last
        if frame is not None:  # so print it on the main screen, leaving room for the summary
            rows = self.console.size.height
            # Scroll what the main screen shows (the lines printed before the dashboard) up into
            # the scrollback, whole: the final frame then never sits under the tail of a line
            # that wrapped and half scrolled away.
            self.console.file.write("\n" * rows)
            height = min(rows, 40)
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


__all__ = [  # with what deploy/view/panels.py holds and callers take from here
    "BELOW_FINAL_FRAME",
    "LAYER_ACTIVE",
    "LAYER_FOCUS",
    "LAYER_LIGHT",
    "LAYER_ROBOT",
    "LAYER_SEC",
    "LAYER_SIGHT",
    "LAYER_STOPPED",
    "LAYER_STYLES",
    "LAYER_TARGET",
    "LAYER_TARGET_CIRCLE",
    "LAYER_TRAIL",
    "LAYER_UNSEEN",
    "LEGEND",
    "MAX_DUTY",
    "MAX_FIGURE_ROWS",
    "PROGRESS_EVERY",
    "TARGET_RADIUS",
    "CanvasView",
    "Derived",
    "Frame",
    "FrameSink",
    "LiveView",
    "ProgressLog",
    "RateMeter",
    "add_run_arguments",
    "agent_rows",
    "algorithm_text",
    "build_canvas",
    "derive",
    "enclosing_circle",
    "figure_text",
    "frame_from_state",
    "outcome_text",
    "print_frame",
    "progress_line",
    "render_frame",
    "robot_layers",
    "run_lines",
    "save_svg",
]
