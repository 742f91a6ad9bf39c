"""What the networked `fatswarm run` says and checks before and after its processes (issue 21):
its capacity estimate and refusal, its last line after a signal, its progress lines' unit, the
plain lines of its parts' logs, and the state an async world shows its observers. No process."""

from __future__ import annotations

import logging
import resource
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fatswarm.deploy.cli import build_parser
from fatswarm.deploy.commands.run import resolve_run
from fatswarm.deploy.net import capacity
from fatswarm.deploy.net.capacity import Machine, estimate_networked
from fatswarm.deploy.net.launcher import check_inputs, stopped_line
from fatswarm.deploy.net.part_common import PlainLines
from fatswarm.deploy.view.dashboard import Frame, outcome_text, progress_line
from fatswarm.domain.outcome import Status

ROOMY = Machine(memory_mb=1e9, threads=10**9, files=(10**6, 10**6))


# --- capacity ---------------------------------------------------------------------------------


def test_the_estimate_grows_with_the_agents_from_the_measured_figures() -> None:
    fork, exec_ = estimate_networked(2000, "fork"), estimate_networked(2000, "exec")
    assert fork.processes == exec_.processes == 2003
    assert fork.memory_mb == pytest.approx(capacity.PARTS_MB + 2000 * 6.7)
    assert 2000 * 5 < fork.memory_mb < 2000 * 8  # an agent measured at 5.2 to 6.3 MB (fork)
    assert exec_.memory_mb > 3 * fork.memory_mb  # a fresh interpreter each: 22 MB measured
    assert fork.startup_s == pytest.approx(capacity.PARTS_START_S + 2000 * 0.011)
    assert exec_.startup_s > 5 * fork.startup_s


def test_a_run_the_machine_holds_is_not_refused_and_says_its_estimate_only_when_large() -> None:
    small, large = estimate_networked(8, "fork"), estimate_networked(200, "fork")
    assert capacity.problem(small, ROOMY) is None and capacity.problem(large, ROOMY) is None
    assert not capacity.worth_saying(small, ROOMY) and capacity.worth_saying(large, ROOMY)
    assert capacity.worth_saying(estimate_networked(50, "exec"), ROOMY)  # agents up in >= 5 s
    tight = replace(ROOMY, memory_mb=2 * small.memory_mb)
    assert capacity.worth_saying(small, tight)  # half of what is available
    text = capacity.estimate_text(large, replace(ROOMY, memory_mb=4096.0))
    assert text == (
        "estimate for n=200 networked (measured per agent, not a promise): 203 processes "
        "(fork), ~1.4 GB of memory of 4.0 GB available, agents up in ~3 s"
    )


def test_a_run_past_the_machines_memory_threads_or_files_is_refused_in_one_line() -> None:
    est = estimate_networked(2000, "fork")
    said = capacity.problem(est, replace(ROOMY, memory_mb=2048.0))
    assert said == (
        "-n 2000 starts 2,003 processes, about 13.2 GB of memory, and only 2.0 GB is available: "
        "use fewer robots or --lockstep (one process), or pass --force to start it anyway"
    )
    said = capacity.problem(est, replace(ROOMY, threads=5000))
    assert said is not None and "10,064 threads, and only 5,000 more may start" in said
    said = capacity.problem(est, replace(ROOMY, files=(1024, 2048)))
    assert said is not None and "about 4,256 open files, and `ulimit -Hn` allows 2,048" in said
    unknown = Machine(memory_mb=None, threads=None, files=(1024, resource.RLIM_INFINITY))
    assert capacity.problem(est, unknown) is None  # nothing known against it


def test_this_machine_is_read_without_failing() -> None:
    here = capacity.this_machine()
    assert here.memory_mb is None or here.memory_mb > 0
    assert here.threads is None or here.threads > 0


