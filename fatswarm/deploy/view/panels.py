"""The dashboard's words: the `Frame` it shows and the text around the picture (counters, agents,
outcome and key lines), and the one line said instead when the terminal is too small for it.

Pure renderers from a plain dataclass: no terminal, no network (deploy/view/dashboard.py lays
them out around the canvas).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from rich.console import Console, ConsoleOptions, Group, RenderResult
from rich.layout import Layout
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from fatswarm.agent import geometry
from fatswarm.deploy.view.lights import Focus
from fatswarm.domain import figures as declared
from fatswarm.domain import tolerance
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.seam import ParamValue
from fatswarm.domain.words import counted, unit, units

TARGET_RADIUS: Final = "target radius"  # the figure that draws the paper's target points
SIDE_WIDTH: Final = 46  # columns of the counters and agents column
KEY_WIDTH: Final = (
    14  # at most, of the counters' labels (an algorithm's figure may have a long one)
)
MAX_FIGURE_ROWS: Final = 8  # figures shown as rows; a line says how many more there are
AGENT_ROWS: Final = 8  # the agents' rows the counters make room for (`SideView`)
MIN_SIZE: Final = (80, 24)  # the smallest terminal the whole dashboard is laid out for
BAR_WIDTH: Final = 10  # columns of the bars beside r_c / r and the targets filled
BAR_DONE, BAR_LEFT = "magenta", "grey35"


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
    unfinished: bool = False  # replay: the record's last round, and it has no result line
    # the run's figures derived from the positions, so far (fatswarm.domain.figures), by name
    derived: dict[str, float] = field(default_factory=dict)
    outside: str = ""  # how the run is outside its algorithm's assumptions ('' if within)
    model: str = ""  # the robot model in one word (`RobotModel.short`: paper); '' if unknown

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
    return Derived(center, rc, radius, targets, polygon_filled(pts, center, rc, frame.n, tol))


def polygon_filled(pts: Points, center: tuple[float, float], rc: float, n: int, tol: float) -> int:
    """How many robots sit on the corners of one regular n-gon inscribed in the SEC, the best
    turned one: the goal's own sense (a formed run shows n / n, whichever way its polygon is
    turned), not the paper's north-based target points of the moment."""
    rel = pts - np.asarray(center)
    on = np.abs(np.hypot(rel[:, 0], rel[:, 1]) - rc) <= tol
    if not on.any() or n < 1:
        return 0
    angles = np.arctan2(rel[on, 1], rel[on, 0])
    best = 0
    for start in angles:  # a corner at each robot on the circle in turn
        step = (angles - start) * n / (2 * np.pi)
        off = np.abs(step - np.round(step)) * 2 * np.pi / n * rc  # arc length to nearest corner
        corners = {int(k) % n for k in np.round(step[off <= tol])}
        best = max(best, len(corners))
    return best


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


def fmt_rate(rate: float | None) -> str:
    return "-" if rate is None else f"{rate:,.1f}"


def outcome_text(frame: Frame) -> str:
    """One line saying how the run ended, that it still runs, or that its record stops there."""
    k, word = frame.collisions_total, unit(frame.scheduler)  # cycles under an async model
    rounds = counted(frame.round, word)
    reached = f"{frame.algorithm} goal reached by {frame.n} robots after {rounds}"
    if frame.status == Status.FORMED and k:
        return f"FORMED WITH {counted(k, 'collision').upper()}: {reached}, not collision-free"
    if frame.status == Status.FORMED:
        head = f"FORMED: {reached}"
    elif frame.status == Status.STALLED:
        head = f"STALLED after {rounds}: no robot can make progress"
    elif frame.status == Status.MAX_ROUNDS:
        head = f"NOT FORMED: stopped at the {word} limit ({rounds})"
    elif frame.unfinished:
        return (
            f"UNFINISHED: the record stops after {word} {frame.round} without a result line "
            "(interrupted, killed, or still being written)"
        )
    else:
        return f"running: {word} {frame.round}"
    failed = int(frame.derived.get("failures") or 0)  # computes that raised (docs/record.md)
    said = f", the algorithm failed {counted(failed, 'time')}" if failed else ""
    return f"{head}, {counted(k, 'collision')}{said}"


def run_lines(frame: Frame, width: int) -> list[str]:
    """`n=8  uniform-circle a=4`, parameters going on to further lines of at most `width`."""
    lines = [f"n={frame.n}  {frame.algorithm}"]
    for word in algorithm_text("", frame.params).split(" ") if frame.params else ():
        if len(lines[-1]) + 1 + len(word) <= width:
            lines[-1] += " " + word
        else:
            lines.append(word)
    return lines


