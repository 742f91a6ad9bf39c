"""`--noise SIGMA` (inaccurate sensors): each position a Look shows is off by a seeded Gaussian
error, drawn by the world from the seed, the robot and its Look. Noise 0 is the run without it,
byte for byte; a noisy run repeats from its seed; a sweep over noise writes the `noise` column.
Networked against lock step: tests/integration/test_model_networked.py."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy.cli import build_parser
from fatswarm.deploy.engine.config import RunConfig
from fatswarm.deploy.sweep.command import build_grid
from fatswarm.deploy.sweep.pool import RunTable, run_spec
from fatswarm.deploy.sweep.table import make_row
from fatswarm.domain.draws import look_noise
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import ModelError, RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.world.looks import Looks
from fatswarm.world.record_read import read_record

POSITIONS = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 4.0], [4.0, 4.0], [8.0, 1.0]])


def looks(noise: float, seed: int = 3) -> Looks:
    setting = Configured.of(load_algorithm("uniform-circle"), len(POSITIONS), {})
    return Looks(RobotModel.of(noise=noise), setting, len(POSITIONS), seed, False)


def test_noise_zero_records_the_run_without_it_byte_for_byte(tmp_path: Path) -> None:
    plain, zero = tmp_path / "plain.jsonl", tmp_path / "zero.jsonl"
    fatswarm.run(6, seed=5, scheduler="ssync", record=plain)
    fatswarm.run(6, seed=5, scheduler="ssync", noise=0, record=zero)
    assert zero.read_bytes() == plain.read_bytes()
    assert "noise" not in plain.read_text()


def test_a_noisy_run_repeats_from_its_seed_and_another_seed_sees_otherwise(
    tmp_path: Path,
) -> None:
    paths = [tmp_path / f"{k}.jsonl" for k in range(3)]
    for path, seed in zip(paths, (5, 5, 6), strict=True):
        fatswarm.run(6, seed=seed, scheduler="fsync", noise=0.05, max_rounds=30, record=path)
    assert paths[0].read_bytes() == paths[1].read_bytes()
    header = read_record(str(paths[0])).header
    assert header.extra["model"]["noise"] == 0.05
    assert RobotModel.from_header(header.extra["model"]) == RobotModel.of(noise=0.05)
    assert looks(0.5, seed=5).view(POSITIONS, 0, 1)[0].tolist() != (
        looks(0.5, seed=6).view(POSITIONS, 0, 1)[0].tolist()
    )


def test_the_error_differs_by_robot_and_by_look_and_scales_with_sigma() -> None:
    exact, noisy = looks(0.0), looks(0.5)
    errors = {}
    for robot, look in ((0, 1), (0, 2), (1, 1)):
        view = noisy.view(POSITIONS, robot, look)[0]
        errors[robot, look] = view - exact.view(POSITIONS, robot, look)[0]
        expected = 0.5 * look_noise(3, robot, look, len(POSITIONS) - 1)
        assert np.allclose(errors[robot, look], expected, rtol=0, atol=1e-12)
    assert not np.allclose(errors[0, 1], errors[0, 2])
    assert not np.allclose(errors[0, 1], errors[1, 1])
    again = noisy.view(POSITIONS, 0, 1)[0] - exact.view(POSITIONS, 0, 1)[0]
    assert np.array_equal(again, errors[0, 1])  # a re-Look of the same round sees the same


@pytest.mark.parametrize("sigma", [-0.1, float("nan"), float("inf")])
def test_a_negative_or_infinite_sigma_is_refused_in_one_line(sigma: float) -> None:
    with pytest.raises(ModelError, match="--noise must be a finite distance >= 0"):
        RunConfig(n=4, model=RobotModel.of(noise=sigma)).resolve()


def test_a_sweep_over_noise_writes_the_noise_column(tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    argv = ["sweep", "-n", "4", "--seeds", "1", "--scheduler", "fsync", "--noise", "0,0.05"]
    grid = build_grid(build_parser().parse_args([*argv, "--out", str(out)]))
    table = RunTable.open(str(out), models=grid.has_models)
    for spec in grid.runs():
        table.append(make_row(spec, run_spec(spec), "0.1.0"))
    table.close()
    with out.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [row["noise"] for row in rows] == ["", "0.05"]
    assert "--noise 0.05" in rows[1]["command"] and "noise" not in rows[0]["command"]
