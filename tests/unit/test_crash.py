"""Issue 10's crash model: f robots crash for good at rounds the adversary draws from the seed; the
world ignores their moves from then on, and the goal is judged on the live robots."""

from __future__ import annotations

from pathlib import Path as FsPath

import numpy as np
import pytest

import fatswarm
from fatswarm.agent.geometry import target_radius
from fatswarm.deploy import cli
from fatswarm.domain.draws import crash_plan
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Configured
from fatswarm.world import core
from fatswarm.world.record_read import read_record
from fatswarm.world.setup import WorldSetup, setup_from_header


@pytest.mark.parametrize("n", [2, 5, 8, 12])
def test_the_plan_is_f_distinct_robots_crashing_within_the_first_2n_rounds(n: int) -> None:
    for f in range(1, n):
        for seed in range(5):
            plan = crash_plan(seed, n, f)
            assert len(plan) == f
            assert all(0 <= robot < n for robot in plan)
            assert all(1 <= at <= 2 * n for at in plan.values())
            assert plan == crash_plan(seed, n, f)  # a pure function of (seed, n, f)


def test_the_plan_differs_by_seed_and_grows_with_f() -> None:
    plans = {tuple(sorted(crash_plan(seed, 8, 2).items())) for seed in range(20)}
    assert len(plans) > 10
    for seed in range(10):  # the f-robot plan is the first f of the adversary's order
        assert crash_plan(seed, 8, 1).items() <= crash_plan(seed, 8, 3).items()


@pytest.mark.parametrize("f", [0, -1, 6, 7])
def test_a_plan_needs_0_lt_f_lt_n(f: int) -> None:
    with pytest.raises(ValueError, match="--crash must be between 1 and n - 1"):
        crash_plan(1, 6, f)


def _check_crashed_robots_stay(record: FsPath) -> int:
    """Assert that every robot the record says crashed never moves after; the crashes seen."""
    rec = read_record(str(record))
    f = rec.header.extra["crash"]
    plan = crash_plan(int(rec.header.seed or 0), rec.header.n, f)
    down: set[int] = set()
    before = rec.header.initial
    for entry in rec.rounds:
        now = set(entry.extra.get("crash", ()))
        assert now == {r for r, at in plan.items() if at == entry.round}
        down |= now
        assert not down & {m.robot for m in entry.moves}  # no move of theirs applied
        for robot in down:
            assert np.array_equal(entry.positions[robot], before[robot])
        assert "recovered" not in entry.extra  # a live agent does not bring them back
        before = entry.positions
    return len(down)


@pytest.mark.parametrize("scheduler", ["fsync", "ssync"])
@pytest.mark.parametrize("n", [6, 8])
def test_lockstep_runs_with_a_crash_keep_the_crashed_robots_still(
    n: int, scheduler: str, tmp_path: FsPath
) -> None:
    crashes = 0
    for seed in (1, 2, 3):
        record = tmp_path / f"run{seed}.jsonl"
        result = fatswarm.run(n=n, seed=seed, scheduler=scheduler, crash=1, record=record)
        assert result.status in ("formed", "stalled", "max_rounds")
        assert result.collisions == 0
        crashes += _check_crashed_robots_stay(record)
    if scheduler == "ssync":
        assert crashes > 0  # the adversary did crash robots mid-run


def test_the_goal_is_judged_on_the_live_robots(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list[int] = []
    real = core.WorldCore._goal

    def spy(self: core.WorldCore, positions: np.ndarray) -> bool:
        out = real(self, positions)
        seen.append(len(self.stuck))
        return out

    monkeypatch.setattr(core.WorldCore, "_goal", spy)
    result = fatswarm.run(n=6, seed=1, scheduler="ssync", crash=1)
    assert result.status == "stalled" and seen and seen[-1] == 1

    # the rule itself: a formed pentagon plus a robot at its centre
    setting = Configured.of(load_algorithm("uniform-circle"), 6, {})
    a = float(setting.values["a"])
    r = target_radius(5, a)
    angles = np.arange(5) * 2 * np.pi / 5
    pentagon = np.column_stack((r * np.cos(angles), r * np.sin(angles)))
    positions = np.vstack((pentagon, [[0.0, 0.0]]))
    setup = WorldSetup("s", 6, 0, "fsync", positions, None)
    world = core.WorldCore(setup, setting)
    assert not world._goal(positions)
    world.stuck = frozenset({5})
    assert world._goal(positions)
    world.stuck = frozenset({0})
    assert not world._goal(positions)


def _fatswarm(*argv: str) -> int:
    return cli.main(["run", "--lockstep", "-q", *argv])


@pytest.mark.parametrize("scheduler", ["fsync", "ssync"])
def test_resuming_a_crash_record_reproduces_it_byte_for_byte(
    scheduler: str, tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = tmp_path / "whole.jsonl"
    assert _fatswarm(
        "-n", "6", "--seed", "2", "--scheduler", scheduler, "--crash", "1", "--record", str(whole)
    ) in (0, 1)
    lines = whole.read_text().splitlines(keepends=True)
    crash_line = next(i for i, line in enumerate(lines) if '"crash":[' in line)
    cuts = [c for c in (crash_line, crash_line + 1) if c < len(lines) - 1]
    assert len(cuts) == (1 if scheduler == "fsync" else 2)  # the fsync run stalls as it crashes
    for cut in cuts:  # a break just before the crash round, and just after it
        part = tmp_path / f"part{cut}.jsonl"
        part.write_text("".join(lines[:cut]))
        assert _fatswarm("--record", str(part), "--resume", "--crash", "2") == 2
        err = capsys.readouterr().err
        assert "--crash 2 contradicts" in err and "crash=1" in err and err.count("\n") == 1
        assert _fatswarm("--record", str(part), "--resume") in (0, 1)
        assert part.read_text() == whole.read_text()


def test_resume_refuses_crash_for_a_record_without(
    tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = tmp_path / "whole.jsonl"
    assert _fatswarm("-n", "6", "--seed", "2", "--record", str(whole)) == 0
    part = tmp_path / "part.jsonl"
    part.write_text("".join(whole.read_text().splitlines(keepends=True)[:4]))
    assert _fatswarm("--record", str(part), "--resume", "--crash", "1") == 2
    assert "whose run has no crashes" in capsys.readouterr().err


@pytest.mark.parametrize("f", ["0", "-1", "6", "9"])
def test_a_crash_count_outside_0_n_is_refused(f: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert _fatswarm("-n", "6", f"--crash={f}") == 2
    err = capsys.readouterr().err
    assert (
        err.startswith("fatswarm run: --crash must be between 1 and n - 1 = 5")
        and err.count("\n") == 1
    )


def test_the_world_reads_f_back_from_the_header_and_a_run_without_says_nothing(
    tmp_path: FsPath,
) -> None:
    record = tmp_path / "run.jsonl"
    fatswarm.run(n=6, seed=1, scheduler="fsync", crash=2, max_rounds=2, record=record)
    setup = setup_from_header(read_record(str(record)).header, "s", None)
    assert setup.crash == 2 and "crash" not in setup.extra
    plain = tmp_path / "plain.jsonl"
    fatswarm.run(n=6, seed=1, scheduler="fsync", max_rounds=2, record=plain)
    rec = read_record(str(plain))
    assert "crash" not in rec.header.extra
    assert setup_from_header(rec.header, "s", None).crash is None
