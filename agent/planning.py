"""What the phases of the plan share (agent/algorithm.py, agent/expansion.py, agent/formation.py):
the quantities of one snapshot, computed once per call, and the tolerant orders that settle ties
without chirality (G12)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from fatswarm.agent.geometry import Circle, mirror_matched
from fatswarm.domain.path import Path, Points

Step = tuple[str, dict[int, Path]]
"""A phase's choice: its kind (`Plan.kind`) and the moves it makes (robot index -> path)."""


@dataclass(frozen=True, slots=True)
class Ctx:
    """Quantities of one snapshot shared by the routines (computed once per call)."""

    pts: Points
    circle: Circle
    tol_at: float
    tol_eq: float
    r: float  # the target radius: FormUCircle moves never bring the SEC below it (G9)
    orientation: float  # +1/-1: the agreed "right" in an asymmetric configuration; 0 if symmetric

    @property
    def symmetric(self) -> bool:
        return self.orientation == 0.0

    @property
    def cx(self) -> float:
        return self.circle.center[0]


# --- ties without chirality (G12) ----------------------------------------------------------------


def orientation_of(pts: Points, cx: float, tol_at: float, tol_eq: float) -> float:
    """s = sign(x - c_x) of the unmatched robot with the largest (y, |x - c_x|); 0 if symmetric.

    It flips with the frame, so `s * x` means the same side to every robot: an agreed left/right.
    """
    idx = (~mirror_matched(pts, cx, tol_at)).nonzero()[0]
    if len(idx) == 0:
        return 0.0
    dx = pts[idx, 0] - cx
    best = first_ranked((-pts[idx, 1], -np.abs(dx)), tol_eq)
    return 1.0 if dx[best] > 0 else -1.0


def ranked(cols: tuple[np.ndarray, ...], tol: float) -> Iterator[int]:
    """Indices in increasing lexicographic order of the key columns `cols` (each (m,)), lazily.

    Values within `tol` of the smallest remaining one count as ties and fall through to the next
    column; full ties go by index. Lazy because the caller usually stops at the first.
    """
    first = np.array(cols[0], dtype=np.float64)  # a copy: taken rows are set to +inf
    for _ in range(len(first)):
        i = int(first.argmin())
        low = first[i]
        if low == np.inf:
            return
        tied = (first <= low + tol).nonzero()[0]
        if len(tied) > 1:  # rare outside mirror pairs: settle on the next columns
            group = tied
            for col in cols[1:]:
                values = col[group]
                group = group[values <= values.min() + tol]
                if len(group) == 1:
                    break
            i = int(group[0])
        first[i] = np.inf
        yield i


class Lazy:
    """An iterator's items, computed as first asked for and replayed on every later pass."""

    def __init__(self, items: Iterator[int]) -> None:
        self._items = items
        self._seen: list[int] = []

    def __iter__(self) -> Iterator[int]:
        yield from self._seen
        for item in self._items:
            self._seen.append(item)
            yield item


def first_ranked(cols: tuple[np.ndarray, ...], tol: float) -> int:
    """Index of the smallest key under the tolerant order of `ranked`."""
    return next(ranked(cols, tol))


def without(pts: Points, i: int) -> Points:
    """All rows but row i (cheaper than np.delete on small arrays)."""
    return np.concatenate((pts[:i], pts[i + 1 :]))