def bar(done: float, total: float, width: int = BAR_WIDTH) -> Text:
    """A bar of `width` columns, filled in proportion to done / total."""
    filled = round(width * min(max(done / total, 0.0), 1.0)) if total > 0 else 0
    text = Text("━" * filled, style=BAR_DONE)
    text.append("━" * (width - filled), style=BAR_LEFT)
    return text


Row = tuple[str | Text, str | Text]  # a counter: its label and its value


# How much a counter matters when the terminal is short (`counters_table(..., most=)`): the
# lowest go first, so that the agents keep their rows; KEEP ones always stay.
KEEP: Final = 9
RANKS: Final = {
    "r_c": 5,
    "r_c / r": 5,
    "targets": 5,
    "collisions": 6,
    "timeouts": 5,
    "failures": 6,
}  # the rest: a figure of the algorithm's 4, a derived figure 2, this round 1, the rate 0 (the
# chosen robot's Look of replay --robot: KEEP - 1)


def counters_table(frame: Frame, derived: Derived, most: int | None = None) -> Table:
    """Round, scheduler, robot model, algorithm, r_c (versus r, targets filled, with bars),
    figures, this round, collisions, rate: one row each, so that the agents keep room at
    80x24; `most`: at most this many rows, the ones that matter least left out (`RANKS`; never
    round, scheduler, model and the algorithm's name)."""
    figures = [(k, v) for k, v in frame.figures.items() if k != TARGET_RADIUS or r_absent(derived)]
    word = unit(frame.scheduler)  # "this cycle" under an async model
    keys = min(KEY_WIDTH, max([len(f"this {word}"), *(len(k) for k, _ in figures)]))
    grid = Table.grid(padding=(0, 1))
    grid.add_column("key", style="bold", no_wrap=True, width=keys, overflow="ellipsis")
    grid.add_column("value", no_wrap=True, overflow="ellipsis")
    seed = f"  seed {frame.seed}" if frame.seed is not None else ""
    ranked: list[tuple[int, Row]] = [
        (KEEP, (word, round_text(frame))),
        (KEEP, ("scheduler", frame.scheduler + seed)),
    ]
    if frame.model:
        ranked.append((KEEP, ("model", Text(frame.model))))
    for i, line in enumerate(run_lines(frame, SIDE_WIDTH - 4 - keys - 1)):  # borders, padding
        ranked.append((3 if i else KEEP, ("" if i else "robots", Text(line))))  # Text: no markup
    ranked += [(RANKS.get(str(k), 4), (k, v)) for k, v in radius_rows(frame, derived)]
    ranked += [(4, row) for row in figure_rows(figures)] + [(2, r) for r in derived_rows(frame)]
    for key, value in tail_rows(frame):
        rank = RANKS.get(str(key), 0 if str(key).endswith("/s") else 1)
        if frame.focus is not None and key == f"robot {frame.focus.robot}":
            rank = KEEP - 1  # what replay --robot is for: the chosen robot's Look
        ranked.append((rank, (key, value)))
    for _, (key, value) in fewest(ranked, most):
        grid.add_row(key, value)
    return grid


def fewest(ranked: list[tuple[int, Row]], most: int | None) -> list[tuple[int, Row]]:
    """`ranked` cut to `most` rows (None: all), leaving out the lowest ranks first (the latest of
    equal ranks first), never a KEEP one; the order kept."""
    if most is None or len(ranked) <= most:
        return ranked
    order = sorted(range(len(ranked)), key=lambda i: (ranked[i][0], -i))
    dropped = {i for i in order[: len(ranked) - most] if ranked[i][0] < KEEP}
    return [row for i, row in enumerate(ranked) if i not in dropped]


def radius_rows(frame: Frame, derived: Derived) -> list[Row]:
    """r_c, or r_c against r and the targets filled, each with a bar."""
    r, rc = derived.target_radius, derived.sec_radius
    if r is None or derived.filled is None:
        return [("r_c", f"{rc:.3f}")]
    return [
        ("r_c / r", Text(f"{rc:.3f} / {r:.3f} ") + bar(min(rc, r), max(r, 1e-9))),
        ("targets", Text(f"{derived.filled} / {frame.n} filled ") + bar(derived.filled, frame.n)),
    ]


