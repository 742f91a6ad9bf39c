"""Run records: written records read back identically; malformed files name line and reason."""

from __future__ import annotations

import json
from pathlib import Path as FsPath

import numpy as np
import pytest

from fatswarm.domain.path import Arc, Line, Path
from fatswarm.world.physics import Collision
from fatswarm.world.record import Header, RecordFormatError, RecordWriter, Result, RoundEntry
from fatswarm.world.record_read import iter_record, read_record

INITIAL = np.array([[0.0, 0.0], [3.0, 0.0]])
AFTER = np.array([[0.0, 1.0], [3.0, 0.0]])
PATH = Path((Line((0.0, 1.0)), Arc((3.0, 0.0), 0.5)))


def write_sample(path: FsPath, *, fsync: bool = False, finish: bool = True) -> None:
    with RecordWriter(path, fsync=fsync) as w:
        w.header(2, 7, "ssync", INITIAL, algorithm="uniform-circle", params={"a": 4.0}, fairness=4)
        w.round(1, [0, 1], {0: (PATH, 1.25)}, AFTER, [Collision(0, 1, 0.5, (0.0, 0.5))])
        w.round(2, [1], {}, AFTER)
        if finish:
            w.result("stalled", 2, AFTER, epochs=1)


def test_written_record_reads_back(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    write_sample(target)
    record = read_record(target)
    assert (record.header.n, record.header.a, record.header.seed) == (2, 4.0, 7)
    assert record.header.scheduler == "ssync" and record.header.extra == {"fairness": 4}
    np.testing.assert_array_equal(record.header.initial, INITIAL)
    first, second = record.rounds
    assert first.active == (0, 1) and first.moves[0].path == PATH
    assert first.moves[0].traveled == 1.25
    assert first.collisions == (Collision(0, 1, 0.5, (0.0, 0.5)),)
    assert second.moves == () and second.collisions == ()
    np.testing.assert_array_equal(second.positions, AFTER)
    assert record.result is not None
    assert (record.result.status, record.result.rounds) == ("stalled", 2)
    assert record.result.epochs == 1 and record.result.extra == {}  # typed, not an extra


def test_lines_follow_the_documented_schema(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    write_sample(target, fsync=True)
    lines = [json.loads(x) for x in target.read_text().splitlines()]
    assert [x["type"] for x in lines] == ["header", "round", "round", "result"]
    assert lines[0]["version"] == 1 and lines[0]["initial"] == [[0.0, 0.0], [3.0, 0.0]]
    assert lines[1]["moves"] == [
        {"robot": 0, "path": [{"line": [0.0, 1.0]}, {"arc": [3.0, 0.0, 0.5]}], "traveled": 1.25}
    ]
    assert lines[1]["collisions"] == [{"robot": 0, "other": 1, "t": 0.5, "point": [0.0, 0.5]}]


def test_writer_truncates_unless_appending(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    write_sample(target)
    write_sample(target)
    assert len(read_record(target).rounds) == 2
    with RecordWriter(target, append=True) as w:
        w.write({"type": "noise"})
    assert target.read_text().splitlines()[-1] == '{"type":"noise"}'


def test_appending_after_a_last_line_without_newline_starts_a_new_line(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    write_sample(target, finish=False)
    target.write_text(target.read_text().rstrip("\n"))  # e.g. cut by hand
    with RecordWriter(target, append=True) as w:
        assert target.read_text().endswith("}")  # nothing is written before the first line
        w.round(3, [0], {}, AFTER)
    assert [r.round for r in read_record(target).rounds] == [1, 2, 3]


def test_unfinished_record_has_no_result(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    write_sample(target, finish=False)
    assert read_record(target).result is None


def test_iter_record_streams_entries_in_order(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    write_sample(target)
    kinds = [type(e) for e in iter_record(target)]
    assert kinds == [Header, RoundEntry, RoundEntry, Result]


def test_writer_refuses_non_finite_numbers(tmp_path: FsPath) -> None:
    with RecordWriter(tmp_path / "run.jsonl") as w, pytest.raises(ValueError):
        w.header(
            1, 0, "fsync", np.array([[np.nan, 0.0]]), algorithm="uniform-circle", params={"a": 4.0}
        )


def mutate(tmp_path: FsPath, line: int, change: dict[str, object] | str) -> FsPath:
    target = tmp_path / "run.jsonl"
    write_sample(target)
    lines = target.read_text().splitlines()
    if isinstance(change, str):
        lines[line - 1] = change
    else:
        entry = json.loads(lines[line - 1])
        entry.update(change)
        lines[line - 1] = json.dumps(entry)
    target.write_text("\n".join(lines) + "\n")
    return target


@pytest.mark.parametrize(
    ("line", "change", "reason"),
    [
        (1, "{not json", "not JSON"),
        (1, {"type": "round"}, "first line must be the header"),
        (1, {"version": 2}, "unsupported record version"),
        (1, {"model": {"visibility": "foggy"}}, "unreadable robot 'model' (--visibility must be"),
        (1, {"model": {"sight": "far"}}, "unreadable robot 'model' (--sight must be"),
        (1, {"model": {"eyes": 2}}, "unreadable robot 'model' (a record's model must be"),
        (1, {"n": 0}, "'n' must be a whole number >= 1"),
        (1, {"initial": [[0, 0]]}, "'initial' must be a list of 2"),
        (2, {"active": [0, 5]}, "robot number in 0..1"),
        (2, {"moves": [{"robot": 0, "path": [{"jump": [1, 2]}], "traveled": 1}]}, "bad path"),
        (2, {"moves": [{"robot": 0, "path": [], "traveled": -1}]}, "'traveled' must be >= 0"),
        (2, {"positions": [[0, 0], [1, "x"]]}, "finite number"),
        (2, {"collisions": [{"robot": 0, "other": 1, "t": 0, "point": [0]}]}, "'point' must be"),
        (3, {"round": 5}, "rounds must be consecutive"),
        (3, {"type": "noise"}, "unknown line type"),
        (4, {"status": "done"}, "'status' must be one of"),
        (3, "[1, 2]", "must be a JSON object"),
    ],
)
def test_malformed_line_is_reported_with_its_number(
    tmp_path: FsPath, line: int, change: dict[str, object] | str, reason: str
) -> None:
    target = mutate(tmp_path, line, change)
    with pytest.raises(RecordFormatError) as info:
        read_record(target)
    message = str(info.value)
    assert message.startswith(f"{target}:{line}: ") and reason in message and "\n" not in message


def test_line_after_result_is_refused(tmp_path: FsPath) -> None:
    target = tmp_path / "run.jsonl"
    write_sample(target)
    with target.open("a") as fh:
        fh.write(json.dumps({"type": "round"}) + "\n")
    with pytest.raises(RecordFormatError, match=":5: nothing may follow the result"):
        read_record(target)


def test_missing_and_empty_files_are_named(tmp_path: FsPath) -> None:
    with pytest.raises(RecordFormatError, match="cannot read run record"):
        read_record(tmp_path / "absent.jsonl")
    (tmp_path / "empty.jsonl").write_text("")
    with pytest.raises(RecordFormatError, match="empty run record"):
        read_record(tmp_path / "empty.jsonl")
