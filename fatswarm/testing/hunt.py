"""The hunt: seeded lock-step runs drawn as `fatswarm hunt` draws them, for a budget of seconds; a
failure (a collision, a stall...) shrunk by `fatswarm hunt`'s shrinker and raised with the run
that replays it."""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from typing import Final

from fatswarm.deploy.hunt.search import (
    Candidate,
    Case,
    Failure,
    Hunt,
    draw_candidate,
    run_candidate,
    start_families,
)
from fatswarm.deploy.hunt.shrink import shrink
from fatswarm.deploy.sweep.grid import params_text
from fatswarm.domain.robot_model import Bodies, RobotModel
from fatswarm.domain.seam import assumptions_of
from fatswarm.testing.look import Look
from fatswarm.testing.report import AlgorithmContractError
from fatswarm.testing.subject import Subject

SHRINK_RUNS: Final = 120  # lock-step runs the shrinking of a hunt's failure may take
SHRINK_CHUNK: Final = 10  # runs between two looks at the clock while shrinking
MIN_SHRINK_S: Final = 1.0  # shrinking may take as long as the hunt took, and this at least
SHOWN_ROUNDS: Final = 12  # rounds of a shrunk schedule the message shows
_FAILURE_WORDS: Final = {
    "collision": "a collision",
    "stalled": "a stall",
    "max_rounds": "no end within the round cap",
    "invariant": "a broken invariant",
    "error": "an error in the algorithm",
}


def run_hunt(
    subject: Subject, seed: int, budget_s: float, sizes: Sequence[int], schedulers: Sequence[str]
) -> tuple[int, int]:
    """Lock-step runs drawn as `fatswarm hunt` draws them (every start family, `sizes`,
    `schedulers`; the paper's model under each of the frames and bodies the algorithm declares),
    from `seed`, until `budget_s` has passed (one run at least): (runs, starts refused).
    Raises AlgorithmContractError at the first failure, shrunk."""
    runs = refused = 0
    refusal = ""
    with subject.reference() as ref:
        texts = [f"{k}={_text(v)}" for k, v in subject.given.items()]
        hunt = Hunt(
            algorithm=ref,
            params=params_text(subject.algorithm, texts),
            families=start_families(),
            sizes=tuple(sizes),
            models=tuple(schedulers),
            robot_models=tuple(
                RobotModel(frames=frames, bodies=bodies)
                for frames in subject.frames
                for bodies in assumptions_of(subject.algorithm).bodies or (Bodies.FAT,)
            ),
        )
        started = time.monotonic()
        deadline = started + budget_s
        for index in itertools.count():
            if index and time.monotonic() >= deadline:
                break
            candidate = draw_candidate(hunt, seed, index)
            outcome, case = run_candidate(hunt, candidate)
            if outcome.refused:
                refused += 1
                refusal = refusal or f"n = {candidate.n}, {candidate.family}: {outcome.refused}"
                continue
            runs += 1
            if outcome.failure is not None and case is not None:
                _hunt_failed(subject, hunt, candidate, outcome.failure, case, started)
    if not runs:
        raise ValueError(
            f"algorithm {subject.name} refused every one of the {refused} starts the hunt drew "
            f"({refusal}); pass sizes= with the n it supports"
        )
    return runs, refused


def _text(value: object) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def _hunt_failed(
    subject: Subject,
    hunt: Hunt,
    candidate: Candidate,
    failure: Failure,
    case: Case,
    hunt_started: float,
) -> None:
    """Shrink the failure of a hunt's run (`fatswarm hunt`'s shrinker, for about as long as the
    hunt took) and raise it."""
    deadline = time.monotonic() + max(MIN_SHRINK_S, time.monotonic() - hunt_started)
    small, found, runs = _shrunk(hunt, case, failure, deadline)
    positions = small.points()
    script = ""
    if small.rounds is not None:
        shown = [list(r) for r in small.rounds[:SHOWN_ROUNDS]]
        more = f" ... ({len(small.rounds)} rounds)" if len(small.rounds) > SHOWN_ROUNDS else ""
        script = f"; active robots by round {shown}{more}, then {small.after}"
    model = "scripted" if small.rounds is not None else small.model
    detail = (
        f"  {_FAILURE_WORDS.get(found.kind, found.kind)}: {found.detail}\n"
        f"  smallest start that breaks it (n = {small.n}, {model}, run seed {small.seed}"
        f"{script}): {Look(positions).describe()}\n"
        f"  found by hunt run {candidate.index} (start family {candidate.family}, n = "
        f"{candidate.n}, {candidate.model}, run seed {candidate.seed}), shrunk in "
        f"{runs} runs"
    )
    raise AlgorithmContractError(
        subject.name, "hunt", detail, positions=positions, kind=found.kind, case=small
    )


def _shrunk(hunt: Hunt, case: Case, failure: Failure, deadline: float) -> tuple[Case, Failure, int]:
    """`fatswarm hunt`'s shrinking of a failure, SHRINK_CHUNK runs at a time until it finds
    nothing smaller, SHRINK_RUNS are spent or `deadline` (time.monotonic) passes: the smallest
    case, its failure and the runs taken."""
    runs = 0
    while runs < SHRINK_RUNS:
        shrunk = shrink(hunt, case, failure.kind, budget=SHRINK_CHUNK)
        runs += shrunk.runs
        if not shrunk.reproduced:
            break
        case, failure = shrunk.case, shrunk.failure
        if not shrunk.steps or time.monotonic() >= deadline:
            break
    return case, failure, runs
