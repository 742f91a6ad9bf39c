"""The words a user reads for a run's counts, decided once: the unit a scheduler counts in ("round",
or "cycle" under an async model) and a count with its noun, plural unless the count is one."""

from __future__ import annotations

from fatswarm.domain.adversary import ASYNC_NAMES


def unit(scheduler: str) -> str:
    """What a run under `scheduler` counts, in the words every summary, progress line and
    dashboard uses: "round" under a round model; "cycle" under an async model, an ended
    Look-Compute-Move cycle (one record line each), whose run also says its virtual "time"."""
    return "cycle" if scheduler in ASYNC_NAMES else "round"


def units(scheduler: str) -> str:
    """`unit` in the plural: "rounds", "cycles" (`rounds/s`, `cycles/s`)."""
    return plural(unit(scheduler))


def plural(word: str, k: float = 2, many: str | None = None) -> str:
    """`word` as it goes with the count `k`: itself for exactly 1, else `many` (default
    `word` + "s": "round" -> "rounds"; give `many` for "process" -> "processes")."""
    if k == 1:
        return word
    return many if many is not None else word + "s"


def counted(k: float, word: str, many: str | None = None) -> str:
    """`k word`, plural unless k is 1 (`plural`): "1 round", "31 rounds", "1 round per second",
    "0.5 rounds"; a float by `:g`."""
    shown = f"{k:g}" if isinstance(k, float) else str(k)
    return f"{shown} {plural(word, k, many)}"


__all__ = ["counted", "plural", "unit", "units"]
