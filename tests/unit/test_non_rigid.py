"""Issue 10's non-rigid model: the adversary stops a move after delta (or at its end), drawn from
(seed, round, robot); a lock-step run records the cut paths, and resumes exactly."""

from __future__ import annotations

import math
from pathlib import Path as FsPath

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy import cli
from fatswarm.domain.draws import cut_fraction
from fatswarm.domain.path import Arc, Line, Path, Point, end_point, path_length, point_at
from fatswarm.world import rounds
from fatswarm.world.faults import cut_path
from fatswarm.world.record_read import read_record
from fatswarm.world.setup import setup_from_header

START: Point = (1.0, 2.0)
LONG = Path((Line((4.0, 2.0)), Arc((4.0, 3.0), math.pi / 2)))  # 3 + pi/2 long


def test_a_path_no_longer_than_delta_is_left_whole() -> None:
    short = Path((Line((1.5, 2.0)),))
    assert cut_path(START, short, 0.5, 0.99) is short
    assert cut_path(START, short, 1.0, 0.0) is short


@pytest.mark.parametrize("u", [0.0, 0.25, 0.5, 0.999999])
@pytest.mark.parametrize("delta", [0.1, 1.0, 3.5])
def test_a_longer_path_is_cut_to_delta_plus_u_of_the_rest_and_ends_on_it(
    delta: float, u: float
) -> None:
    whole = path_length(START, LONG)
    cut = cut_path(START, LONG, delta, u)
    wanted = delta + u * (whole - delta)
    assert path_length(START, cut) == pytest.approx(wanted, abs=1e-12)
    assert delta - 1e-12 <= path_length(START, cut) <= whole
    assert np.allclose(end_point(START, cut), point_at(START, LONG, wanted), atol=1e-12)


def test_the_draw_is_a_pure_function_of_seed_round_and_robot() -> None:
    draws = {
        (s, r, k): cut_fraction(s, r, k) for s in (0, 1, 2**40) for r in (1, 2, 3) for k in range(6)
    }
    assert all(0.0 <= u < 1.0 for u in draws.values())
    assert draws == {key: cut_fraction(*key) for key in draws}  # no hidden state
    assert len(set(draws.values())) == len(draws)  # robots, rounds and seeds draw apart
    assert cut_fraction(0, 1, 0) != cut_fraction(0, 2, 0) != cut_fraction(1, 2, 0)


@pytest.mark.parametrize("scheduler", ["fsync", "ssync"])
@pytest.mark.parametrize("seed", [1, 2])
def test_the_paper_algorithm_forms_under_non_rigid_moves_and_records_the_cut_paths(
    scheduler: str, seed: int, tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen: list[tuple[Point, Path, float, float, Path]] = []

    def spy(start: Point, path: Path, delta: float, u: float) -> Path:
        out = cut_path(start, path, delta, u)
        seen.append((start, path, delta, u, out))
        return out

    monkeypatch.setattr(rounds, "cut_path", spy)
    record = tmp_path / "run.jsonl"
    result = fatswarm.run(n=6, seed=seed, scheduler=scheduler, non_rigid=1.0, record=record)
    assert (result.status, result.collisions) == ("formed", 0)
    rec = read_record(str(record))
    assert rec.header.extra["non_rigid"] == 1.0
    for start, path, delta, u, out in seen:  # the rule, for every move
        whole = path_length(start, path)
        want = whole if whole <= delta else delta + u * (whole - delta)
        assert path_length(start, out) == pytest.approx(want, abs=1e-9)
    applied = {(tuple(map(float, s)), o) for s, _, _, _, o in seen}
    cuts = 0
    before = rec.header.initial
    for entry in rec.rounds:
        cut = set(entry.extra.get("cut", ()))
        cuts += len(cut)
        for move in entry.moves:  # the record keeps the path as cut
            start = (float(before[move.robot, 0]), float(before[move.robot, 1]))
            assert (start, move.path) in applied
            assert path_length(start, move.path) >= 1.0 - 1e-9 or move.robot not in cut
        before = entry.positions
    assert cuts > 0  # the adversary did stop moves


def test_a_rigid_record_says_nothing_of_non_rigid(tmp_path: FsPath) -> None:
    record = tmp_path / "run.jsonl"
    fatswarm.run(n=6, seed=1, scheduler="fsync", record=record)
    rec = read_record(str(record))
    assert "non_rigid" not in rec.header.extra
    assert not any("cut" in entry.extra for entry in rec.rounds)


def _fatswarm(*argv: str) -> int:
    return cli.main(["run", "--lockstep", "-q", *argv])


@pytest.mark.parametrize("scheduler", ["fsync", "ssync"])
def test_resuming_a_non_rigid_record_reproduces_it_byte_for_byte(
    scheduler: str, tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = tmp_path / "whole.jsonl"
    assert (
        _fatswarm(
            "-n",
            "6",
            "--seed",
            "2",
            "--scheduler",
            scheduler,
            "--non-rigid",
            "1",
            "--record",
            str(whole),
        )
        == 0
    )
    lines = whole.read_text().splitlines(keepends=True)
    assert any('"cut"' in line for line in lines[1:5])
    part = tmp_path / "part.jsonl"
    part.write_text("".join(lines[:5]))  # the header and 4 rounds: a crash
    assert _fatswarm("--record", str(part), "--resume", "--non-rigid", "2") == 2
    err = capsys.readouterr().err
    assert "--non-rigid 2 contradicts" in err and "non_rigid=1" in err and err.count("\n") == 1
    assert _fatswarm("--record", str(part), "--resume") == 0
    assert part.read_text() == whole.read_text()


def test_resume_refuses_non_rigid_for_a_rigid_record(
    tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = tmp_path / "whole.jsonl"
    assert _fatswarm("-n", "6", "--seed", "2", "--record", str(whole)) == 0
    part = tmp_path / "part.jsonl"
    part.write_text("".join(whole.read_text().splitlines(keepends=True)[:4]))
    assert _fatswarm("--record", str(part), "--resume", "--non-rigid", "1") == 2
    assert "whose run has rigid moves" in capsys.readouterr().err


@pytest.mark.parametrize("delta", ["0", "-1", "inf", "nan"])
def test_a_delta_that_is_not_a_finite_positive_distance_is_refused(
    delta: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _fatswarm("-n", "6", f"--non-rigid={delta}") == 2
    err = capsys.readouterr().err
    assert err.startswith("fatswarm run: --non-rigid must be") and err.count("\n") == 1


def test_the_world_reads_delta_back_from_the_header(tmp_path: FsPath) -> None:
    record = tmp_path / "run.jsonl"
    fatswarm.run(n=6, seed=1, scheduler="fsync", non_rigid=0.5, max_rounds=2, record=record)
    setup = setup_from_header(read_record(str(record)).header, "s", None)
    assert setup.non_rigid == 0.5
    assert "non_rigid" not in setup.extra
    assert setup.version and "fatswarm_version" not in setup.extra  # typed, not an open field
