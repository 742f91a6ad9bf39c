"""The dashboard laid out for 80x24 and up: agent rows visible, the verdict and the key help whole,
robots told apart from the circle and numbered, one line below 80x24, no fragment on exit."""

from __future__ import annotations

import io
import math
import re

import numpy as np
import pytest
from rich.console import Console
from rich.style import Style

from fatswarm.deploy.view.dashboard import (
    LAYER_ROBOT,
    LAYER_STYLES,
    LAYER_TARGET,
    LAYER_TARGET_CIRCLE,
    Frame,
    LiveView,
    build_canvas,
    derive,
    render_frame,
)
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Configured

KEYS = "[paused x10 rounds/s]  space play/pause  ←/→ step  +/- speed  g/G first/last  q quit"


def polygon(n: int, side: float = 4.0) -> np.ndarray:
    r = side / (2 * math.sin(math.pi / n))
    theta = 2 * math.pi * np.arange(n) / n
    return np.column_stack((r * np.sin(theta), r * np.cos(theta)))


def live_frame(n: int, status: str = "running", **fields: object) -> Frame:
    """A live frame of the paper's algorithm on a formed n-gon, every agent alive."""
    positions = polygon(n)
    figures = Configured.of(load_algorithm("uniform-circle"), n, {"a": 4.0}).figures(positions)
    base: dict[str, object] = dict(
        round=31, n=n, scheduler="ssync", positions=positions, params={"a": 4.0},
        figures=figures, active=tuple(range(0, n, 2)), moved=tuple(range(0, n, 2)),
        status=status, alive=(True,) * n, last_active=(31,) * n, last_path_length=(0.5,) * n,
        timeouts=(0,) * n, rounds_per_second=14.0, max_rounds=400, seed=3, swarm="lab",
    )  # fmt: skip
    base.update(fields)
    return Frame(**base)  # type: ignore[arg-type]


def screen(frame: Frame, cols: int, rows: int, keys: str | None = None) -> list[str]:
    """The lines a terminal of cols x rows shows of the frame."""
    console = Console(width=cols, height=rows, record=True, color_system=None, file=io.StringIO())
    console.print(render_frame(frame, footer=keys, screen=(cols, rows)), height=rows)
    return console.export_text().rstrip("\n").split("\n")


@pytest.mark.parametrize("n", [6, 8, 16])
@pytest.mark.parametrize("replay", [False, True], ids=["live", "replay"])
def test_at_80x24_agent_rows_show_and_the_verdict_is_whole(n: int, replay: bool) -> None:
    if replay:  # a replay's frame: no liveliness, no rate; and the key help below the verdict
        frame = live_frame(n, status="formed", alive=None, rounds_per_second=None, last_round=31)
    else:
        frame = live_frame(n, status="formed")
    lines = screen(frame, 80, 24, KEYS if replay else None)
    assert len(lines) == 24 and all(len(line) <= 80 for line in lines)
    rows = [
        int(m.group(1)) for line in lines for m in re.finditer(r"│\s+(\d+)\s+(?:yes|-)\s", line)
    ]
    assert rows[:3] == [0, 1, 2], "\n".join(lines)
    top = max(i for i, line in enumerate(lines) if line.startswith("╭") and line.count("╭") == 1)
    footer = " ".join(line.strip("│ ") for line in lines[top + 1 : -1])
    verdict = f"FORMED: uniform-circle goal reached by {n} robots after 31 rounds, 0 collisions"
    assert verdict in re.sub(r"\s+", " ", footer), "\n".join(lines)
    assert "…" not in footer
    assert not replay or "q quit" in footer


def test_key_hints_are_not_cut_at_120_columns() -> None:
    lines = screen(live_frame(8, status="formed"), 120, 40, KEYS)
    assert any(KEYS in line for line in lines), "\n".join(lines[-5:])


@pytest.mark.parametrize(("cols", "rows"), [(79, 24), (80, 23), (50, 12), (40, 8)])
def test_below_80x24_one_line_says_so_and_the_run_still_shows(cols: int, rows: int) -> None:
    lines = screen(live_frame(8, status="formed"), cols, rows)
    said = " ".join(line.strip() for line in lines)
    assert f"too small ({cols}x{rows}): the dashboard needs 80x24" in said
    assert any(line.startswith("round 31 (limit 400), 8 robots") for line in lines)
    assert all(len(line) <= cols for line in lines)
    assert len([line for line in lines if line.strip()]) <= rows


@pytest.mark.parametrize("n", [32, 48, 64])
def test_many_robots_keep_the_round_line_whole(n: int) -> None:
    lines = screen(live_frame(n), 120, 40)
    this_round = next(line for line in lines if "this round" in line)
    assert re.search(
        rf"this round\s+{len(range(0, n, 2))} active\s+{len(range(0, n, 2))} moved", this_round
    )
    assert "…" not in this_round
    assert any(re.search(r"round\s+31 \(limit 400\)", line) for line in lines)


@pytest.mark.parametrize("n", [32, 64])
def test_no_circle_dot_touches_a_disc_so_robots_stand_apart(n: int) -> None:
    frame = live_frame(n)
    canvas = build_canvas(frame, derive(frame), cols=72, rows=36)
    vp = canvas.viewport
    jj, ii = np.nonzero((canvas.dots > 0) & (canvas.dots < LAYER_TARGET))  # circles and paths
    for x, y in frame.positions:
        ci, cj = vp.to_dot(float(x), float(y))
        near = np.hypot(ii + 0.5 - ci, jj + 0.5 - cj) <= 1.0 / vp.units_per_dot + 1.0
        assert not near.any()
    assert (canvas.dots == LAYER_TARGET_CIRCLE).any()  # the circle is still drawn between them


def test_robot_ids_are_written_on_discs_with_room() -> None:
    frame = live_frame(6, active=(), moved=())
    canvas = build_canvas(frame, derive(frame), cols=60, rows=30)
    text = ["".join(chunk for chunk, _ in row) for row in canvas.runs()]
    for i, (x, y) in enumerate(frame.positions):
        col, row = canvas.viewport.to_cell(float(x), float(y))
        assert text[row][col] == str(i)
    assert {layer for _, layer in canvas.labels.values()} == {128 + LAYER_ROBOT}


def test_the_target_circle_is_bright_on_dark_terminals() -> None:
    colour = Style.parse(LAYER_STYLES[LAYER_TARGET_CIRCLE]).color
    assert colour is not None and colour.name == "bright_blue"


def test_the_final_frame_scrolls_the_lines_before_it_away_whole() -> None:
    """A long line printed before the dashboard wraps; the final frame must not leave its tail
    on the screen: the main screen is scrolled (rows newlines) before the frame is printed."""
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=80, height=24, color_system=None)
    out.write("seed 123 " + "x" * 150 + "\n")
    view = LiveView(console)
    view.show(live_frame(6))
    view.close(live_frame(6, status="formed"))
    raw = out.getvalue()
    after = raw[raw.rfind("\x1b[?1049l") + len("\x1b[?1049l") :]
    assert after.startswith("\n" * 24)
    assert "fatswarm · live" in after[24:]
