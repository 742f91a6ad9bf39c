"""The machinery of `fatswarm hunt`: candidate runs and shrinkings in worker processes, the pool
loop that keeps the hunt reproducible from its seed, and the files each failure is saved as.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import logging
import os
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
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
from fatswarm.deploy.hunt.shrink import DEFAULT_SHRINK_RUNS, Shrunk, shrink
from fatswarm.deploy.sweep.executor import Batcher, Workers, quiet_logs
from fatswarm.deploy.sweep.pool import WorkerDiedError, sigint_blocked
from fatswarm.world.record import RecordWriter

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


def search_batch(hunt: Hunt, candidates: Sequence[Candidate]) -> list[Searched]:
    """Run candidates one after the other (one task of the executor, in a worker)."""
    quiet_logs()
    return [search(hunt, candidate) for candidate in candidates]


def shrink_failure(hunt: Hunt, case: Case, kind: str, budget: int) -> Shrunk:
    """Shrink a failure (in a worker): only the shrunk case crosses back, so that the folder is
    written where the hunt runs, whatever machine shrank it."""
    quiet_logs()
    return shrink(hunt, case, kind, budget=budget)


def save_shrunk(
    hunt: Hunt,
    hunt_seed: int,
    candidate: Candidate,
    failure: Failure,
    case: Case,
    shrunk: Shrunk,
    folder: str,
) -> Saved:
    """Save a shrunk failure in `folder` (a new directory): start.json, schedule.json, the
    record of the shrunk run as `fatswarm run` makes it from those files (record.jsonl), the
    command that replays it, and summary.json."""
    os.makedirs(folder)
    _write_json(os.path.join(folder, "start.json"), start_data(hunt, shrunk.case))
    script = schedule_data(shrunk.case)
    if script is not None:
        _write_json(os.path.join(folder, "schedule.json"), script)
    logger = logging.getLogger("fatswarm")
    propagate, logger.propagate = logger.propagate, False  # a robot's warnings: not here
    try:
        replayed = replay_files(hunt, shrunk.case, folder)
    finally:
        logger.propagate = propagate
    summary = summary_data(hunt, hunt_seed, candidate, failure, shrunk, case, replayed)
    with open(os.path.join(folder, "command"), "w", encoding="utf-8") as fh:
        fh.write(
            f"# from this folder: replays the failure and writes replay.jsonl\n"
            f"{replay_command(hunt, shrunk.case)}\n"
        )
    _write_json(os.path.join(folder, "summary.json"), summary)
    return Saved(candidate, folder, summary)


def shrink_and_save(
    hunt: Hunt,
    hunt_seed: int,
    candidate: Candidate,
    failure: Failure,
    case: Case,
    folder: str,
    budget: int,
) -> Saved:
    """Shrink a failure and save it in `folder`, in one process (`shrink_failure`, then
    `save_shrunk`)."""
    shrunk = shrink_failure(hunt, case, failure.kind, budget)
    return save_shrunk(hunt, hunt_seed, candidate, failure, case, shrunk, folder)


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
            robot_model=setup.robot_model,
            settings=setup.settings,
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
    workers: Workers,
    out: str,
    on_change: Callable[[Tally], None],
    stop: Callable[[], bool],
) -> tuple[Tally, bool]:
    """Hunt on `workers`; (the tally, True when it ended, False when `stop()` turned true first:
    the workers' runs are then dropped, the failures saved so far stay).

    Candidate i is `draw_candidate(hunt, hunt_seed, i)`, whichever worker runs it, in batches of
    about a second (`Batcher`). A failure is shrunk once every candidate before it has run, and
    only the first `budget.failures` of them are, and its folder is written here, so a hunt with
    a run budget finds and saves the same failures on any number of cores or machines.
    Raises WorkerDiedError if a worker vanished.
    """
    tally = Tally()
    loop = _HuntLoop(hunt, hunt_seed, budget, workers, out, tally)
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
                except workers.died:
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
            workers.kill()


@dataclass(frozen=True, slots=True)
class _Shrinking:
    """A failure being shrunk, and where it goes once shrunk."""

    found: Searched
    folder: str


class _HuntLoop:
    """What `run_hunt`'s loop keeps: the searches and shrinkings in flight, the failures found
    and not yet settled (shrunk and saved, or passed over), and how far the hunt has run."""

    def __init__(
        self,
        hunt: Hunt,
        hunt_seed: int,
        budget: Budget,
        workers: Workers,
        out: str,
        tally: Tally,
    ) -> None:
        self.hunt, self.hunt_seed, self.budget = hunt, hunt_seed, budget
        self.workers, self.out, self.tally = workers, out, tally
        self.batcher = Batcher(workers.slots)
        self.searches: dict[cf.Future[list[Searched]], list[Candidate]] = {}
        self.shrinks: dict[cf.Future[Shrunk], _Shrinking] = {}
        self.failed: dict[int, Searched] = {}  # found, waiting to be settled
        self.settled: list[int] = []
        self.done: set[int] = set()
        self.frontier = 0  # every candidate below frontier has run
        self.drawn = 0

    def searching(self) -> bool:
        """Whether the search still draws candidates (its budget is not spent)."""
        if self.budget.runs is not None and self.drawn >= self.budget.runs:
            return False
        return not self.dropping()

    def dropping(self) -> bool:
        """Whether the candidates in flight are no longer needed: enough failures settled, or
        the time is up (a run budget's candidates all count, so that it is reproducible)."""
        budget = self.budget
        if len(self.settled) >= budget.failures:
            return True
        return budget.seconds is not None and time.monotonic() - self.tally.started >= (
            budget.seconds
        )

    def feed(self) -> None:
        """Keep the workers busy with batches of candidates while searching; once the search is
        over, drop the candidates no longer needed and, when none runs, settle every failure
        found."""
        if self.searching():
            with sigint_blocked():
                while len(self.searches) < self.batcher.in_flight() and self.searching():
                    self._submit_batch()
        elif self.dropping():
            for future in [f for f in self.searches if f.cancel()]:
                del self.searches[future]  # never started: the search is over
        if not self.searching() and not self.searches:
            self.settle(everything=True)
        self.tally.shrinking = len(self.shrinks)

    def _submit_batch(self) -> None:
        left = None if self.budget.runs is None else self.budget.runs - self.drawn
        size = self.batcher.size(left if left is not None else 1 << 30)
        if left is not None:
            size = min(size, left)
        batch = [draw_candidate(self.hunt, self.hunt_seed, self.drawn + i) for i in range(size)]
        self.drawn += size
        self.searches[self.workers.executor.submit(search_batch, self.hunt, batch)] = batch

    def over(self) -> bool:
        """Whether nothing runs and nothing more will."""
        return not self.searches and not self.shrinks and not self.searching()

    def ready(self) -> set[cf.Future[Any]]:
        """The tasks that ended within POLL_S."""
        waiting: list[cf.Future[Any]] = [*self.searches, *self.shrinks]
        ready, _ = cf.wait(waiting, timeout=POLL_S, return_when=cf.FIRST_COMPLETED)
        return ready

    def collect(self, future: cf.Future[Any]) -> None:
        """Count a batch's runs (keeping the failures to settle), or save a shrunk failure."""
        if future in self.searches:
            del self.searches[future]
            results: list[Searched] = future.result()
            for result in results:
                self.batcher.observe(result.wall_s)
                _count(self.tally, result)
                self.done.add(result.candidate.index)
                if result.outcome.failure is not None and result.case is not None:
                    self.failed[result.candidate.index] = result
        else:
            shrinking = self.shrinks.pop(future)
            found, shrunk = shrinking.found, future.result()
            assert found.outcome.failure is not None and found.case is not None
            self.tally.saved.append(
                save_shrunk(
                    self.hunt,
                    self.hunt_seed,
                    found.candidate,
                    found.outcome.failure,
                    found.case,
                    shrunk,
                    shrinking.folder,
                )
            )

    def advance(self) -> None:
        """Move the frontier past the candidates that have run and settle the failures below it."""
        while self.frontier in self.done:
            self.frontier += 1
        self.settle(everything=False)
        self.tally.shrinking = len(self.shrinks)

    def settle(self, everything: bool) -> None:
        """Shrink the failures found below the frontier (all of them with `everything`), in the
        hunt's order, up to `budget.failures`."""
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
            with sigint_blocked():
                future = self.workers.executor.submit(
                    shrink_failure, self.hunt, found.case, kind, self.budget.shrink_runs
                )
            self.shrinks[future] = _Shrinking(found, folder)


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
    "save_shrunk",
    "search",
    "search_batch",
    "shrink_and_save",
    "shrink_failure",
]
