"""The algorithm seam: finding algorithms, their parameters, the agent's checks, the CLI, the
record header and the Python API."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np
import pytest

import fatswarm
from fatswarm.agent.service import Robot, WrongAlgorithmError
from fatswarm.deploy import cli
from fatswarm.domain.registry import available, load_algorithm
from fatswarm.domain.seam import (
    AlgorithmError,
    AlgorithmParamsError,
    Configured,
    ParamSpec,
    parse_assignments,
    resolve_values,
)
from fatswarm.world.protocol import Snapshot
from fatswarm.world.record_read import read_record

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parents[1] / "data"


def test_both_shipped_algorithms_are_registered_by_name() -> None:
    names = available()
    assert {"uniform-circle", "gathering"} <= set(names)
    assert load_algorithm("uniform-circle").name == "uniform-circle"
    assert load_algorithm("gathering").name == "gathering"


@pytest.mark.parametrize(
    ("ref", "says"),
    [
        ("nope", "no algorithm named 'nope'"),
        ("fatswarm.agent.nothing:ALGORITHM", "cannot import"),
        ("fatswarm.agent.gathering:NOTHING", "has no attribute"),
        ("fatswarm.agent.geometry:sec", "not an algorithm (missing name"),
        ("missing/file.py:ALGORITHM", "no file missing/file.py"),
        ("gathering:", "expected module:attribute"),
    ],
)
def test_an_algorithm_that_cannot_be_loaded_is_one_line(ref: str, says: str) -> None:
    with pytest.raises(AlgorithmError, match=re.escape(says)) as info:
        load_algorithm(ref)
    assert "\n" not in str(info.value)


def test_a_user_file_that_raises_on_import_is_one_line(tmp_path: Path) -> None:
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('oops')\n")
    with pytest.raises(AlgorithmError, match="raised RuntimeError: oops"):
        load_algorithm(f"{broken}:ALGORITHM")


def test_the_example_file_loads_by_path_and_by_relative_path(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(ROOT)
    assert load_algorithm("examples/spread_out.py:ALGORITHM").name == "spread-out"
    assert load_algorithm(f"{ROOT}/examples/spread_out.py:ALGORITHM").name == "spread-out"


def test_parameters_parse_from_text_and_refuse_unknown_names() -> None:
    circle = load_algorithm("uniform-circle")
    assert resolve_values(circle, {"a": "5"}) == {"a": 5.0}
    assert resolve_values(circle) == {"a": 4.0}
    with pytest.raises(AlgorithmParamsError, match=r"has no parameter 'b' \(it has: a\)"):
        resolve_values(circle, {"b": "1"})
    with pytest.raises(AlgorithmParamsError, match="takes a float"):
        resolve_values(circle, {"a": "wide"})
    with pytest.raises(AlgorithmParamsError, match="must be finite"):
        resolve_values(circle, {"a": "inf"})
    with pytest.raises(AlgorithmParamsError, match=r"a must be > 3"):
        Configured.of(circle, 4, {"a": 2})


def test_typed_parameters_of_every_kind() -> None:
    assert ParamSpec("on", False, "").parse("yes") is True
    assert ParamSpec("k", 3, "").parse("12") == 12
    assert ParamSpec("mode", "x", "").parse("fast") == "fast"
    with pytest.raises(AlgorithmParamsError, match="takes a bool"):
        ParamSpec("on", False, "").parse("perhaps")
    with pytest.raises(AlgorithmParamsError, match="takes a int"):
        ParamSpec("k", 3, "").coerce(1.5)
    assert parse_assignments(["a=5", " b = x "]) == {"a": "5", "b": "x"}
    with pytest.raises(AlgorithmParamsError, match="NAME=VALUE"):
        parse_assignments(["a"])


def _snapshot(algorithm: str, params: dict[str, float | int | str | bool]) -> Snapshot:
    view = np.array([[4.0, 0.0], [0.0, 5.0]])
    return Snapshot(round=1, n=3, algorithm=algorithm, params=params, view=view)


def test_an_agent_stays_put_for_a_world_running_another_algorithm() -> None:
    robot = Robot(load_algorithm("uniform-circle"))
    with pytest.raises(WrongAlgorithmError, match="the world runs algorithm 'gathering'"):
        robot.look_compute(_snapshot("gathering", {"tolerance": 0.001}))
    with pytest.raises(AlgorithmParamsError, match="a must be > 3"):
        robot.look_compute(_snapshot("uniform-circle", {"a": 1.0}))


def test_an_agent_follows_the_parameters_each_snapshot_carries() -> None:
    robot = Robot(load_algorithm("gathering"))
    loose, _ = robot.look_compute(_snapshot("gathering", {"tolerance": 1e-3}))
    strict, _ = robot.look_compute(_snapshot("gathering", {"tolerance": 100.0}))
    assert loose and not strict  # a tolerance above every step: the robot stays


def test_fatswarm_algorithms_lists_them_and_refuses_an_unknown_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert cli.main(["algorithms"]) == 0
    out = capsys.readouterr().out
    assert "uniform-circle:" in out and "--param a=4.0" in out and "gathering:" in out
    assert cli.main(["algorithms", "nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no algorithm named 'nope'" in err[0]


@pytest.mark.parametrize(
    ("flags", "says"),
    [
        (["--algorithm", "gathering", "-a", "5"], "gathering has no parameter 'a'"),
        (["--param", "a"], "--param takes NAME=VALUE"),
        (["--param", "a=5", "-a", "5"], "give the side once"),
        (["--algorithm", "nope"], "no algorithm named 'nope'"),
        (["--algorithm", "gathering", "--param", "tolerance=0"], "tolerance must be"),
    ],
)
def test_run_refuses_bad_algorithm_flags_with_one_line(
    flags: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(["run", "--lockstep", "-n", "4", "--seed", "1", *flags]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0], err


def test_a_lockstep_record_header_says_how_to_repeat_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "g.jsonl"
    argv = [
        "run",
        "--lockstep",
        "-n",
        "5",
        "--seed",
        "4",
        "--algorithm",
        "gathering",
        "--param",
        "tolerance=0.01",
        "--record",
        str(record),
        "-q",
    ]
    assert cli.main(argv) == 0
    assert "algorithm=gathering tolerance=0.01" in capsys.readouterr().out
    header = read_record(record).header
    assert (header.algorithm, header.algorithm_ref, header.params) == (
        "gathering",
        "gathering",
        {"tolerance": 0.01},
    )
    assert header.extra["start"] == "clustered" and header.extra["fairness"] == 10
    assert header.extra["fatswarm_version"] == fatswarm.__version__
    assert "--param" in header.extra["command"]
    assert "a" not in json.loads(record.read_text().splitlines()[0])  # gathering has no a


def test_a_record_from_before_the_seam_reads_as_the_papers_algorithm() -> None:
    header = read_record(DATA / "lockstep-n6-seed1.jsonl").header
    assert (header.algorithm, header.algorithm_ref, header.params) == (
        "uniform-circle",
        "uniform-circle",
        {"a": 4.0},
    )


def test_the_readme_python_example_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Python API", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    assert len(code.strip().splitlines()) == 5
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("formed ") and out[0].endswith(" 0")
    rounds = int(out[0].split()[1])
    assert out[1] == f"({rounds + 1}, 8, 2)"
    assert os.path.exists(tmp_path / "run.jsonl")


def test_the_api_takes_positions_and_refuses_bad_ones() -> None:
    square = np.array([[0.0, 0.0], [6.0, 0.0], [6.0, 6.0], [0.0, 6.0]])
    result = fatswarm.run(positions=square, scheduler="fsync")
    assert result.status == "formed" and np.array_equal(result.initial, square)
    with pytest.raises(ValueError, match=r"\(n, 2\) array"):
        fatswarm.run(positions=np.zeros(3))
    with pytest.raises(ValueError, match="overlap"):
        fatswarm.run(positions=np.zeros((2, 2)))


FAULTY = """
from fatswarm.domain.path import STAY, Line, Path
from fatswarm.domain.seam import ParamSpec

