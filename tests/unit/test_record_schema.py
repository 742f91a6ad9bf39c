"""docs/record.schema.json: every kind of line fatswarm writes (every scheduler, non-rigid moves,
crashes, faults of a networked world, resumed and capped runs, collisions, another algorithm, a
real networked run, the committed test records) validates against it, and it refuses lines that
break the format, so that docs/record.md and the writer cannot drift apart unnoticed."""

from __future__ import annotations

import contextlib
import copy
import io
import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from jsonschema import Draft202012Validator

from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy import cli
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.domain.path import STAY, Line, point_at
from fatswarm.domain.path import Path as RobotPath
from fatswarm.world.core import WorldCore, WorldSetup, crash_after
from fatswarm.world.protocol import Begin, Commit, MoveSubmitted
from fatswarm.world.record import RecordWriter, read_record

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = ROOT / "docs" / "record.schema.json"
DATA = ROOT / "tests" / "data"
DOC = ROOT / "docs" / "record.md"
GRID_SNAP = 1e-9  # movers end on the 2^-30 grid: at most 6.6e-10 from where their path took them

RecordLine = dict[str, Any]


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON (the writer never writes it)")


def lines_of(path: Path) -> list[RecordLine]:
    """The record's lines as JSON objects (NaN and Infinity refused, as the writer never writes
    them and a JSON Schema number would let them through)."""
    return [
        json.loads(text, parse_constant=_no_constant)
        for text in path.read_text().splitlines()
        if text.strip()
    ]


@pytest.fixture(scope="module")
def validator() -> Draft202012Validator:
    schema = json.loads(SCHEMA.read_text())
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema)


def problems(validator: Draft202012Validator, record: Path) -> list[str]:
    """Every schema error of every line, as `line N: message`."""
    return [
        f"line {number}: {error.message}"
        for number, line in enumerate(lines_of(record), start=1)
        for error in validator.iter_errors(line)
    ]


# --- records of every kind ----------------------------------------------------------------------


def fatswarm_lockstep(record: Path, *flags: str) -> None:
    """`fatswarm run --lockstep -q --record RECORD FLAGS` in this process (summary discarded)."""
    with contextlib.redirect_stdout(io.StringIO()):
        code = cli.main(["run", "--lockstep", "-q", "--record", str(record), *flags])
    assert code in (0, 1, 3), f"fatswarm run {flags} exited {code}"


def bump(view: np.ndarray, params: Any) -> RobotPath:
    """Two robots: rush at the other when far (contact stops both), back off to 4 when near."""
    ((x, y),) = view
    distance = float(np.hypot(x, y))
    if distance > 6.0:
        return RobotPath((Line((x, y)),))
    if distance < 4.0:
        k = (4.0 - distance) / (2.0 * distance)
        return RobotPath((Line((-k * x, -k * y)),))
    return STAY


def collide(record: Path) -> None:
    """Two robots that run into each other: a round with two collisions (both were moving)."""
    with RecordWriter(record) as rec:
        run_lockstep(
            np.array([[0.0, 0.0], [8.0, 0.0]]),
            Params(2, 4.0),
            make_scheduler("fsync", 2, 0),
            seed=0,
            record=rec,
            compute=bump,
            header_extra={"command": ["test_record_schema.py", "collide"]},
        )


def faults(record: Path) -> None:
    """The networked world's core with robot 1's agent gone, then back: rounds with `timed_out`,
    then `crashed` (after crash_after(2) rounds) and `recovered`, and a max_rounds result."""
    cap = crash_after(2) + 2
    setup = WorldSetup(
        swarm="schema",
        n=2,
        seed=5,
        scheduler="fsync",
        initial=np.array([[0.0, 0.0], [10.0, 0.0]]),
        max_rounds=cap,
        algorithm="gathering",
        extra={"move_timeout": 5.0},
    )
    with RecordWriter(record) as rec:
        world = WorldCore(setup, rec)
        world.set_alive(0, True)
        for round_no in range(1, cap + 1):
            if round_no == crash_after(2) + 1:
                world.set_alive(1, True)  # back, but it sends no move: still timed out
            assert world.control(Begin(round_no, (0, 1)))[0].ok
            assert world.look(0) is not None
            step = 0.5 if round_no % 2 else -0.5  # robot 0 keeps moving, so nothing stalls
            world.move(
                0, MoveSubmitted(robot=0, round=round_no, path=RobotPath((Line((0.0, step)),)))
            )
            assert world.control(Commit(round_no, timed_out=(1,)))[0].ok
    assert world.status == "max_rounds"


