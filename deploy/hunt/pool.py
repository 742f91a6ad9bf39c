"""The machinery of `fatswarm hunt`: candidate runs and shrinkings in worker processes, the pool
loop that keeps the hunt reproducible from its seed, and the files each failure is saved as.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import multiprocessing
import os
import time
from collections import Counter
from collections.abc import Callable, Iterator
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import Any, Final

from fatswarm.deploy.engine.config import RunConfig
from fatswarm.deploy.hunt.files import (
    folder_name,
    replay_argv,
    replay_command,
    schedule_data,
    start_data,
    summary_data,
)
from fatswarm.deploy.hunt.search import (
    Candidate,
    Case,
    Failure,
    Hunt,
    HuntInputError,
    Outcome,
    draw_candidate,
    run_candidate,
    run_case,
)
from fatswarm.deploy.hunt.shrink import DEFAULT_SHRINK_RUNS, shrink
from fatswarm.deploy.sweep.pool import (
    WorkerDiedError,
    _kill_workers,
    _sigint_blocked,
    init_worker,
)
from fatswarm.world.record import RecordWriter

IN_FLIGHT_PER_JOB: Final = 2  # candidate runs queued per worker: busy, yet quick to stop
POLL_S: Final = 0.2  # how often the pool loop looks at the stop flag and the clock


# -- in a worker --------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Searched:
    """A candidate's run, as a worker answers: its outcome and, if it failed, the Case."""

    candidate: Candidate
    outcome: Outcome
    case: Case | None
    wall_s: float


@dataclass(frozen=True, slots=True)
class Saved:
    """A failure shrunk and saved: its folder and its summary.json."""

    candidate: Candidate
    folder: str
    summary: dict[str, Any]


def search(hunt: Hunt, candidate: Candidate) -> Searched:
    """Run one candidate (in a worker)."""
    t0 = time.perf_counter()
    outcome, case = run_candidate(hunt, candidate)
    return Searched(candidate, outcome, case, time.perf_counter() - t0)


def shrink_and_save(
    hunt: Hunt,
    hunt_seed: int,
    candidate: Candidate,
    failure: Failure,
    case: Case,
    folder: str,
    budget: int,
) -> Saved:
    """Shrink a failure and save it in `folder` (a new directory): start.json, schedule.json, the
    record of the shrunk run as `fatswarm run` makes it from those files (record.jsonl), the
    command that replays it, and summary.json."""
    shrunk = shrink(hunt, case, failure.kind, budget=budget)
    os.makedirs(folder)
    _write_json(os.path.join(folder, "start.json"), start_data(hunt, shrunk.case))
    script = schedule_data(shrunk.case)
    if script is not None:
        _write_json(os.path.join(folder, "schedule.json"), script)
    replayed = replay_files(hunt, shrunk.case, folder)
    summary = summary_data(hunt, hunt_seed, candidate, failure, shrunk, case, replayed)
    with open(os.path.join(folder, "command"), "w", encoding="utf-8") as fh:
        fh.write(
            f"# from this folder: replays the failure and writes replay.jsonl\n"
            f"{replay_command(hunt, shrunk.case)}\n"
        )
    _write_json(os.path.join(folder, "summary.json"), summary)
    return Saved(candidate, folder, summary)


def replay_files(hunt: Hunt, case: Case, folder: str) -> Failure | None:
    """Run the saved files of `case` in `folder` as `fatswarm run` reads them (the same
    `RunConfig.resolve`: `load_init`, `load_script`), writing record.jsonl; the failure it
    shows (None: it did not fail, which would be a bug of the hunt)."""
    argv = replay_argv(hunt, case, folder)
    config = RunConfig(
        algorithm=hunt.algorithm,
        params=dict(hunt.params),
        seed=case.seed,
        init=argv[argv.index("--init") + 1],
        scheduler=argv[argv.index("--scheduler") + 1],
        schedule=(argv[argv.index("--schedule") + 1] if "--schedule" in argv else None),
        max_rounds=case.max_rounds,
        non_rigid=hunt.non_rigid,
        crash=hunt.crash,
        model=case.robot_model,
        record_views=hunt.record_views,
        command=tuple(argv),
    )
    setup = config.resolve()
    writer = RecordWriter(os.path.join(folder, "record.jsonl"))
    try:
        outcome = run_case(
            hunt,
            setup.initial,
            setup.scheduler,
            setup.scheduler.name,
            seed=setup.seed,
            max_rounds=setup.max_rounds,
            stop_early=False,
            record=writer,
            header_extra=config.header_extra(networked=False, n=setup.params.n),
            robot_model=setup.robot_model,
        )
    finally:
        writer.close()
    return outcome.failure


