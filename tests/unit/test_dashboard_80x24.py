"""The final dashboard frame of a finished run of 8 robots at 80x24, as rich renders it: every
agent's row, the legend word for word and the verdict whole, under fsync, async and lights; an
async run's dashboard counts cycles; the robot model is named."""

from __future__ import annotations

import io
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rich.console import Console

import fatswarm
from fatswarm.deploy.view.dashboard import Frame, canvas_legend, derive, render_frame
from fatswarm.deploy.view.panels import SIDE_WIDTH
from fatswarm.domain.outcome import Status
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import Configured

RUNS = {  # (scheduler, algorithm, robot model)
    "fsync": ("fsync", "uniform-circle", {}),
    "async": ("async", "uniform-circle", {}),
    "luminous": ("async", "uniform-circle-lights", {}),
    "opaque": ("ssync", "gathering", {"visibility": "opaque", "sight": 9.0}),
}


def finished_frame(scheduler: str, algorithm: str, model: dict[str, Any]) -> Frame:
    """The live dashboard's last frame of a finished lock-step run of 8 robots (what the world's
    final state shows: every agent alive, the algorithm's figures, lights, the outside line)."""
    result = fatswarm.run(n=8, seed=1, scheduler=scheduler, algorithm=algorithm, **model)
    setting = Configured.of(load_algorithm(algorithm), 8, result.params)
    return Frame(
        round=result.rounds, n=8, scheduler=scheduler, positions=result.positions,
        algorithm=algorithm, params=dict(result.params),
        figures=setting.figures(result.positions), status=result.status, seed=1,
        alive=(True,) * 8, last_active=(result.rounds,) * 8, last_path_length=(1.5,) * 8,
        timeouts=(0,) * 8, rounds_per_second=41.0, max_rounds=400, swarm="lab",
        lights=result.lights, palette=tuple(sorted(setting.colours)),
        derived={k: float(v) for k, v in result.derived.items() if isinstance(v, (int, float))},
        outside=result.outside, model=RobotModel.of(**model).short,
    )  # fmt: skip


def screen(frame: Frame, cols: int = 80, rows: int = 24) -> list[str]:
    console = Console(width=cols, height=rows, record=True, color_system=None, file=io.StringIO())
    console.print(render_frame(frame, screen=(cols, rows)), height=rows)
    return console.export_text().rstrip("\n").split("\n")


@pytest.fixture(scope="module", params=sorted(RUNS))
def final(request: pytest.FixtureRequest) -> tuple[str, Frame]:
    return request.param, finished_frame(*RUNS[request.param])


def test_at_80x24_the_final_frame_keeps_every_agent_the_legend_and_the_verdict(
    final: tuple[str, Frame],
) -> None:
    name, frame = final
    lines = screen(frame)
    shown = "\n".join(lines)
    assert len(lines) == 24 and all(len(line) <= 80 for line in lines), shown
    rows = [int(m[1]) for line in lines for m in re.finditer(r"│\s+(\d+)\s+yes\s", line)]
    assert rows == list(range(8)), shown
    assert "more robot" not in shown
    canvas = "\n".join(line[: 80 - SIDE_WIDTH] for line in lines)  # the canvas's column
    flat = re.sub(r"[\s│╭╮╰╯─]+", " ", canvas)
    legend = canvas_legend(frame, derive(frame)).plain
    assert legend in flat, f"{legend!r} not whole in\n{shown}"
    top = max(i for i, line in enumerate(lines) if line.startswith("╭") and line.count("╭") == 1)
    footer = re.sub(r"\s+", " ", " ".join(line.strip("│ ") for line in lines[top + 1 : -1]))
    word = "cycles" if RUNS[name][0] == "async" else "rounds"
    assert f"goal reached by 8 robots after {frame.round} {word}" in footer, shown
    assert "…" not in footer


def test_async_dashboards_count_cycles_and_name_no_round(final: tuple[str, Frame]) -> None:
    name, frame = final
    text = "\n".join(screen(frame, 120, 40))
    if RUNS[name][0] == "async":
        assert re.search(rf"cycle\s+{frame.round} \(limit 400\)", text), text
        assert re.search(r"cycles/s\s+41\.0", text) and "this cycle" in text
        assert "round" not in text.replace("surround", ""), text
    else:
        assert re.search(r"rounds/s\s+41\.0", text) and "this round" in text