def resumed(record: Path) -> None:
    """A lock-step ssync run cut after 5 rounds (a crash: no result line), then --resume'd."""
    whole = record.with_name("whole.jsonl")
    fatswarm_lockstep(whole, "-n", "5", "--seed", "1", "--scheduler", "ssync")
    record.write_text("".join(whole.read_text().splitlines(keepends=True)[:6]))
    fatswarm_lockstep(record, "--resume")


def scripted(record: Path) -> None:
    """The scripted scheduler from a --schedule file, from an --init file."""
    schedule, init = record.with_name("schedule.json"), record.with_name("init.json")
    schedule.write_text(json.dumps({"rounds": [[0, 2], [1], [3], [0, 1, 2, 3]]}))
    init.write_text(json.dumps({"positions": [[0, 0], [3, 0], [0, 3], [-3, -1]], "a": 4.0}))
    fatswarm_lockstep(
        record,
        "--init",
        str(init),
        "--seed",
        "1",
        "--scheduler",
        "scripted",
        "--schedule",
        str(schedule),
    )


def lockstep(*flags: str) -> Callable[[Path], None]:
    return lambda record: fatswarm_lockstep(record, *flags)


def rounds_with(key: str) -> Callable[[list[RecordLine]], bool]:
    return lambda lines: any(line["type"] == "round" and key in line for line in lines)


def has_arc(lines: list[RecordLine]) -> bool:
    return any(
        "arc" in segment
        for line in lines
        if line["type"] == "round"
        for move in line["moves"]
        for segment in move["path"]
    )


def status(name: str) -> Callable[[list[RecordLine]], bool]:
    return lambda lines: lines[-1]["type"] == "result" and lines[-1]["status"] == name


def header_without(key: str) -> Callable[[list[RecordLine]], bool]:
    return lambda lines: key not in lines[0]


# name: (how to make it, what it must show for the kind to be covered)
KINDS: dict[str, tuple[Callable[[Path], None], Callable[[list[RecordLine]], bool]]] = {
    "fsync-with-an-arc": (
        lockstep("-n", "5", "--seed", "3", "--start", "dense", "--scheduler", "fsync"),
        has_arc,
    ),
    "ssync": (lockstep("-n", "5", "--seed", "1", "--scheduler", "ssync"), status("formed")),
    "centralized": (
        lockstep("-n", "4", "--seed", "1", "--scheduler", "centralized"),
        status("formed"),
    ),
    "scripted": (scripted, status("formed")),
    "non-rigid": (
        lockstep("-n", "5", "--seed", "1", "--scheduler", "fsync", "--non-rigid", "1"),
        rounds_with("cut"),
    ),
    "crash-stalled": (
        lockstep("-n", "4", "--seed", "2", "--scheduler", "fsync", "--crash", "1"),
        lambda lines: rounds_with("crash")(lines) and status("stalled")(lines),
    ),
    "max-rounds": (lockstep("-n", "5", "--seed", "1", "--max-rounds", "3"), status("max_rounds")),
    "gathering": (
        lockstep("-n", "5", "--seed", "1", "--algorithm", "gathering"),
        header_without("a"),
    ),
    "resumed": (resumed, status("formed")),
    "collisions": (collide, lambda lines: any(line.get("collisions") for line in lines[1:-1])),
    "async": (
        lockstep("-n", "5", "--seed", "1", "--scheduler", "async", "--non-rigid", "1"),
        lambda lines: (
            rounds_with("look")(lines) and rounds_with("cut")(lines) and "time" in lines[-1]
        ),
    ),
    "async-slowest": (
        lockstep("-n", "4", "--seed", "2", "--scheduler", "async-slowest"),
        lambda lines: "fairness_time" in lines[0] and status("formed")(lines),
    ),
    "world-faults": (
        faults,
        lambda lines: all(rounds_with(key)(lines) for key in ("timed_out", "crashed", "recovered")),
    ),
}


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    made: dict[str, Path] = {}
    for name, (make, _) in KINDS.items():
        folder = tmp_path_factory.mktemp(name)
        make(folder / "run.jsonl")
        made[name] = folder / "run.jsonl"
    return made


