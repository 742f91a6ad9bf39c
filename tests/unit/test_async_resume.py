"""Async runs resume and survive restarts (issue 28): a record replayed from its start is checked
line by line, the coordinator draws delays for the cycles the world says began (so a restarted
one goes on as before), a coordinator whose world is gone gives up after its bound, and async
lines name the robots the crash adversary crashed and when."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path as FsPath

import pytest

from fatswarm.agent.params import Params
from fatswarm.coordinator.async_rounds import AsyncCoordinatorCore
from fatswarm.coordinator.rounds import Ask, CoordinatorCore, Finished, RoundTimes
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import (
    HistoryMismatchError,
    ReplayedRecord,
    run_lockstep,
)
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.deploy.view.summary import crashes_in
from fatswarm.domain.adversary import make_async
from fatswarm.domain.outcome import Status
from fatswarm.world.protocol import Begin, Commit, ControlReply, Hello
from fatswarm.world.record import RecordWriter, RunRecord
from fatswarm.world.record_read import read_record


def _run(path: FsPath, name: str = "async", n: int = 5, seed: int = 2, **kw: object) -> RunRecord:
    with RecordWriter(path) as journal:
        run_lockstep(
            random_start(n, seed),
            Params(n),
            make_scheduler(name, n, seed),
            seed=seed,
            record=journal,
            **kw,  # type: ignore[arg-type]
        )
    return read_record(path)


def _resume(
    record: RunRecord, path: FsPath, name: str = "async", n: int = 5, seed: int = 2
) -> None:
    with RecordWriter(path, append=True) as journal:
        run_lockstep(
            random_start(n, seed),
            Params(n),
            make_scheduler(name, n, seed),
            seed=seed,
            record=journal,
            history=record.rounds,
        )


@pytest.mark.parametrize("name", ["async", "async-slowest"])
@pytest.mark.parametrize("cut", [0, 1, 17])
def test_a_cut_async_record_resumed_in_lock_step_is_the_whole_run_byte_for_byte(
    tmp_path: FsPath, name: str, cut: int
) -> None:
    whole = tmp_path / "whole.jsonl"
    record = _run(whole, name)
    part = tmp_path / "part.jsonl"
    lines = whole.read_text().splitlines(keepends=True)
    part.write_text("".join(lines[: 1 + cut]))
    _resume(read_record(part), part, name)
    assert part.read_bytes() == whole.read_bytes()
    assert record.result is not None


def test_a_record_this_run_does_not_make_is_refused_naming_the_cycle(tmp_path: FsPath) -> None:
    whole = tmp_path / "whole.jsonl"
    _run(whole)
    lines = whole.read_text().splitlines(keepends=True)
    third = json.loads(lines[3])
    third["positions"][0][0] += 1.0
    part = tmp_path / "part.jsonl"
    part.write_text("".join([*lines[:3], json.dumps(third, separators=(",", ":")) + "\n"]))
    before = part.read_bytes()
    with pytest.raises(HistoryMismatchError, match=r"^cycle 3 is not the one .* positions"):
        _resume(read_record(part), part)
    assert part.read_bytes() == before  # nothing appended


def test_a_replayed_record_writes_only_the_lines_after_its_own(tmp_path: FsPath) -> None:
    record = _run(tmp_path / "whole.jsonl")
    written: list[object] = []

    class Lines:
        def append(self, line: object) -> None:
            written.append(line)

        def close(self) -> None:
            pass

    replayed = ReplayedRecord(Lines(), record.rounds[:4])
    replayed.append(record.header)  # the record's header: not written again
    for entry in record.rounds[:5]:
        replayed.append(entry)
    assert replayed.done and written == [record.rounds[4]]


def test_a_restarted_async_coordinator_draws_the_delays_of_the_cycles_the_world_began() -> None:
    model = make_async("async", 3, 0)
    core = AsyncCoordinatorCore(lambda n: model, RoundTimes(), resume_live=range(3))
    for robot in range(3):
        core.on_alive(robot, True, 0.0)
    (hello,) = core.start(0.0)
    assert isinstance(hello, Ask) and isinstance(hello.request, Hello)
    # the world has run 7 instants; robot 1 Looks next, at 5.0, in its 4th cycle
    stands = ControlReply(
        ok=True, reason="", n=3, committed=7, open_round=0, status=Status.RUNNING,
        now=4.0, looks=((0, 6.0), (1, 5.0), (2, 7.5)),
    )  # fmt: skip
    (begin,) = core.on_reply(stands, 0.0)  # no NotRoundBasedError: nothing to replay
    assert isinstance(begin, Ask) and isinstance(begin.request, Begin)
    assert begin.request.round == 8
    assert begin.request.active == (1,)
    assert "resuming after instant 7" in [n.text for n in core.pop_notes()]
    opened = dataclasses.replace(stands, open_round=8, cycles=((1, 4),))
    assert core.on_reply(opened, 0.0) == []  # collecting robot 1's move
    (commit,) = core.on_tick(RoundTimes().move_timeout_s)
    assert isinstance(commit, Ask) and isinstance(commit.request, Commit)
    cycle = model.cycle(1, 4)
    assert commit.request.delays == ((1, cycle.compute, cycle.wait),)


def test_the_cycles_of_an_open_instant_cross_the_wire() -> None:
    reply = ControlReply(
        ok=True, reason="", n=3, committed=2, open_round=3, status=Status.RUNNING,
        now=1.5, looks=((0, 1.5),), cycles=((0, 12), (2, 1)),
    )  # fmt: skip
    assert ControlReply.decode(reply.encode()) == reply
    plain = dataclasses.replace(reply, now=0.0, looks=(), cycles=())
    assert b"cycles" not in plain.encode()  # a round run's replies stay as they were


def test_a_coordinator_whose_world_never_answers_gives_up_after_its_bound() -> None:
    core = CoordinatorCore(lambda n: make_scheduler("ssync", n, 1), RoundTimes(give_up_s=30.0))
    now, actions = 0.0, core.start(0.0)
    while not any(isinstance(a, Finished) for a in actions):
        assert now < 31.0, "retried past its bound"
        if actions:
            actions = core.on_reply(None, now)  # no answer: down, or gone for good
            continue
        deadline = core.next_deadline()
        assert deadline is not None
        now = deadline
        actions = core.on_tick(now)
    (finished,) = actions
    assert isinstance(finished, Finished)
    assert finished.gave_up.startswith("the world gave no usable answer for 30 s")
    assert now >= 30.0


def test_an_async_record_names_each_crash_and_its_time_and_summaries_read_them(
    tmp_path: FsPath,
) -> None:
    record = _run(tmp_path / "crash.jsonl", n=6, seed=2, crash=1, non_rigid=0.5)
    lines = [e for e in record.rounds if "crash" in e.extra]
    assert len(lines) == 1
    (entry,) = lines
    (robot,) = entry.extra["crash"]
    (when,) = entry.extra["crash_at"].values()
    assert entry.extra["crash_at"] == {str(robot): when} and when <= entry.extra["end"]
    assert crashes_in(record.rounds) == ((robot, entry.round),)
    assert all(robot not in e.active for e in record.rounds if e.round > entry.round)
    plain = _run(tmp_path / "plain.jsonl", n=6, seed=2)
    assert not any("crash" in e.extra or "crash_at" in e.extra for e in plain.rounds)


def test_cycles_the_record_says_timed_out_time_out_again_in_the_replay(tmp_path: FsPath) -> None:
    # a networked run's slow agent, played here by a move the world refuses (a coordinate past
    # the wire's bound) at the 9th Look: its cycle line says timed_out, which no compute redoes
    from fatswarm.agent import algorithm
    from fatswarm.domain.path import Line, Path, Points

    calls = [0]

    def once_refused(view: Points, params: object) -> Path:
        calls[0] += 1
        if calls[0] == 9:
            return Path((Line((1e12, 0.0)),))
        return algorithm.compute(view, params)  # type: ignore[arg-type]

    whole = tmp_path / "whole.jsonl"
    record = _run(whole, compute=once_refused)
    timed_out = [e.round for e in record.rounds if e.extra.get("timed_out")]
    assert len(timed_out) == 1
    lines = whole.read_text().splitlines(keepends=True)
    part = tmp_path / "part.jsonl"
    part.write_text("".join(lines[: timed_out[0] + 3]))  # the time-out among the lines replayed
    with RecordWriter(part, append=True) as journal:
        run_lockstep(
            random_start(5, 2),
            Params(5),
            make_scheduler("async", 5, 2),
            seed=2,
            record=journal,
            history=read_record(part).rounds,
            compute=algorithm.compute,  # every compute plain: only the record says time out
        )
    assert part.read_bytes() == whole.read_bytes()
