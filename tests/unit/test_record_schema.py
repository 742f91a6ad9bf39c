"""docs/record.schema.json: every kind of line fatswarm writes (every scheduler, non-rigid moves,
crashes, faults of a networked world, resumed and capped runs, collisions, another algorithm, the
robot models with lights and recorded views, the committed test records) validates against it,
and it refuses lines that break the format, so that docs/record.md and the writer cannot drift
apart unnoticed. The records of every kind are made in tests/support/record_kinds.py;
tests/integration/test_record_schema_networked.py adds a real networked run's."""

from __future__ import annotations

import copy
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from jsonschema import Draft202012Validator
from record_kinds import KINDS, RecordLine, lines_of, problems

from fatswarm.domain.path import point_at
from fatswarm.world.record_read import read_record

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
DOC = ROOT / "docs" / "record.md"
GRID_SNAP = 1e-9  # movers end on the 2^-30 grid: at most 6.6e-10 from where their path took them


# --- records of every kind (tests/support/record_kinds.py) -------------------------------------


@pytest.mark.parametrize("kind", KINDS)
def test_every_line_of_each_kind_of_record_validates(
    validator: Draft202012Validator, records: dict[str, Path], kind: str
) -> None:
    lines = lines_of(records[kind])
    assert KINDS[kind][1](lines), f"the {kind} record no longer shows what it is here for"
    assert problems(validator, records[kind]) == []
    read_record(records[kind])  # and the reader takes it whole


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
    "header-with-an-unknown-visibility": (
        "header",
        put(
            "model",
            {
                "visibility": "foggy",
                "sight": None,
                "lights": "full",
                "frames": "y-axis",
                "frame_change": "fixed",
            },
        ),
    ),
    "header-with-a-zero-sight": (
        "header",
        put(
            "model",
            {
                "visibility": "opaque",
                "sight": 0,
                "lights": "full",
                "frames": "y-axis",
                "frame_change": "fixed",
            },
        ),
    ),
    "header-with-a-model-missing-an-axis": ("header", put("model", {"visibility": "opaque"})),
    "header-with-record-views-false": ("header", put("record_views", False)),
    "header-with-an-empty-assumption": ("header", put("assumption", "")),
    "round-with-a-colour-by-index": ("round", put("lights", [0, 1])),
    "round-with-no-lights": ("round", put("lights", [])),
    "round-with-a-colour-with-a-space": ("round", put("lights", ["dark red"])),
    "round-with-views-as-a-list": ("round", put("views", [[1, 2]])),
    "round-with-views-keyed-by-name": ("round", put("views", {"r0": [1]})),
    "round-with-views-keyed-with-a-zero": ("round", put("views", {"01": [1]})),
    "round-with-a-robot-seen-twice": ("round", put("views", {"0": [1, 1]})),
    "round-with-a-negative-robot-seen": ("round", put("views", {"0": [-1]})),
    "round-with-no-failure-in-failed": ("round", put("failed", {})),
    "round-with-a-failure-that-is-no-text": ("round", put("failed", {"0": 3})),
    "round-with-a-failure-keyed-by-name": ("round", put("failed", {"r0": "KeyError"})),
    "round-with-failed-as-a-list": ("round", put("failed", ["0"])),
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


def test_the_robot_model_fields_validate_on_any_record(
    validator: Draft202012Validator, records: dict[str, Path]
) -> None:
    """The model's header fields and round fields, as the writer writes them (docs/record.md):
    an unlimited sight is null, a robot that Looked and saw nobody has an empty list."""
    lines = sample_lines(records)
    header = {
        **lines["header"],
        "model": {
            "visibility": "opaque-centres",
            "sight": None,
            "lights": "internal",
            "frames": "disoriented",
            "frame_change": "every-look",
        },
        "record_views": True,
        "assumption": "algorithm a assumes frames y-axis; this run gives it disoriented",
    }
    assert validator.is_valid(header)
    line = lines["round"]
    n = len(line["positions"])
    round_line = {**line, "lights": ["still"] * n, "views": {"0": [], str(n - 1): [0]}}
    assert validator.is_valid(round_line)


def test_a_header_may_carry_fields_of_its_own(
    validator: Draft202012Validator, records: dict[str, Path]
) -> None:
    """The header is open by design (`fatswarm world --header`): unknown keys pass."""
    header = {**sample_lines(records)["header"], "lab": {"operator": "ada"}}
    assert validator.is_valid(header)