def figure_rows(figures: list[tuple[str, float]]) -> list[Row]:
    """The algorithm's figures, at most MAX_FIGURE_ROWS rows (the agents need room too)."""
    shown = figures if len(figures) <= MAX_FIGURE_ROWS else figures[: MAX_FIGURE_ROWS - 1]
    rows: list[Row] = [(Text(k), figure_text(v)) for k, v in shown]  # Text: labels, no markup
    if len(shown) < len(figures):
        rows.append(("", Text(f"… {len(figures) - len(shown)} more figures", style="dim")))
    return rows


RUN_WORDS: Final = {
    declared.Summary.MIN: "least",
    declared.Summary.MAX: "most",
    declared.Summary.SUM: "total",
    declared.Summary.COUNT: "count",
}  # how a derived row names the run's value beside the round's


def derived_rows(frame: Frame) -> list[Row]:
    """The declared figures of the frame's positions the dashboard shows (fatswarm.domain.figures:
    min gap...), live and in replay alike, with the run's value so far when the frame has it:
    `0.412  least 0.113`."""
    pts = np.asarray(frame.positions, dtype=np.float64).reshape(-1, 2)
    rows: list[Row] = []
    for f in declared.derived_figures():
        if declared.Place.DASHBOARD not in f.places or f.derive is None:
            continue
        text = declared.shown(f.derive(pts))
        run, word = frame.derived.get(f.name), RUN_WORDS.get(f.summary)
        if run is not None and word is not None:
            text += f"  {word} {declared.shown(run)}"
        rows.append((f.words, text))
    return rows


def tail_rows(frame: Frame) -> list[Row]:
    """This round (cycle), collisions, the chosen robot's Look, the rate (live), timeouts and
    failed computes (how many agents are alive: the agents panel's title, `agents_title`)."""
    stopped = f"  {len(frame.stopped)} stopped" if frame.stopped else ""
    word = unit(frame.scheduler)
    rows: list[Row] = [
        (f"this {word}", f"{len(frame.active)} active  {len(frame.moved)} moved{stopped}"),
        ("collisions", str(frame.collisions_total)),
    ]
    if frame.focus is not None:
        rows.append((f"robot {frame.focus.robot}", frame.focus.line()))
    if frame.last_round is None:  # a replay has no rate
        rows.append((f"{units(frame.scheduler)}/s", fmt_rate(frame.rounds_per_second)))
    if sum(frame.timeouts):
        rows.append(("timeouts", str(sum(frame.timeouts))))
    failed = int(frame.derived.get("failures") or 0)  # computes that raised, over the run
    if failed:
        rows.append(("failures", str(failed)))
    return rows


def r_absent(derived: Derived) -> bool:
    """Whether the counters show no target radius of their own (so its figure is a row)."""
    return derived.target_radius is None or derived.filled is None


def round_text(frame: Frame) -> str:
    """`17 / 91` in a replay, `17 (limit 400)` live, or the round alone."""
    if frame.last_round is not None:
        return f"{frame.round} / {frame.last_round}"
    if frame.max_rounds is not None:
        return f"{frame.round} (limit {frame.max_rounds})"
    return f"{frame.round}"


def agent_rows(frame: Frame) -> list[int]:
    """Robots in the order the agents panel lists them: by number, so that a row stays put."""
    return list(range(frame.n))


class AgentsView:
    """The agents list by robot number, cut to the rows that fit (with a line saying how many
    are left out, and how many of those are active or gone).

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
            text.append("\n" + more_robots(f, order[len(shown) :]), style="dim")
        yield text


def more_robots(frame: Frame, hidden: list[int]) -> str:
    """`… 22 more robots (3 active, 1 gone)`: the rows that did not fit."""
    active = sum(1 for i in hidden if i in set(frame.active))
    gone = sum(1 for i in hidden if frame.alive is not None and not frame.alive[i])
    notes = [f"{active} active"] if active else []
    notes += [f"{gone} gone"] if gone else []
    return f"… {counted(len(hidden), 'more robot')}" + (f" ({', '.join(notes)})" if notes else "")


def agents_title(frame: Frame) -> str:
    """`agents · alive 7 / 8`: the agents panel's title, with how many are alive when known."""
    if frame.alive is None:
        return "agents"
    return f"agents · alive {sum(frame.alive)} / {frame.n}"


def agents_height(n: int) -> int:
    """The agents panel's rows that show every robot, or AGENT_ROWS of them and a "more" line:
    what the counters make room for (`SideView`)."""
    return min(n, AGENT_ROWS) + (n > AGENT_ROWS) + 1 + 2  # the header, the borders


