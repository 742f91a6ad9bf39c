"""Replaying a hunt's failure exactly (a Case under its script) and shrinking it: greedy delta
debugging (fewer robots, a shorter script, a smaller seed, simpler coordinates) while the smaller
case still fails the same way. Deterministic, no printing: `deploy/hunt/pool.py` runs it."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Final

import numpy as np

from fatswarm.coordinator.schedule import Scripted, make_scheduler
from fatswarm.deploy.hunt.search import (
    COLLISION,
    COMPUTE,
    ERROR,
    INVARIANT,
    Case,
    Failure,
    Hunt,
    Outcome,
    run_case,
)
from fatswarm.deploy.scenarios.starts import overlapping_pair
from fatswarm.domain.path import Points

DEFAULT_SHRINK_RUNS: Final = 200  # runs one failure's shrinking may take
SEED_TRIES: Final = (0, 1, 2, 3)  # simpler run seeds the shrinker tries
DECIMAL_TRIES: Final = (0, 1, 2, 3, 4, 6)  # decimals the shrinker rounds coordinates to
MAX_DECIMALS: Final = 17  # repr of a double never needs more
# Shrinking a failure that shows in round k runs each proposal to FACTOR k + SLACK rounds only.
HORIZON_FACTOR: Final = 2
HORIZON_SLACK: Final = 10
ROUND_DROP_LIMIT: Final = 48  # scripts this long or shorter also have single rounds dropped


def replay(
    hunt: Hunt,
    case: Case,
    *,
    stop_early: bool = True,
    record: Any = None,
    max_rounds: int | None = None,
) -> Outcome:
    """Run a Case under its scripted schedule (or its own model, when it has no script) and its
    robot model, up to its cap or the lower `max_rounds`."""
    if case.rounds is None:
        scheduler: Any = make_scheduler(case.model, case.n, case.seed)
        model = case.model
    else:
        scheduler, model = Scripted(case.rounds, case.after), "scripted"
    cap = case.max_rounds if max_rounds is None else min(max_rounds, case.max_rounds)
    return run_case(
        hunt,
        case.points(),
        scheduler,
        model,
        seed=case.seed,
        max_rounds=cap,
        stop_early=stop_early,
        record=record,
        robot_model=case.robot_model,
    )


# -- shrinking ---------------------------------------------------------------------------------


@dataclass(slots=True)
class Shrunk:
    """A shrinking's result: the smallest case found that fails with the same kind, its failure,
    the runs it took, and whether the unshrunk case replayed at all under its script."""

    case: Case
    failure: Failure
    runs: int
    reproduced: bool
    steps: list[str] = field(default_factory=list)  # the shrink steps taken, in order


def decimals(value: float) -> int:
    """The fewest decimals that write `value` exactly (17 for most grid values)."""
    for places in range(MAX_DECIMALS):
        if round(value, places) == value:
            return places
    return MAX_DECIMALS


def case_decimals(case: Case) -> int:
    """The most decimals any coordinate of the case needs."""
    return max((decimals(v) for p in case.positions for v in p), default=0)


def _cap_for(hunt: Hunt, case: Case, n: int) -> int:
    """A shrunk case's cap: the hunt's `--max-rounds`, or the default of its model for its n
    (so a case past its cap is past the cap that model would give its n robots)."""
    return hunt.cap(n, case.model)


def drop_robots(hunt: Hunt, case: Case, robots: Sequence[int]) -> Case | None:
    """The case without `robots`: the others renumbered in order, the script's sets likewise
    (rounds left empty are dropped); None if too few robots would remain."""
    gone = set(robots)
    keep = [i for i in range(case.n) if i not in gone]
    if len(keep) < max(2, (hunt.crash or 0) + 1):
        return None
    number = {old: new for new, old in enumerate(keep)}
    rounds = (
        None
        if case.rounds is None
        else tuple(
            sets
            for sets in (tuple(number[r] for r in rnd if r in number) for rnd in case.rounds)
            if sets
        )
        or (tuple(range(len(keep))),)
    )
    return replace(
        case,
        positions=tuple(case.positions[i] for i in keep),
        rounds=rounds,
        max_rounds=_cap_for(hunt, case, len(keep)),
    )


def _fewer_robots(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    """Drop halves, quarters... then single robots (delta debugging's complements)."""
    size = case.n // 2
    while size >= 1:
        for lo in range(0, case.n, size):
            smaller = drop_robots(hunt, case, range(lo, min(lo + size, case.n)))
            if smaller is not None:
                yield f"dropped robots {lo}..{min(lo + size, case.n) - 1}", smaller
        size //= 2


def _shorter_schedule(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    """fsync from the start; then the script cut to its first 1, 2, 4... rounds (then fsync);
    then, for a short script, single rounds dropped or made fsync rounds."""
    del hunt
    if case.rounds is None:
        return
    everyone = tuple(range(case.n))
    if case.rounds != (everyone,) or case.after != "fsync":
        yield "fsync from round 1", replace(case, rounds=(everyone,), after="fsync")
    length = len(case.rounds)
    keep = 1
    while keep < length:
        yield (
            f"first {keep} rounds, then fsync",
            replace(case, rounds=case.rounds[:keep], after="fsync"),
        )
        keep *= 2
    if 1 < length <= ROUND_DROP_LIMIT:
        for k in range(length):
            yield (
                f"dropped round {k + 1}",
                replace(case, rounds=case.rounds[:k] + case.rounds[k + 1 :]),
            )
        for k in range(length):
            if case.rounds[k] != everyone:
                yield (
                    f"round {k + 1} all active",
                    replace(case, rounds=(*case.rounds[:k], everyone, *case.rounds[k + 1 :])),
                )


def _simpler_seed(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    del hunt
    for seed in SEED_TRIES:
        if seed < case.seed:
            yield f"seed {seed}", replace(case, seed=seed)


def _simpler_coordinates(hunt: Hunt, case: Case) -> Iterator[tuple[str, Case]]:
    """The swarm moved by a whole vector towards the origin; every coordinate rounded to fewer
    decimals; then each coordinate alone."""
    del hunt
    pts = case.points()
    shift = np.round(pts.mean(axis=0)) + 0.0  # + 0.0: no -0.0
    if shift.any():
        moved = pts - shift
        yield f"moved by {(0.0 - shift).tolist()}", replace(case, positions=_pairs(moved))
    most = case_decimals(case)
    for places in DECIMAL_TRIES:
        if places < most:
            yield (
                f"coordinates to {places} decimals",
                replace(case, positions=_pairs(np.round(pts, places))),
            )
    for i in range(case.n):
        for axis in (0, 1):
            value = float(pts[i, axis])
            for places in DECIMAL_TRIES:
                if places < decimals(value):
                    changed = pts.copy()
                    changed[i, axis] = round(value, places)
                    yield (
                        f"robot {i} {'xy'[axis]} to {places} decimals",
                        replace(case, positions=_pairs(changed)),
                    )
                    break


def _pairs(points: Points) -> tuple[tuple[float, float], ...]:
    return tuple((float(x) + 0.0, float(y) + 0.0) for x, y in points)  # + 0.0: no -0.0


SHRINK_STEPS: Final = (_fewer_robots, _shorter_schedule, _simpler_seed, _simpler_coordinates)


def _valid(case: Case) -> bool:
    pts = case.points()
    return bool(np.isfinite(pts).all()) and overlapping_pair(pts) is None


def shrink(hunt: Hunt, case: Case, kind: str, *, budget: int = DEFAULT_SHRINK_RUNS) -> Shrunk:
    """The smallest case found that fails with the same `kind`: greedily, fewer robots, a shorter
    script (then fsync), a smaller seed, simpler coordinates, again until a whole pass finds
    nothing or `budget` runs are spent. Deterministic: no draw, the same steps in the same order.

    The case is first replayed under its script: if that does not fail with `kind` (a model a
    script cannot replay), it is returned as it is with `reproduced` False.
    """
    first = replay(hunt, case)
    runs = 1
    if first.failure is None or first.failure.kind != kind:
        failure = first.failure or Failure(kind, 0, "not reproduced by a scripted replay")
        return Shrunk(case, failure, runs, reproduced=False)
    best, failure = _cut_after(case, first), first.failure
    taken: list[str] = []
    improved = True
    while improved and runs < budget:
        improved = False
        for step in SHRINK_STEPS:
            progress = True
            while progress and runs < budget:
                progress = False
                for what, proposal in step(hunt, best):
                    if runs >= budget:
                        break
                    if not _valid(proposal):
                        continue
                    runs += 1
                    outcome = replay(hunt, proposal, max_rounds=_horizon(failure))
                    if outcome.failure is not None and outcome.failure.kind == kind:
                        best, failure = _cut_after(proposal, outcome), outcome.failure
                        taken.append(what)
                        progress = improved = True
                        break
    return Shrunk(best, failure, runs, reproduced=True, steps=taken)


def _horizon(failure: Failure) -> int | None:
    """How far a proposal is run while shrinking a failure that shows in a round (a collision,
    an invariant, a failed compute, an error): a little past where the best case so far fails. A
    proposal failing later is passed over (a smaller shrink, never a wrong one: a run's rounds
    before its cap do not depend on the cap); it saves running every proposal that does not fail
    to its cap."""
    if failure.kind in (COLLISION, INVARIANT, COMPUTE, ERROR):
        return HORIZON_FACTOR * failure.round + HORIZON_SLACK
    return None


def _cut_after(case: Case, outcome: Outcome) -> Case:
    """A case failing by a collision, an invariant or a compute needs no script past its failing
    round."""
    assert outcome.failure is not None
    if (
        case.rounds is not None
        and outcome.failure.kind in (COLLISION, INVARIANT, COMPUTE)
        and (0 < outcome.failure.round < len(case.rounds))
    ):
        return replace(case, rounds=case.rounds[: outcome.failure.round])
    return case


__all__ = [
    "DEFAULT_SHRINK_RUNS",
    "Shrunk",
    "case_decimals",
    "decimals",
    "drop_robots",
    "replay",
    "shrink",
]
