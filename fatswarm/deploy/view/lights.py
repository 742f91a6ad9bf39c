"""Lights and views in the pictures: each robot drawn in its colour, and what one robot saw.

A record names each robot's colour in every round line (`lights`) but not the algorithm's palette
(the header does not hold it), so the pictures give colours to the names **in alphabetical order
over the whole record**: the first name gets LIGHT_HEX[0], the second LIGHT_HEX[1], and so on. One
record thus looks the same in `fatswarm replay` and `fatswarm plot`, whichever round is shown, and
a legend names the colours. The start (round 0) is drawn without colours: no line records it.

With `--record-views`, a round line also says which robots each robot that Looked in it saw
(`views`); `Focus` is what one chosen robot saw in one round, for the pictures to highlight, and
whether its compute then failed (the line's `failed`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from rich.text import Text

from fatswarm.domain.lights import LIGHT_HEX as LIGHT_HEX  # the pictures import it from here
from fatswarm.domain.path import Path, Points, point_at
from fatswarm.domain.robot_model import Bodies, ModelError, RobotModel
from fatswarm.world.record import Header, RoundEntry, RunRecord, move_origin
from fatswarm.world.timeline import is_async

UNSEEN_STYLE: Final = "grey39"  # robots the chosen robot did not see, in its Look's round
FOCUS_STYLE: Final = "bold bright_white"  # the ring around the chosen robot
SIGHT_STYLE: Final = "white"  # the circle of its sight, about where it Looked from
NO_VIEWS: Final = "the record has no views of what each robot saw: record it with --record-views"


def light_number(palette: Sequence[str], name: str | None) -> int | None:
    """The number of the colour drawn for light `name`, an index in LIGHT_HEX (None for a name
    not in the record's palette)."""
    if name is None or name not in palette:
        return None
    return list(palette).index(name) % len(LIGHT_HEX)


def light_hex(palette: Sequence[str], name: str | None) -> str | None:
    """The colour drawn for light `name` (None for a name not in the record's palette)."""
    number = light_number(palette, name)
    return None if number is None else LIGHT_HEX[number]


def lights_of(entry: RoundEntry, n: int) -> tuple[str, ...] | None:
    """Every robot's colour name after this round line, None if it names none (or not n names)."""
    lights = entry.extra.get("lights")
    if not isinstance(lights, list) or len(lights) != n:
        return None
    if not all(isinstance(name, str) for name in lights):
        return None
    return tuple(lights)


def record_palette(record: RunRecord) -> tuple[str, ...]:
    """The colour names the record's lines show, sorted: colour k of the pictures is name k."""
    names: set[str] = set()
    for entry in record.rounds:
        names.update(lights_of(entry, record.header.n) or ())
    return tuple(sorted(names))


def views_of(entry: RoundEntry, n: int) -> dict[int, tuple[int, ...]]:
    """Who saw whom in this round line: robot -> the robots it saw ({} without views); a robot
    number or a list that is not one is left out."""
    views = entry.extra.get("views")
    if not isinstance(views, Mapping):
        return {}
    out: dict[int, tuple[int, ...]] = {}
    for key, seen in views.items():
        robot = int(key) if isinstance(key, str) and key.isdigit() else -1
        if 0 <= robot < n and isinstance(seen, list) and all(_robot(s, n) for s in seen):
            out[robot] = tuple(sorted(seen))
    return out


def _robot(value: Any, n: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value < n


def has_views(record: RunRecord) -> bool:
    """Whether the record says what robots saw (its header's `record_views`, or a line's views)."""
    if record.header.extra.get("record_views") is True:
        return True
    return any("views" in entry.extra for entry in record.rounds)


def sight_of(header: Header) -> float | None:
    """The record's sight distance (None: unlimited, or a model this fatswarm cannot read)."""
    try:
        return RobotModel.from_header(header.extra.get("model")).sight
    except ModelError:
        return None


def body_radius(header: Header) -> float:
    """The radius robots are drawn with: 1, the unit (fat robots), or 0 (`--bodies points`)."""
    try:
        bodies = RobotModel.from_header(header.extra.get("model")).bodies
    except ModelError:
        return 1.0
    return 0.0 if bodies is Bodies.POINTS else 1.0


def failed_of(entry: RoundEntry, robot: int) -> str | None:
    """Why `robot`'s compute failed in this line (its `failed`: `Type: message`), else None."""
    failed = entry.extra.get("failed")
    why = failed.get(str(robot)) if isinstance(failed, Mapping) else None
    return " ".join(why.split()) if isinstance(why, str) else None


def line_word(record: RunRecord) -> str:
    """What a record line is called: "round", or "cycle" for an async record."""
    return "cycle" if is_async(record) else "round"


@dataclass(frozen=True, slots=True)
class Focus:
    """What robot `robot` saw in one round: `looked` whether it Looked in it, `seen` the robots it
    saw, from `origin` (where it was at its Look) within `sight` (None: unlimited).
    `recorded` False: the record holds no views at all (so nothing is dimmed). `failed`: why its
    compute failed in this round (`Type: message`), None if it did not."""

    robot: int
    looked: bool = False
    seen: tuple[int, ...] = ()
    origin: tuple[float, float] | None = None
    sight: float | None = None
    recorded: bool = True
    failed: str | None = None

    def dims(self, other: int) -> bool:
        """Whether robot `other` is drawn dimmed: the chosen robot Looked and did not see it."""
        return self.looked and other != self.robot and other not in self.seen

    def line(self) -> str:
        """What it saw, in a few words (the dashboard's counters show it)."""
        failed = "" if self.failed is None else "failed; "  # short: the panel is narrow
        if not self.recorded:
            return failed + "views not recorded"
        if not self.looked:
            return failed + "did not Look this round"
        seen = " ".join(map(str, self.seen)) or "nobody"
        return f"{failed}saw {len(self.seen)}: {seen}"


def focus_per_round(record: RunRecord, robot: int) -> list[Focus]:
    """`Focus` of `robot` for the start (round 0: no Look) and each round line, in order."""
    recorded, sight = has_views(record), sight_of(record.header)
    n = record.header.n
    before = record.header.initial
    out = [Focus(robot, sight=sight, recorded=recorded)]
    for entry in record.rounds:
        views, failed = views_of(entry, n), failed_of(entry, robot)
        if robot in views:
            origin = move_origin(entry, robot, before)
            out.append(Focus(robot, True, views[robot], origin, sight, recorded, failed))
        else:
            out.append(Focus(robot, sight=sight, recorded=recorded, failed=failed))
        before = entry.positions
    return out


def palette_legend(palette: Sequence[str]) -> Text:
    """Each colour name of the record in its colour, a space after each."""
    text = Text()
    for name in palette:
        text.append(name, style=light_hex(palette, name) or "")
        text.append(" ")
    return text


def focus_legend(focus: Focus | None) -> Text:
    """What the highlighting of a chosen robot means (empty without one)."""
    text = Text()
    if focus is not None:
        text.append(f" ◯ robot {focus.robot}", style=FOCUS_STYLE)
        if focus.looked:
            text.append(" unseen", style=UNSEEN_STYLE)
            if focus.sight is not None:
                text.append(" sight", style=SIGHT_STYLE)
    return text


# --- where robots were when one of them Looked (plot --robot --round) ----------------------------


@dataclass(frozen=True, slots=True)
class LookScene:
    """Robot `robot`'s Look in round line `round`: every robot's position and colour (None when
    the record does not say) at that Look, what it saw, and the move it then made, or why its
    compute failed (`failed`: `Type: message`; None if it did not); `word`: what the record calls
    a line ("round", or "cycle" under async)."""

    robot: int
    round: int
    positions: Points  # (n, 2) world frame
    lights: tuple[str, ...] | None
    seen: tuple[int, ...]
    sight: float | None
    move: tuple[tuple[float, float], Path, float] | None  # origin, path, arc length covered
    failed: str | None = None
    word: str = "round"


def look_scene(record: RunRecord, robot: int, round_no: int) -> LookScene | str:
    """The scene of `robot`'s Look in round `round_no` (async: record line, an ended cycle), or
    one line saying why there is none."""
    n, word = record.header.n, line_word(record)
    if not has_views(record):
        return NO_VIEWS
    index = next((i for i, e in enumerate(record.rounds) if e.round == round_no), None)
    if index is None:
        return f"the record has no {word} {round_no}"
    entry = record.rounds[index]
    views = views_of(entry, n)
    if robot not in views:
        looked = [e.round for e in record.rounds if robot in views_of(e, n)]
        shown = ", ".join(map(str, looked[:8])) + (", ..." if len(looked) > 8 else "")
        where = f"it Looked in {word}s {shown}" if looked else "it never Looked with views recorded"
        return f"robot {robot} did not Look in {word} {round_no} ({where})"
    positions, lights = _at_look(record, index)
    move = next((m for m in entry.moves if m.robot == robot), None)
    before = record.rounds[index - 1].positions if index else record.header.initial
    origin = move_origin(entry, robot, before)
    return LookScene(
        robot, round_no, positions, lights, views[robot], sight_of(record.header),
        None if move is None else (origin, move.path, move.traveled), failed_of(entry, robot),
        word,
    )  # fmt: skip


def _at_look(record: RunRecord, index: int) -> tuple[Points, tuple[str, ...] | None]:
    """Positions and colours when round line `index`'s robot Looked: before the round in rounds;
    async: rebuilt at the Look's time (docs/record.md), colours of the last line ended by then."""
    n, entry = record.header.n, record.rounds[index]
    look = entry.extra.get("look")
    if not isinstance(look, (int, float)) or isinstance(look, bool):  # rounds: the line before
        if index == 0:
            return record.header.initial, None
        return record.rounds[index - 1].positions, lights_of(record.rounds[index - 1], n)
    positions = np.array(record.header.initial, dtype=np.float64)
    latest: dict[int, float] = {}
    lights: tuple[str, ...] | None = None
    for e in record.rounds:
        start, end = e.extra.get("start"), e.extra.get("end")
        if isinstance(end, (int, float)) and end <= look and e is not entry:
            lights = lights_of(e, n) or lights
        if not isinstance(start, (int, float)) or start > look:
            continue
        for m in e.moves:
            if start >= latest.get(m.robot, -np.inf):
                latest[m.robot] = start
                origin = move_origin(e, m.robot, positions)
                positions[m.robot] = point_at(origin, m.path, min(look - start, m.traveled))
    return positions, lights
