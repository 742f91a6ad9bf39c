"""Run records of every kind fatswarm writes, made in this process (lock step and the world's
core), and their lines checked against docs/record.schema.json: shared by the unit and the
integration tests of the schema (tests/conftest.py makes them fixtures)."""

from __future__ import annotations

import contextlib
import io
import json
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
from fatswarm.domain.path import STAY, Line
from fatswarm.domain.path import Path as RobotPath
from fatswarm.world.core import WorldCore
from fatswarm.world.faults import crash_after
from fatswarm.world.journal import load_configured, perform
from fatswarm.world.protocol import Begin, Commit, MoveSubmitted
from fatswarm.world.record import RecordWriter
from fatswarm.world.setup import WorldSetup

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = ROOT / "docs" / "record.schema.json"

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


def schema_validator() -> Draft202012Validator:
    """A validator of docs/record.schema.json (the schema itself checked first)."""
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
        world = WorldCore(setup, load_configured(setup))
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
            perform(world.take_effects(), rec)  # the header first, then this round
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


LIT_SPREAD = f"{ROOT / 'tests' / 'data' / 'lit_spread.py'}:ALGORITHM"  # a luminous test algorithm


def luminous(flags: str) -> Callable[[Path], None]:
    """A lock-step run of the luminous test algorithm with these (space-separated) flags."""
    return lockstep("--algorithm", LIT_SPREAD, *flags.split())


def header_has(*keys: str) -> Callable[[list[RecordLine]], bool]:
    return lambda lines: all(key in lines[0] for key in keys)


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
    "async-crash": (  # the crash adversary's crash, on the first cycle line after it
        lockstep("-n", "6", "--seed", "2", "--scheduler", "async", "--crash", "1"),
        lambda lines: rounds_with("crash")(lines) and rounds_with("crash_at")(lines),
    ),
    "async-slowest": (
        lockstep("-n", "4", "--seed", "2", "--scheduler", "async-slowest"),
        lambda lines: "fairness_time" in lines[0] and status("formed")(lines),
    ),
    "world-faults": (
        faults,
        lambda lines: all(rounds_with(key)(lines) for key in ("timed_out", "crashed", "recovered")),
    ),
    "lights-views-opaque": (
        luminous(
            "-n 6 --seed 3 --scheduler fsync --record-views --sight 6 --visibility opaque"
            " --frames disoriented"
        ),
        lambda lines: (
            header_has("model", "record_views")(lines)
            and rounds_with("lights")(lines)
            and rounds_with("views")(lines)
        ),
    ),
    "lights-views-async": (
        luminous(
            "-n 6 --seed 3 --scheduler async --record-views --sight 6 --visibility opaque-centres"
            " --frames chirality --frame-change every-look"
        ),
        lambda lines: (
            header_has("model", "record_views", "fairness_time")(lines)
            and rounds_with("look")(lines)
            and rounds_with("lights")(lines)
            and rounds_with("views")(lines)
        ),
    ),
    "lights-crash-external": (
        luminous("-n 8 --seed 4 --scheduler ssync --crash 2 --visibility opaque --lights external"),
        lambda lines: (
            header_has("model")(lines)
            and rounds_with("crash")(lines)
            and rounds_with("lights")(lines)
            and not rounds_with("views")(lines)
        ),
    ),
    "paper-model-views": (
        lockstep("-n", "5", "--seed", "1", "--record-views"),
        lambda lines: (
            header_has("record_views")(lines)
            and header_without("model")(lines)
            and rounds_with("views")(lines)
            and not rounds_with("lights")(lines)
        ),
    ),
    "compute-failed": (  # the paper's algorithm refuses a view short of n - 1 robots
        lockstep("-n", "6", "--seed", "3", "--visibility", "opaque", "--scheduler", "ssync"),
        lambda lines: rounds_with("failed")(lines) and status("stalled")(lines),
    ),
    "outside-assumption": (
        lockstep("-n", "5", "--seed", "1", "--frames", "chirality"),
        lambda lines: header_has("model", "assumption")(lines) and status("stalled")(lines),
    ),
}


def make_records(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One record of each kind of KINDS, each in a folder of its own: name -> path."""
    made: dict[str, Path] = {}
    for name, (make, _) in KINDS.items():
        folder = tmp_path_factory.mktemp(name)
        make(folder / "run.jsonl")
        made[name] = folder / "run.jsonl"
    return made
