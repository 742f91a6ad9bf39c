"""What the phases of the plan share (agent/algorithm.py, agent/expansion.py, agent/formation.py):
the quantities of one snapshot, computed once per call, and the tolerant orders that settle ties
without chirality (G12)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import NamedTuple

import numpy as np

from fatswarm.agent.geometry import Circle, mirror_matched
from fatswarm.domain.path import Path, Points

Step = tuple[str, dict[int, Path]]
"""A phase's choice: its kind (`Plan.kind`) and the moves it makes (robot index -> path)."""

TieKeys = Callable[[], tuple[np.ndarray, ...]]
"""The key columns after the first, made only when a tie needs them."""


class Ctx(NamedTuple):
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
    unmatched = ~mirror_matched(pts, cx, tol_at)
    if not unmatched[unmatched.argmax()]:
        return 0.0
    idx = unmatched.nonzero()[0]
    xs, ys = pts[:, 0], pts[:, 1]
    best = int(idx[first_ranked(-ys[idx], tol_eq, lambda: (-np.abs(xs[idx] - cx),))])
    return 1.0 if float(xs[best]) - cx > 0 else -1.0


def ranked(first: np.ndarray, tol: float, tie_keys: TieKeys | None = None) -> Iterator[int]:
    """Indices in increasing lexicographic order of the key columns (each (m,)), lazily.

    `first` is the first column, `tie_keys()` the others. Values within `tol` of the smallest
    remaining one count as ties and fall through to the next column; full ties go by index. Lazy
    because the caller usually stops at the first, and the later columns are rarely needed.
    """
    keys = np.asarray(first, dtype=np.float64)
    rest: tuple[np.ndarray, ...] | None = None
    copied = False
    for _ in range(len(keys)):
        i = int(keys.argmin())
        low = keys[i]
        if low == np.inf:
            return
        tied = (keys <= low + tol).nonzero()[0]
        if len(tied) > 1:  # rare outside mirror pairs: settle on the next columns
            if rest is None:
                rest = tie_keys() if tie_keys is not None else ()
            group = tied.tolist()
            for col in rest:
                values = col[group].tolist()
                bound = min(values) + tol
                group = [g for g, v in zip(group, values, strict=True) if v <= bound]
                if len(group) == 1:
                    break
            i = group[0]
        yield i
        if not copied:  # taken rows are set to +inf, in a copy
            keys = keys.copy()
            copied = True
        keys[i] = np.inf


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


def first_ranked(first: np.ndarray, tol: float, tie_keys: TieKeys | None = None) -> int:
    """Index of the smallest key under the tolerant order of `ranked`."""
    return next(ranked(first, tol, tie_keys))


def without(pts: Points, i: int) -> Points:
    """All rows but row i (cheaper than np.delete on small arrays)."""
    return np.concatenate((pts[:i], pts[i + 1 :]))
