"""The adversaries' part in the world: moves cut short (non-rigid) and robots crashed, and when a
robot whose agent is gone counts as crashed."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

from fatswarm.domain.path import Path, Point, path_length, truncate

CRASH_MIN_ROUNDS: Final = 10


def crash_after(n: int) -> int:
    """Committed rounds a robot's agent may be gone before it counts as crashed: twice the
    default fairness bound (every live robot is active at least once in 2n rounds), >= 10."""
    return max(CRASH_MIN_ROUNDS, 4 * n)


def cut_path(start: Point, path: Path, delta: float, u: float) -> Path:
    """`path` (from `start`) as the non-rigid adversary stops it: whole if its length L is at most
    `delta`, else its prefix of length delta + u (L - delta), u in [0, 1) (issue 10's model: the
    robot travels at least delta, or reaches its end)."""
    length = path_length(start, path)
    if length <= delta:
        return path
    return truncate(start, path, delta + u * (length - delta))


def stuck_in(plan: Mapping[int, int], round_no: int) -> list[int]:
    """The robots the crash adversary crashes in round `round_no` (`plan`: robot -> its round,
    `fatswarm.domain.draws.crash_plan`)."""
    return sorted(r for r, at in plan.items() if at == round_no)
