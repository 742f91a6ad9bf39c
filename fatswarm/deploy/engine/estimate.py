"""How long a lock-step run takes and how big its record grows: a rough model, measured on a
2-core machine, for the estimate a large run prints before it starts and the ETA of its progress."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

from fatswarm.domain.adversary import ASYNC_NAMES

SECONDS_PER_ROUND: Final = 3e-4  # a round's fixed cost (scheduler, progress, record line)
SECONDS_PER_ROBOT_ROUND: Final = 8e-6  # canonical form, plan and physics grow about linearly
RECORD_BYTES_PER_ROUND: Final = 200
RECORD_BYTES_PER_ROBOT_ROUND: Final = 45  # one position per robot and round, plus its path
# Rounds a correct run takes, per sequential step of the algorithm (about n + 2 steps: one mover
# or one mirror pair each): 1 under fsync, about 2 under ssync, about n when one robot moves at
# a time (centralized; scripted is anyone's guess). deploy/engine/lockstep.py sets its caps 10x
# higher. Under the async models a "round" is an ended cycle: about 3n a step (2.3n to 3.9n
# measured at n = 5, 8, 12 in docs/results.md's sweep).
EXPECTED_ROUNDS_PER_STEP: Final = {"fsync": 1, "ssync": 2}
ASYNC_CYCLES_PER_STEP_PER_ROBOT: Final = 3


def expected_rounds_per_step(n: int, scheduler: str, reach: float = 0.0) -> int:
    """Rounds (ended cycles under an async model) a correct run takes per step of the algorithm;
    under an async model the others cycle about once per 2 time units while a move of about
    `reach` lasts (n = 8 with a target radius of 1e4 took 302,547 cycles)."""
    if scheduler in ASYNC_NAMES:
        per_robot = max(ASYNC_CYCLES_PER_STEP_PER_ROBOT, math.ceil(reach / 2.0))
        return per_robot * max(1, n)
    return EXPECTED_ROUNDS_PER_STEP.get(scheduler, max(1, n))


ESTIMATE_FROM_N: Final = 200  # a lockstep run this large says what it will cost before it starts
ESTIMATE_FROM_S: Final = 5.0  # ... as does one expected to take this long


@dataclass(frozen=True, slots=True)
class Estimate:
    """A rough forecast of a lockstep run (of what is left of it, after `done` rounds): as a
    correct run goes, and if it runs to the cap. `word`: what it counts ("round", or "cycle"
    under an async model)."""

    rounds: int
    seconds: float
    record_bytes: int
    cap_rounds: int
    cap_seconds: float
    cap_record_bytes: int
    done: int = 0
    word: str = "round"


def estimate_lockstep(
    n: int, scheduler: str, max_rounds: int, done: int = 0, reach: float = 0.0
) -> Estimate:
    """The forecast of an n-robot lockstep run under `scheduler`, capped at `max_rounds`; of the
    rounds left after `done` (a resumed run). `reach`: the run's (`lockstep.run_reach`), which
    the cycles of an async run grow with."""
    expected = min(max_rounds, expected_rounds_per_step(n, scheduler, reach) * (n + 2))
    rounds, cap = max(0, expected - done), max(0, max_rounds - done)
    round_s = SECONDS_PER_ROUND + SECONDS_PER_ROBOT_ROUND * n
    round_bytes = RECORD_BYTES_PER_ROUND + RECORD_BYTES_PER_ROBOT_ROUND * n
    return Estimate(
        rounds,
        rounds * round_s,
        rounds * round_bytes,
        cap,
        cap * round_s,
        cap * round_bytes,
        done,
        "cycle" if scheduler in ASYNC_NAMES else "round",
    )


def estimate_text(forecast: Estimate, n: int, *, record: bool) -> str:
    """The line a large lockstep run prints before it starts (to stderr); a resumed run's says
    what is left after its committed rounds."""
    f = forecast
    if f.done:
        size = "appended to the record" if record else "a --record would take"
        head = f"estimate for the rest of n={n} after {f.word} {f.done} (a rough model): "
        if f.rounds == 0:
            return (
                f"{head}longer than a correct run takes; at most {_count(f.cap_rounds, f.word)} "
                f"more (the cap): {_duration(f.cap_seconds)}, {size} ~{_size(f.cap_record_bytes)}"
            )
        head += f"~{_count(f.rounds, f.word)} more"
    else:
        size = "record" if record else "a --record would take"
        head = f"estimate for n={n} (a rough model, not a measurement): ~{_count(f.rounds, f.word)}"
    line = f"{head}, {_duration(f.seconds)}, {size} ~{_size(f.record_bytes)}"
    if f.cap_rounds == f.rounds:
        return line
    return (
        f"{line}; at the {f.word} cap of {f.done + f.cap_rounds}: {_duration(f.cap_seconds)}, "
        f"~{_size(f.cap_record_bytes)}"
    )


def _count(k: int, word: str) -> str:
    return f"{k} {word}{'' if k == 1 else 's'}"


def eta_text(done: int, rounds_per_s: float, expected: int, cap: int, word: str = "round") -> str:
    """How long is left after `done` rounds (`word`s: cycles under an async model) at
    `rounds_per_s`: to the expected end, at most to the cap."""
    if rounds_per_s <= 0:
        return "eta unknown"
    to_cap = _duration((cap - done) / rounds_per_s)
    if done < expected:
        return f"eta {_duration((expected - done) / rounds_per_s)}, at most {to_cap} ({word} cap)"
    return f"eta: longer than estimated, at most {to_cap} ({word} cap)"


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"~{max(1, round(seconds))} s"
    if seconds < 90 * 60:
        return f"~{seconds / 60:.1f} min"
    return f"~{seconds / 3600:.1f} h"


def _size(nbytes: float) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if nbytes >= scale:
            return f"{nbytes / scale:.1f} {unit}"
    return f"{nbytes:.0f} B"


__all__ = [
    "ESTIMATE_FROM_N",
    "ESTIMATE_FROM_S",
    "EXPECTED_ROUNDS_PER_STEP",
    "Estimate",
    "estimate_lockstep",
    "estimate_text",
    "eta_text",
]