class Faulty:
    name = "faulty"
    summary = "robots whose compute fails in the way `mode` says"
    parameters = (ParamSpec("mode", "raise", "raise, none or nan"),)

    def make_params(self, n, values):
        return values["mode"]

    def compute(self, view, mode):
        if mode in ("badgoal", "badfigures"):
            return STAY
        if mode == "raise":
            return 1 / 0
        if mode == "none":
            return None
        return Path((Line((float("nan"), 0.0)),))

    def goal(self, positions, mode):
        if mode == "badgoal":
            return positions[99]
        return True

    def figures(self, positions, mode):
        return {"x": float("nan"), "y": 1.0} if mode != "badfigures" else {"x": "wide"}

ALGORITHM = Faulty()
"""


@pytest.mark.parametrize(
    ("mode", "says"),
    [
        ("raise", "ZeroDivisionError: division by zero"),
        ("none", "TypeError: compute returned NoneType, not a Path"),
    ],
)
def test_a_failing_compute_in_lock_step_stays_and_the_round_line_says_why(
    tmp_path: Path, mode: str, says: str, caplog: pytest.LogCaptureFixture
) -> None:
    source = tmp_path / "faulty.py"
    source.write_text(FAULTY)
    record = tmp_path / "run.jsonl"
    result = fatswarm.run(
        3,
        algorithm=f"{source}:ALGORITHM",
        params={"mode": mode},
        seed=1,
        scheduler="fsync",
        max_rounds=4,
        record=record,
    )
    # every robot active, none asked to stay: the run stalls at once, and counts its failures
    assert (result.status, result.rounds, result.moves) == ("stalled", 1, 0)
    assert result.derived["failures"] == 3
    assert result.derived["first_failure"] == f"robot 0 in round 1: {says}"
    (entry,) = read_record(record).rounds
    assert "timed_out" not in entry.extra
    assert entry.extra["failed"] == {"0": says, "1": says, "2": says}
    said = [r.getMessage() for r in caplog.records if "the algorithm failed" in r.getMessage()]
    assert len(said) == 1 and says in said[0]  # one line for the kind, no traceback


def test_a_move_the_world_refuses_in_lock_step_leaves_the_robot_timed_out_as_networked(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    source = tmp_path / "faulty.py"
    source.write_text(FAULTY)
    record = tmp_path / "run.jsonl"
    result = fatswarm.run(
        3,
        algorithm=f"{source}:ALGORITHM",
        params={"mode": "nan"},
        seed=1,
        scheduler="fsync",
        max_rounds=4,
        record=record,
    )
    assert (result.status, result.rounds, result.moves) == ("max_rounds", 4, 0)
    assert result.derived["failures"] == 0
    rounds = read_record(record).rounds
    assert all(entry.extra["timed_out"] == [0, 1, 2] for entry in rounds)
    faults = [r.getMessage() for r in caplog.records if r.name == "fatswarm.lockstep"]
    assert len(faults) == 3 and "sent a move the world refuses" in faults[0]
    assert "only counted" in faults[-1]


def test_a_goal_that_raises_ends_the_lockstep_run_with_one_line_naming_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = tmp_path / "faulty.py"
    source.write_text(FAULTY)
    record = tmp_path / "run.jsonl"
    argv = [
        "run",
        "--lockstep",
        "-n",
        "3",
        "--seed",
        "1",
        "--algorithm",
        f"{source}:ALGORITHM",
        "--param",
        "mode=badgoal",
        "--record",
        str(record),
        "-q",
    ]
    assert cli.main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the goal of algorithm faulty raised IndexError" in err[0], err
    assert re.search(r"\(at faulty\.py:\d+\)", err[0])
    assert len(read_record(record).rounds) >= 1  # the rounds before it are kept


def test_figures_that_fail_leave_the_world_without_them_and_drop_non_finite_ones(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    from fatswarm.world.core import WorldCore
    from fatswarm.world.journal import load_configured, perform
    from fatswarm.world.setup import WorldSetup

    source = tmp_path / "faulty.py"
    source.write_text(FAULTY)
    ref = f"{source}:ALGORITHM"
    start = np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
    setup = WorldSetup("s", 3, 1, "fsync", start, 10, algorithm=ref, params={"mode": "stay"})
    fine = WorldCore(setup, load_configured(setup))
    assert fine.state().figures == {"y": 1.0}
    setup = WorldSetup("s", 3, 1, "fsync", start, 10, algorithm=ref, params={"mode": "badfigures"})
    broken = WorldCore(setup, load_configured(setup))
    assert broken.state().figures == {} and broken.state().figures == {}
    perform(broken.take_effects(), None)  # its notes, as the world's shell logs them
    warned = [r for r in caplog.records if "figures of algorithm faulty raised" in r.getMessage()]
    assert len(warned) == 1