def essentials(frame: Frame) -> int:
    """How many counters are never left out (KEEP: the round, scheduler, model, robots)."""
    return 3 + bool(frame.model)


def essentials_line(frame: Frame) -> str:
    """The counters never left out, in one line (`round 10 (limit 400) · fsync seed 1 · paper`),
    for a frame too short for them beside the agents (`SideView(counters=False)`)."""
    seed = f" seed {frame.seed}" if frame.seed is not None else ""
    words = [f"{unit(frame.scheduler)} {round_text(frame)}", frame.scheduler + seed, frame.model]
    return " · ".join(word for word in words if word)


class SideView:
    """The counters above the agents, laid out for the height rich gives them: when fewer than
    AGENT_ROWS agents (or fewer than all, if there are no more) would fit below every counter,
    the counters that matter least make room (`counters_table(most=)`), so that at 80x24 the
    agents of 8 robots stay whole; many robots take what is left below every counter. Without
    `counters` (a frame too short even for the essentials, whose header then says them:
    `essentials_line`), the agents alone."""

    def __init__(self, frame: Frame, derived: Derived, counters: bool = True) -> None:
        self.frame, self.derived, self.counters = frame, derived, counters

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        agents = Panel(AgentsView(self.frame), title=agents_title(self.frame))
        if not self.counters:
            yield from console.render(agents, options)
            return
        height = options.height or options.size.height
        counters = counters_table(self.frame, self.derived)
        room = height - agents_height(self.frame.n) - 2  # the counters' rows that leave it
        if counters.row_count > room:
            counters = counters_table(self.frame, self.derived, most=max(room, 0))
        layout = Layout(name="side")
        layout.split_column(
            Layout(Panel(counters, title="run"), name="counters", size=counters.row_count + 2),
            Layout(agents, name="agents"),
        )
        yield from console.render(layout, options)


# --- the bottom lines, and a terminal too small for the rest ------------------------------------


def wrapped(text: str, width: int) -> list[str]:
    """`text` in lines of at most `width` columns (words kept whole when they fit)."""
    return textwrap.wrap(text, max(width, 10), break_on_hyphens=False) or [""]


def footer_lines(frame: Frame, keys: str | None, width: int) -> list[Text]:
    """The outcome, the line saying that the run is outside its algorithm's assumptions (if it
    is), then the key help, each wrapped to the footer panel's inside (`width` is the
    terminal's): nothing is cut, however narrow the terminal."""
    inside = width - 4  # the panel's borders and padding
    lines = [Text(line) for line in wrapped(outcome_text(frame), inside)]
    if frame.outside:  # the run went ahead outside its algorithm's assumptions: said each frame
        lines += [Text(line, style="yellow") for line in wrapped(frame.outside, inside)]
    lines += [Text(line, style="dim") for line in wrapped(keys, inside)] if keys else []
    return lines


def too_small(frame: Frame, title: str, keys: str | None, size: tuple[int, int]) -> Group:
    """What a terminal smaller than MIN_SIZE shows: the run in a few lines, and one line saying
    that the dashboard needs more room."""
    cols, rows = size
    alive = f", {sum(frame.alive)} / {frame.n} alive" if frame.alive is not None else ""
    counts = counted(frame.collisions_total, "collision")
    lines = [
        title,
        *wrapped(
            f"too small ({cols}x{rows}): the dashboard needs {MIN_SIZE[0]}x{MIN_SIZE[1]}", cols
        ),
        *wrapped(
            f"{unit(frame.scheduler)} {round_text(frame)}, {frame.n} robots, {counts}{alive}", cols
        ),
        *wrapped(outcome_text(frame), cols),
        *(wrapped(keys, cols) if keys else []),
    ]
    # a Group: printed alone, a Text would lose its no_wrap (rich joins the Texts it prints)
    return Group(Text("\n".join(lines), no_wrap=True, overflow="ellipsis"))


__all__ = [
    "MIN_SIZE",
    "SIDE_WIDTH",
    "TARGET_RADIUS",
    "AgentsView",
    "Derived",
    "Frame",
    "SideView",
    "agent_rows",
    "agents_height",
    "agents_title",
    "algorithm_text",
    "counters_table",
    "derive",
    "derived_rows",
    "enclosing_circle",
    "essentials",
    "essentials_line",
    "figure_text",
    "fmt_rate",
    "footer_lines",
    "outcome_text",
    "run_lines",
    "too_small",
]