def test_the_soft_open_files_limit_is_raised_as_far_as_the_run_needs(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    limits = {"now": (1024, 4096)}
    monkeypatch.setattr(resource, "getrlimit", lambda _: limits["now"])
    monkeypatch.setattr(resource, "setrlimit", lambda _, value: limits.update(now=value))
    capacity.raise_open_files(estimate_networked(100, "fork"))  # 456 files: enough already
    assert limits["now"] == (1024, 4096)
    capacity.raise_open_files(estimate_networked(1000, "fork"))
    assert limits["now"] == (2256, 4096)
    capacity.raise_open_files(estimate_networked(5000, "fork"))  # as far as the hard limit
    assert limits["now"] == (4096, 4096)


def _run_args(*flags: str) -> Any:
    return build_parser().parse_args(["run", *flags])


def test_fatswarm_run_refuses_a_run_past_the_machine_before_anything_unless_forced(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(capacity, "this_machine", lambda: replace(ROOMY, memory_mb=100.0))
    problem, _, _ = check_inputs(_run_args("-n", "8", "--seed", "1"), resolve_run)
    assert problem is not None and problem.startswith("-n 8 starts 11 processes, about 134 MB")
    forced = _run_args("-n", "8", "--seed", "1", "--record", str(tmp_path / "r.jsonl"), "--force")
    problem, _, setup = check_inputs(forced, resolve_run)
    assert problem is None and setup is not None and setup.params.n == 8


# --- what a signalled run says last -----------------------------------------------------------


def test_a_signalled_run_says_after_which_round_and_how_to_go_on() -> None:
    def said(word: str, done: int, record: str | None, scheduler: str = "ssync") -> str:
        return stopped_line(word, done, record=record, scheduler=scheduler, seed=5)

    assert said("interrupted", 12, "run.jsonl") == (
        "interrupted after round 12; go on with `fatswarm run --record run.jsonl --resume`"
    )
    assert said("terminated", 0, "my runs/a b.jsonl") == (
        "terminated after round 0; go on with `fatswarm run --record 'my runs/a b.jsonl' --resume`"
    )
    assert said("interrupted", 7, None) == (
        "interrupted after round 7 (no --record: nothing to resume)"
    )
    assert said("interrupted", 40, "a.jsonl", "async") == (
        "interrupted after cycle 40; go on with `fatswarm run --record a.jsonl --resume`"
    )


@pytest.mark.parametrize("record", ["run.jsonl", "a b.jsonl", None])
@pytest.mark.parametrize("scheduler", ["ssync", "async-slowest"])
@pytest.mark.parametrize("word", ["interrupted", "terminated"])
def test_the_networked_line_is_the_lock_steps_less_its_lockstep_flag(
    record: str | None, scheduler: str, word: str
) -> None:
    from fatswarm.deploy.commands.resume import stopped_line as lockstep_line

    mine = stopped_line(word, 9, record=record, scheduler=scheduler, seed=3)
    theirs = lockstep_line(word, 9, record=record, scheduler=scheduler, lockstep=True, seed=3)
    assert mine == theirs.replace("fatswarm run --lockstep ", "fatswarm run ")


# --- progress lines in the run's unit ---------------------------------------------------------


def _frame(scheduler: str, status: Status, round_no: int = 164) -> Frame:
    positions = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 3.0]])
    return Frame(
        round=round_no,
        n=3,
        scheduler=scheduler,
        positions=positions,
        status=status,
        rounds_per_second=12.0,
    )


@pytest.mark.parametrize("status", [Status.RUNNING, Status.FORMED, Status.STALLED])
def test_an_async_runs_progress_lines_count_ended_cycles(status: Status) -> None:
    frame = _frame("async", status)
    line = progress_line(frame)
    assert line.startswith(f"cycle 164 {status}: ") and line.endswith(", 12.0 cycles/s")
    assert "round" not in line
    outcome = outcome_text(frame)
    assert "round" not in outcome and ("164 cycles" in outcome or status == Status.RUNNING)
    limit = _frame("async-slowest", Status.MAX_ROUNDS, 1)
    assert outcome_text(limit).startswith("NOT FORMED: stopped at the cycle limit (1 cycle)")


def test_a_round_runs_progress_lines_count_rounds() -> None:
    for status in (Status.RUNNING, Status.FORMED, Status.MAX_ROUNDS):
        frame = _frame("ssync", status)
        assert progress_line(frame).startswith(f"round 164 {status}: ")
        assert progress_line(frame).endswith(", 12.0 rounds/s") and "cycle" not in outcome_text(
            frame
        )


# --- the parts' log lines under `fatswarm run` ------------------------------------------------


def test_a_parts_log_message_under_fatswarm_run_is_one_plain_line() -> None:
    record = logging.LogRecord(
        "fatswarm.world", logging.WARNING, __file__, 1, "state file %s: dropping", ("x",), None
    )
    assert PlainLines().format(record) == "fatswarm world: state file x: dropping"


# --- the state an async world shows -----------------------------------------------------------


def test_an_async_worlds_state_counts_ended_cycles_and_a_round_worlds_its_rounds() -> None:
    from fatswarm.world.core import WorldCore
    from fatswarm.world.journal import load_configured
    from fatswarm.world.protocol import Begin, Commit
    from fatswarm.world.service import observed_state
    from fatswarm.world.setup import WorldSetup

    start = np.array([[3.0 * i, 0.0] for i in range(3)])
    setup = WorldSetup("t", 3, 0, "async-slowest", start, 100)
    world = WorldCore(setup, load_configured(setup))
    first = ((0, 0.0), (1, 0.0), (2, 0.0))  # every robot Looks at 0: one instant, three cycles
    reply, _ = world.control(Begin(1, (0, 1, 2), at=0.0, looks=first))
    assert reply.ok and reply.open_round == 1
    delays = tuple((r, 0.0, 1.0) for r in range(3))
    reply, _ = world.control(Commit(1, (0, 1, 2), delays=delays))
    assert reply.ok and world.committed == 1  # one instant...
    cycles = world.tracker.snapshot().rounds
    assert cycles == 3  # ...in which three cycles ended
    assert observed_state(world).round == cycles and world.state().round == 1
    fsync = WorldSetup("t", 3, 0, "fsync", start, 100)
    rounds = WorldCore(fsync, load_configured(fsync))
    assert observed_state(rounds).round == rounds.state().round  # rounds are rounds
