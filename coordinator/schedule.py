"""Schedulers: which robots are active in each round. Seeded and reproducible.

API CONTRACT (stub; the scheduler helper replaces the bodies, keeps the signatures).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol


class Scheduler(Protocol):
    """Picks the active set of a round among the live robots."""

    name: str

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        """The sorted, non-empty active subset of `live` for round `round_no` (1-based)."""
        ...


def make_scheduler(
    name: str, n: int, seed: int, schedule_path: str | None = None, fairness: int | None = None
) -> Scheduler:
    """Build 'fsync', 'ssync', 'centralized' or 'scripted' (the latter reads `schedule_path`)."""
    raise NotImplementedError