def test_the_dashboard_names_the_robot_model(final: tuple[str, Frame]) -> None:
    name, frame = final
    text = "\n".join(screen(frame))
    expected = "opaque+sight9" if name == "opaque" else "paper"
    assert re.search(rf"model\s+{re.escape(expected)}\s", text), text


def test_live_replayed_and_lockstep_frames_carry_the_model_word(tmp_path: Path) -> None:
    from fatswarm.deploy.view.dashboard import frame_from_state
    from fatswarm.deploy.view.replay import build_frames
    from fatswarm.world.observers import AgentInfo, WorldState
    from fatswarm.world.record_read import read_record

    model = RobotModel.of(visibility="opaque", sight=9.0)
    state = WorldState(
        round=3, n=2, algorithm="gathering", params={}, figures={}, scheduler="ssync", swarm="s",
        positions=np.array([[0.0, 0.0], [3.0, 0.0]]), active=(), open_round=0, moved=(),
        stopped=(), collisions_total=0, status=Status.RUNNING,
        agents=(AgentInfo(True, 3, 0.0, 0),) * 2, model=model,
    )  # fmt: skip
    assert frame_from_state(state).model == "opaque+sight9"
    path = tmp_path / "run.jsonl"
    fatswarm.run(n=4, seed=1, algorithm="gathering", visibility="opaque", sight=9.0, record=path)
    frames = build_frames(read_record(str(path)))
    assert {f.model for f in frames} == {"opaque+sight9"}
    assert re.search(r"model\s+opaque\+sight9", "\n".join(screen(frames[-1], 120, 40)))


def test_the_final_frame_left_above_the_summary_at_80x24_keeps_every_agent(
    final: tuple[str, Frame],
) -> None:
    """On an 80x24 terminal the live view leaves its last frame in the rows the summary does not
    need (`LiveView.close`): the agents, the legend and the verdict stay whole, the essential
    counters move to the header line."""
    from fatswarm.deploy.view.dashboard import LiveView

    name, frame = final
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=80, height=24, color_system=None)
    view = LiveView(console)
    view.close(frame)
    raw = out.getvalue()
    lines = raw[raw.rfind("\x1b[?1049l") + len("\x1b[?1049l") :].strip("\n").split("\n")
    shown = "\n".join(lines)
    assert len(lines) <= 24 - 6 and all(len(line) <= 80 for line in lines), shown
    rows = [int(m[1]) for line in lines for m in re.finditer(r"│\s+(\d+)\s+yes\s", line)]
    assert rows == list(range(8)), shown
    word = "cycle" if RUNS[name][0] == "async" else "round"
    said = f"{word} {frame.round} (limit 400) · {RUNS[name][0]} seed 1 · {frame.model} · "
    assert lines[0].startswith(said), shown
    canvas = "\n".join(line[: 80 - SIDE_WIDTH] for line in lines)
    legend = canvas_legend(frame, derive(frame)).plain
    assert legend in re.sub(r"[\s│╭╮╰╯─]+", " ", canvas), shown
    footer = re.sub(r"[\s│╭╮╰╯─]+", " ", shown[shown.rindex("╭") :])
    assert f"goal reached by 8 robots after {frame.round} {word}s" in footer, shown


def test_replay_robot_keeps_the_chosen_robots_look_and_every_agent_at_80x24(
    tmp_path: Path,
) -> None:
    from fatswarm.deploy.view.replay import build_frames, focus_on
    from fatswarm.world.record_read import read_record

    path = tmp_path / "run.jsonl"
    fatswarm.run(n=8, seed=1, scheduler="fsync", record=path, record_views=True, sight=9.0)
    record = read_record(str(path))
    frames = focus_on(build_frames(record), record, 3)
    lines = screen(frames[2])
    shown = "\n".join(lines)
    assert re.search(r"│ robot 3\s+\S", shown), shown  # the Look's counter
    rows = [int(m[1]) for line in lines for m in re.finditer(r"│\s+(\d+)\s+-\s", line)]
    assert rows == list(range(8)), shown
