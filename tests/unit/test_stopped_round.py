"""The round a stopped lock-step run names is the last its record holds, not the watch's count
(a signal can land between a round line's write and the count of it)."""

from __future__ import annotations

from pathlib import Path as FsPath

import numpy as np

from fatswarm.deploy.commands.run_lockstep import TAIL_BYTES, last_round
from fatswarm.world.record import RecordWriter


def _record(path: FsPath, n: int, rounds: int) -> None:
    positions = np.arange(2 * n, dtype=np.float64).reshape(n, 2) * 3.0
    with RecordWriter(path) as writer:
        writer.header(n, 1, "fsync", positions, algorithm="uniform-circle", params={"a": 1.0})
        for k in range(1, rounds + 1):
            writer.round(k, list(range(n)), {}, positions)


def test_a_round_line_the_watch_has_not_counted_is_named(tmp_path: FsPath) -> None:
    path = tmp_path / "run.jsonl"
    _record(path, 4, 3)
    assert last_round(str(path), 2) == 3


def test_a_torn_end_is_not_a_round(tmp_path: FsPath) -> None:
    path = tmp_path / "run.jsonl"
    _record(path, 4, 3)
    with open(path, "a", encoding="utf-8") as f:
        f.write('{"type": "round", "round": 4, "active": [0, 1')
    assert last_round(str(path), 3) == 3


def test_a_last_line_longer_than_one_read_is_read_whole(tmp_path: FsPath) -> None:
    path = tmp_path / "run.jsonl"
    _record(path, 4000, 2)  # a round line of about 100 kB
    with open(path, "a", encoding="utf-8") as f:
        f.write("x" * (2 * TAIL_BYTES))  # a torn end longer than the first read
    assert path.stat().st_size > 3 * TAIL_BYTES
    assert last_round(str(path), 0) == 2


def test_a_header_alone_or_no_file_keeps_the_count(tmp_path: FsPath) -> None:
    path = tmp_path / "run.jsonl"
    _record(path, 3, 0)
    assert last_round(str(path), 0) == 0
    assert last_round(str(tmp_path / "missing.jsonl"), 5) == 5
