"""What the phases of the plan share (agent/algorithm.py, agent/expansion.py, agent/formation.py):
the quantities of one snapshot, computed once per call, and the tolerant orders that settle ties
without chirality (G12)."""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Iterator
from typing import NamedTuple

import numpy as np

from fatswarm.agent.geometry import MATCH_WINDOW, Circle, mirror_matched
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
    best = _top_unmatched(pts, cx, tol_at, tol_eq)
    if best is None:  # not settled among the top few: match every robot
        return orientation_of_all(pts, cx, tol_at, tol_eq)
    if best < 0:
        return 0.0
    return 1.0 if float(pts[best, 0]) - cx > 0 else -1.0


def orientation_of_all(pts: Points, cx: float, tol_at: float, tol_eq: float) -> float:
    """`orientation_of` by matching every robot with its mirror image (no top-down shortcut)."""
    unmatched = ~mirror_matched(pts, cx, tol_at)
    if not unmatched[unmatched.argmax()]:
        return 0.0
    idx = unmatched.nonzero()[0]
    xs, ys = pts[:, 0], pts[:, 1]
    best = int(idx[first_ranked(-ys[idx], tol_eq, lambda: (-np.abs(xs[idx] - cx),))])
    return 1.0 if float(xs[best]) - cx > 0 else -1.0


TOP_ROBOTS = 16
"""`_top_unmatched` matches at most this many robots, from the top, before giving up."""


def _top_unmatched(pts: Points, cx: float, tol_at: float, tol_eq: float) -> int | None:
    """`orientation_of`'s robot, found by matching robots from the top down, as a canonical form
    (sorted by y) allows: the answer is the top unmatched robot and its ties, and those are
    usually among the first few. -1 if every robot matches (n <= TOP_ROBOTS); None if the rows
    are not sorted by y or the answer is not settled within TOP_ROBOTS robots (or windows).

    The very operations of `mirror_matched` (each robot against the robots whose y lies in
    [y - tol, y + tol], as its searchsorted windows) and of `first_ranked` (ties within tol_eq of
    the largest y, then of the largest |x - c_x|, then the lowest index), on Python floats.
    """
    n = len(pts)
    if n < 2 or not 0.0 <= tol_at < math.inf:
        return None
    ys = pts[:, 1]
    if np.count_nonzero(ys[:-1] <= ys[1:]) < n - 1:  # not sorted (or NaN: it compares False)
        return None
    y_list = ys.tolist()
    if not math.isfinite(y_list[0]) or not math.isfinite(y_list[-1]):  # sorted: all finite then
        return None
    if n > MATCH_WINDOW:
        # mirror_matched compares all pairs when a window [y - tol, y + tol] holds more than
        # MATCH_WINDOW robots: these are MATCH_WINDOW rows apart, so no more than 2 tol apart in
        # y (and a margin for the rounding of y +- tol, as mirror_matched's own). The
        # differences are finite (the heights are), so "some <= 2 reach" is "not min > 2 reach".
        reach = tol_at + 1e-9 * (max(abs(y_list[0]), abs(y_list[-1])) + tol_at)
        apart = ys[MATCH_WINDOW:] - ys[:-MATCH_WINDOW]
        if np.count_nonzero(apart <= 2.0 * reach):
            return None
    x_list = pts[:, 0].tolist()
    tol2 = tol_at * tol_at
    mirror_x = 2.0 * cx
    found: list[int] = []  # unmatched robots, from the top down
    bound = math.inf  # the tied robots' -y reach at most this
    for q in range(n - 1, max(-1, n - 1 - TOP_ROBOTS), -1):
        y = y_list[q]
        if -y > bound:
            break
        mx = mirror_x - x_list[q]
        lo_q, hi_q = bisect.bisect_left(y_list, y - tol_at), bisect.bisect_right(y_list, y + tol_at)
        for j in range(lo_q, hi_q):
            dx, dy = x_list[j] - mx, y_list[j] - y
            if dx * dx + dy * dy <= tol2:
                break
        else:
            if not found:
                bound = -y + tol_eq
            found.append(q)
    else:
        if n > TOP_ROBOTS:
            return None  # not settled: the top robots match, or the ties go on below them
        if not found:
            return -1
    # first_ranked: the lowest index of the largest y (found[-1] has the largest y among the
    # lowest indices), the ties within tol_eq of it, then the second key over them
    if len(found) == 1 and tol_eq >= 0.0:  # low <= low + tol_eq: the one robot ties with itself
        return found[0]
    low = -y_list[found[0]]
    tied = sorted(q for q in found if -y_list[q] <= low + tol_eq)
    if len(tied) == 1:
        return tied[0]
    values = [-abs(x_list[q] - cx) for q in tied]
    least = min(values) + tol_eq
    return next(q for q, v in zip(tied, values, strict=True) if v <= least)


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
        low = float(keys[i])  # (the same sum low + tol as on a numpy scalar, cheaper)
        if low == math.inf:
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