def _write_json(path: str, data: dict[str, Any]) -> None:
    """`data` as JSON in a new file, a list of lists (positions, rounds) one inner list a line."""

    def text(value: Any) -> str:
        if isinstance(value, list) and value and all(isinstance(v, list) for v in value):
            return "[\n  " + ",\n  ".join(json.dumps(v) for v in value) + "\n ]"
        return json.dumps(value, indent=1).replace("\n", "\n ")

    body = ",\n".join(f" {json.dumps(key)}: {text(value)}" for key, value in data.items())
    with open(path, "x", encoding="utf-8") as fh:
        fh.write("{\n" + body + "\n}\n")


# -- the pool -----------------------------------------------------------------------------------


@dataclass(slots=True)
class Tally:
    """What the hunt has seen so far, for the progress line and the summary."""

    runs: int = 0
    refused: int = 0
    kinds: Counter[str] = field(default_factory=Counter)  # failures found, by kind
    saved: list[Saved] = field(default_factory=list)  # in the hunt's order once it ends
    shrinking: int = 0  # failures being shrunk now
    started: float = field(default_factory=time.monotonic)

    @property
    def found(self) -> int:
        return sum(self.kinds.values())


@dataclass(frozen=True, slots=True)
class Budget:
    """When the search stops drawing candidates: after `runs` candidates, after `seconds`, or
    once `failures` failures are settled (the first ones in the hunt's order)."""

    runs: int | None
    seconds: float | None
    failures: int
    shrink_runs: int = DEFAULT_SHRINK_RUNS


def run_hunt(
    hunt: Hunt,
    hunt_seed: int,
    budget: Budget,
    jobs: int,
    out: str,
    on_change: Callable[[Tally], None],
    stop: Callable[[], bool],
) -> tuple[Tally, bool]:
    """Hunt on `jobs` worker processes; (the tally, True when it ended, False when `stop()`
    turned true first: the workers are then killed, the failures saved so far stay).

    Candidate i is `draw_candidate(hunt, hunt_seed, i)`, whichever worker runs it. A failure is
    shrunk once every candidate before it has run, and only the first `budget.failures` of them
    are, so a hunt with a run budget finds and saves the same failures on any number of cores.
    Raises WorkerDiedError if a worker vanished.
    """
    tally = Tally()
    pool = cf.ProcessPoolExecutor(
        max_workers=jobs, mp_context=multiprocessing.get_context("spawn"), initializer=init_worker
    )
    loop = _HuntLoop(hunt, hunt_seed, budget, jobs, out, pool, tally)
    finished = False
    try:
        while True:
            if stop():
                return tally, False
            loop.feed()
            if loop.over():
                finished = True
                break
            for future in loop.ready():
                try:
                    loop.collect(future)
                except BrokenProcessPool:
                    if stop():
                        return tally, False
                    raise WorkerDiedError(
                        "a worker process died (killed, or out of memory?) "
                        "while hunting; rerun with the same --seed"
                    ) from None
            loop.advance()
            on_change(tally)
        tally.saved.sort(key=lambda saved: saved.candidate.index)
        return tally, True
    finally:
        if not finished:
            _kill_workers(pool)
        pool.shutdown(wait=True, cancel_futures=True)