@pytest.fixture(scope="module")
def networked_record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real networked run (router, world, coordinator, 4 agent processes): about 2 s."""
    record = tmp_path_factory.mktemp("networked") / "run.jsonl"
    argv = [
        sys.executable,
        "-m",
        "fatswarm.deploy.cli",
        "run",
        "-n",
        "4",
        "--seed",
        "3",
        "--scheduler",
        "fsync",
        "--record",
        str(record),
        "-q",
        "--no-dashboard",
        "--pace",
        "0",
    ]
    proc = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    try:
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 0, out.decode(errors="replace")
    return record


@pytest.mark.parametrize("kind", KINDS)
def test_every_line_of_each_kind_of_record_validates(
    validator: Draft202012Validator, records: dict[str, Path], kind: str
) -> None:
    lines = lines_of(records[kind])
    assert KINDS[kind][1](lines), f"the {kind} record no longer shows what it is here for"
    assert problems(validator, records[kind]) == []
    read_record(records[kind])  # and the reader takes it whole


@pytest.mark.integration
def test_every_line_of_a_networked_record_validates(
    validator: Draft202012Validator, networked_record: Path
) -> None:
    header = lines_of(networked_record)[0]
    assert header["swarm"] != "lockstep" and "move_timeout" in header
    assert problems(validator, networked_record) == []


@pytest.mark.integration
def test_the_records_use_every_key_the_schema_names(
    records: dict[str, Path], networked_record: Path
) -> None:
    """The kinds above cover the format: a key the schema names that no record shows would be
    documented but untested (and a key no schema names fails validation above)."""
    schema = json.loads(SCHEMA.read_text())
    seen: dict[str, set[str]] = {"header": set(), "round": set(), "result": set()}
    for record in [*records.values(), networked_record]:
        for line in lines_of(record):
            seen[line["type"]] |= set(line)
    for kind, keys in seen.items():
        assert set(schema["$defs"][kind]["properties"]) <= keys, kind


@pytest.mark.parametrize("record", sorted(DATA.glob("*.jsonl")), ids=lambda p: p.name)
def test_every_line_of_the_committed_test_records_validates(
    validator: Draft202012Validator, record: Path
) -> None:
    assert problems(validator, record) == []


def test_the_example_lines_of_record_md_validate(validator: Draft202012Validator) -> None:
    blocks = re.findall(r"```json\n(.*?)```", DOC.read_text(), flags=re.DOTALL)
    examples = [json.loads(text) for block in blocks for text in block.splitlines()]
    assert {line["type"] for line in examples} == {"header", "round", "result"}
    assert [error.message for line in examples for error in validator.iter_errors(line)] == []


def test_there_are_committed_test_records_to_validate() -> None:
    assert len(list(DATA.glob("*.jsonl"))) >= 2


def test_a_position_within_a_round_is_the_point_at_that_time_along_the_path(
    records: dict[str, Path],
) -> None:
    """docs/record.md's recipe: all paths start at t = 0 from the previous positions at unit
    speed; a robot stops at `traveled` (a collision's `t` for the robot it stopped), which is
    where the round line puts it (up to the grid snap)."""
    checked = 0
    for record in records.values():
        run = read_record(record)
        before = run.header.initial
        for entry in run.rounds:
            stops = {c.robot: c.t for c in entry.collisions}
            for move in entry.moves:
                start = (float(before[move.robot, 0]), float(before[move.robot, 1]))
                end = point_at(start, move.path, move.traveled)
                assert (
                    np.hypot(
                        end[0] - entry.positions[move.robot, 0],
                        end[1] - entry.positions[move.robot, 1],
                    )
                    <= GRID_SNAP
                )
                if move.robot in stops:
                    assert stops[move.robot] == move.traveled
                checked += 1
            before = entry.positions
    assert checked > 50


# --- lines that break the format are refused ----------------------------------------------------


def drop(key: str) -> Callable[[RecordLine], None]:
    return lambda line: line.pop(key)


def drop_all(line: RecordLine, *keys: str) -> None:
    for key in keys:
        line.pop(key)


def put(key: str, value: Any) -> Callable[[RecordLine], None]:
    return lambda line: line.update({key: value})


def in_first_move(key: str, value: Any) -> Callable[[RecordLine], None]:
    return lambda line: line["moves"][0].update({key: value})


def first_segment(value: Any) -> Callable[[RecordLine], None]:
    return lambda line: line["moves"][0].update({"path": [value]})


# (line kind, how the line is broken)
BROKEN: dict[str, tuple[str, Callable[[RecordLine], None]]] = {
    "header-without-n": ("header", drop("n")),
    "header-with-a-text-seed": ("header", put("seed", "1")),
    "header-of-another-version": ("header", put("version", 2)),
    "header-with-a-negative-crash": ("header", put("crash", -1)),
    "header-with-neither-params-nor-a": ("header", lambda line: drop_all(line, "params", "a")),
    "round-without-positions": ("round", drop("positions")),
    "round-without-collisions": ("round", drop("collisions")),
    "round-with-a-text-active-set": ("round", put("active", "0 1")),
    "round-with-an-unknown-key": ("round", put("speed", 1.0)),
    "round-with-an-empty-cut-list": ("round", put("cut", [])),
    "round-with-a-boolean-robot": ("round", in_first_move("robot", True)),
    "round-with-a-negative-traveled": ("round", in_first_move("traveled", -1.0)),
    "round-with-an-unknown-move-key": ("round", in_first_move("speed", 1.0)),
    "round-with-an-empty-path": ("round", in_first_move("path", [])),
    "round-with-an-unknown-segment": ("round", first_segment({"curve": [0.0, 0.0]})),
    "round-with-a-two-key-segment": (
        "round",
        first_segment({"line": [0.0, 0.0], "arc": [0.0, 0.0, 1.0]}),
    ),
    "round-with-a-short-arc": ("round", first_segment({"arc": [0.0, 1.0]})),
    "round-with-a-three-number-point": ("round", lambda line: line["positions"][0].append(0.0)),
    "result-still-running": ("result", put("status", "running")),
    "result-with-an-unknown-key": ("result", put("verdict", "fine")),
    "result-with-fractional-rounds": ("result", put("rounds", 2.5)),
    "unknown-line-type": ("result", put("type", "note")),
}


def sample_lines(records: dict[str, Path]) -> dict[str, RecordLine]:
    """A header with params and a, a round with a move, and a result, of one record."""
    lines = lines_of(records["ssync"])
    return {
        "header": lines[0],
        "result": lines[-1],
        "round": next(line for line in lines[1:-1] if line["moves"]),
    }


@pytest.mark.parametrize("broken", BROKEN)
def test_a_line_that_breaks_the_format_is_refused(
    validator: Draft202012Validator, records: dict[str, Path], broken: str
) -> None:
    kind, damage = BROKEN[broken]
    line = copy.deepcopy(sample_lines(records)[kind])
    assert validator.is_valid(line)
    damage(line)
    assert not validator.is_valid(line)


def test_a_header_may_carry_fields_of_its_own(
    validator: Draft202012Validator, records: dict[str, Path]
) -> None:
    """The header is open by design (`fatswarm world --header`): unknown keys pass."""
    header = {**sample_lines(records)["header"], "lab": {"operator": "ada"}}
    assert validator.is_valid(header)