class _HuntLoop:
    """What `run_hunt`'s pool loop keeps: the searches and shrinkings in flight, the failures
    found and not yet settled (shrunk and saved, or passed over), and how far the hunt has run."""

    def __init__(
        self,
        hunt: Hunt,
        hunt_seed: int,
        budget: Budget,
        jobs: int,
        out: str,
        pool: cf.ProcessPoolExecutor,
        tally: Tally,
    ) -> None:
        self.hunt, self.hunt_seed, self.budget = hunt, hunt_seed, budget
        self.jobs, self.out, self.pool, self.tally = jobs, out, pool, tally
        self.searches: dict[cf.Future[Searched], Candidate] = {}
        self.shrinks: dict[cf.Future[Saved], Candidate] = {}
        self.failed: dict[int, Searched] = {}  # found, waiting to be settled
        self.settled: list[int] = []
        self.done: set[int] = set()
        self.frontier = 0  # every candidate below frontier has run
        self.drawn = 0

    def searching(self) -> bool:
        """Whether the search still draws candidates (its budget is not spent)."""
        budget = self.budget
        if len(self.settled) >= budget.failures:
            return False
        if budget.runs is not None and self.drawn >= budget.runs:
            return False
        return budget.seconds is None or time.monotonic() - self.tally.started < budget.seconds

    def feed(self) -> None:
        """Keep the workers busy with candidates while searching; once the search is over, drop
        the candidates not started and, when none runs, settle every failure found."""
        if self.searching():
            with _sigint_blocked():
                while len(self.searches) < self.jobs * IN_FLIGHT_PER_JOB and self.searching():
                    candidate = draw_candidate(self.hunt, self.hunt_seed, self.drawn)
                    self.searches[self.pool.submit(search, self.hunt, candidate)] = candidate
                    self.drawn += 1
        else:
            for future in [f for f in self.searches if f.cancel()]:
                del self.searches[future]  # never started: the search is over
            if not self.searches:
                self.settle(everything=True)
        self.tally.shrinking = len(self.shrinks)

    def over(self) -> bool:
        """Whether nothing runs and nothing more will."""
        return not self.searches and not self.shrinks and not self.searching()

    def ready(self) -> set[cf.Future[Any]]:
        """The runs that ended within POLL_S."""
        waiting: list[cf.Future[Any]] = [*self.searches, *self.shrinks]
        ready, _ = cf.wait(waiting, timeout=POLL_S, return_when=cf.FIRST_COMPLETED)
        return ready

    def collect(self, future: cf.Future[Any]) -> None:
        """Count a candidate's run (keeping a failure to settle) or keep a saved failure."""
        if future in self.searches:
            candidate = self.searches.pop(future)
            result: Searched = future.result()
            _count(self.tally, result)
            self.done.add(candidate.index)
            if result.outcome.failure is not None and result.case is not None:
                self.failed[candidate.index] = result
        else:
            self.shrinks.pop(future)
            self.tally.saved.append(future.result())

    def advance(self) -> None:
        """Move the frontier past the candidates that have run and settle the failures below it."""
        while self.frontier in self.done:
            self.frontier += 1
        self.settle(everything=False)
        self.tally.shrinking = len(self.shrinks)

    def settle(self, everything: bool) -> None:
        """Shrink and save the failures found below the frontier (all of them with `everything`),
        in the hunt's order, up to `budget.failures`."""
        for index in sorted(self.failed):
            if len(self.settled) >= self.budget.failures or (
                index >= self.frontier and not everything
            ):
                return
            found = self.failed.pop(index)
            assert found.outcome.failure is not None and found.case is not None
            self.settled.append(index)
            kind = found.outcome.failure.kind
            folder = os.path.join(self.out, folder_name(found.candidate, kind))
            with _sigint_blocked():
                future = self.pool.submit(
                    shrink_and_save,
                    self.hunt,
                    self.hunt_seed,
                    found.candidate,
                    found.outcome.failure,
                    found.case,
                    folder,
                    self.budget.shrink_runs,
                )
            self.shrinks[future] = found.candidate


def _count(tally: Tally, result: Searched) -> None:
    tally.runs += 1
    if result.outcome.refused:
        tally.refused += 1
    if result.outcome.failure is not None:
        tally.kinds[result.outcome.failure.kind] += 1


def check_out(out: str) -> None:
    """Refuse an --out that is a file, a non-empty directory, or in a missing directory."""
    if os.path.exists(out) and not os.path.isdir(out):
        raise HuntInputError(f"--out {out} is not a directory; name a new directory")
    if os.path.isdir(out) and any(_entries(out)):
        raise HuntInputError(
            f"--out {out} is not empty (a previous hunt?); name a new directory or empty it"
        )
    parent = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(parent):
        raise HuntInputError(f"--out {out}: the directory {parent} does not exist; create it first")


def _entries(folder: str) -> Iterator[str]:
    with os.scandir(folder) as entries:
        for entry in entries:
            yield entry.name


__all__ = [
    "Budget",
    "Saved",
    "Searched",
    "Tally",
    "check_out",
    "replay_files",
    "run_hunt",
    "search",
    "shrink_and_save",
]
