"""`math.fsum` of every row of an array at once, the very bits: what an algorithm's round hook
(`compute_views`, fatswarm/domain/seam.py) needs to give each robot the sum its `compute` makes.

`math.fsum` is correctly rounded: any method that finds the exact sum's nearest float (ties to
even) gives its bits. `fsum_rows` splits each row exactly into a part whose sum is exact in
floating point and a small rest (Rump, Ogita and Oishi's ExtractVector), sums the rest with a
bound on its error, and keeps the result only where that bound proves it is the correctly
rounded sum; the few rows it cannot prove (ties, all-but-cancelling rows) go to `math.fsum`.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.scratch import scratch

Rows = NDArray[np.float64]  # (k, m)
Sums = NDArray[np.float64]  # (k,)

UNIT: Final = 2.0**-53  # the unit roundoff of float64
TINY: Final = 2.0**-900  # rows whose largest value is below this go to math.fsum (no underflow)
HUGE: Final = 2.0**900  # rows whose largest value is above this go to math.fsum (no overflow)
NEAR_REL: Final = 2.0**-30  # `nearest_norms`' candidates: squares within this of the least
SQUARE_TINY: Final = 2.0**-900  # squares below: underflow may have cost relative accuracy
SQUARE_HUGE: Final = 2.0**900  # squares above: near overflow
FEW: Final = 4096  # `fsum_rows` finds the largest value by its index up to this many values
HYPOT_ALL: Final = 512  # `nearest_norms` takes np.hypot of every element up to this many


def fsum_rows(values: Rows) -> Sums:
    """`math.fsum` along axis 1 of `values` (k, m) or (k, m, d): (k,) or (k, d), bit for bit
    (0.0 for an empty or all-zero row, as `math.fsum`). Rows of non-finite values go to
    `math.fsum` too (its answer, or its exception)."""
    x = np.asarray(values, dtype=np.float64)
    m = x.shape[1]
    if m == 0 or x.size == 0:
        return np.zeros(x.shape[:1] + x.shape[2:], dtype=np.float64)
    # one sigma for every row: a power of two 2^(M + e) with 2^e > max|x| and 2^M >= m + 2.
    # (x + sigma) - sigma is then exact, x less it is exact, and the parts are multiples of
    # 2^-53 sigma below sigma / 2^M in size, so each row's sum of them is exact in any order
    # (Rump, Ogita and Oishi's ExtractVector)
    if x.size <= FEW:  # an index costs less than a reduction here; NaN: NaN (not finite)
        flat = x.reshape(-1)  # (a copy where x is not contiguous)
        amax = max(float(flat[flat.argmax()]), -float(flat[flat.argmin()]))
    else:
        amax = max(float(x.max()), -float(x.min()))
    if amax == 0.0:  # every value a zero: every sum 0.0
        return np.zeros(x.shape[:1] + x.shape[2:], dtype=np.float64)
    if not TINY <= amax <= HUGE:
        out = np.zeros(x.shape[:1] + x.shape[2:], dtype=np.float64)
        return _fsum_each(x, out, np.ones(out.shape, dtype=np.bool_))
    sigma = math.ldexp(1.0, math.frexp(amax)[1] + (m + 1).bit_length())  # 2^M >= m + 2
    high = np.add(x, sigma, out=scratch("fsum_rows", x.shape))
    high -= sigma  # (x + sigma is positive: no high part is -0.0, nor then any sum of them)
    exact: Sums = np.add.reduce(high, axis=1)
    if _alike(high, x):  # every value its own high part (all on a common grid): the sum is
        return exact  # exact (a zero sum +0.0, as math.fsum has it)
    rest = np.subtract(x, high, out=high)  # exact; |rest| <= 2^-53 sigma: sum <= m 2^-53 sigma
    approx = np.add.reduce(rest, axis=1)
    # |approx - sum(rest)| <= (m - 1) u / (1 - (m - 1) u) * sum|rest|: doubled for the rounding
    # of the bound's own computation
    bound = (2.0 * m * UNIT) * (m * UNIT) * sigma
    total = exact + approx
    back = total - exact  # TwoSum: total + err == exact + approx, exactly
    err = (exact - (total - back)) + (approx - back)
    gap = np.minimum(np.nextafter(total, np.inf) - total, total - np.nextafter(total, -np.inf))
    room = 0.5 * gap - np.abs(err)  # how far the exact sum may stray and still round to total
    proved = (total != 0.0) & (bound * 1.01 < room * 0.99)
    out = np.zeros(total.shape, dtype=np.float64)
    out[proved] = total[proved]
    return _fsum_each(x, out, ~proved)


def _alike(a: Rows, b: Rows) -> bool:
    """Whether `a` and `b` are equal element by element (-0.0 equal to 0.0): up to
    FEW values by their bytes first, fewer calls than a comparison where they are the same."""
    if a.size <= FEW and a.tobytes() == b.tobytes():
        return True
    same = np.equal(a, b, out=scratch("fsum_rows", a.shape, np.bool_)).reshape(-1)
    return bool(same[same.argmin()])


def _fsum_each(x: Rows, out: Sums, rows: NDArray[np.bool_]) -> Sums:
    """`out` with `math.fsum` of each of `rows` of `x` (along axis 1) filled in."""
    for at in zip(*np.nonzero(rows), strict=True):
        column = x[(at[0], slice(None), *at[1:])]
        out[at] = math.fsum(column.tolist())
    return out


def nearest_norms(xs: Rows, ys: Rows) -> Sums:
    """(k,) `np.hypot(xs[i], ys[i]).min()` of every row, bit for bit, for (k, m) coordinates
    (m >= 1). Up to HYPOT_ALL elements, just that; past it, `np.hypot` only on each row's
    candidates, the elements whose x^2 + y^2 is within NEAR_REL of the row's least. Outside that
    margin an element's norm is larger by far more than np.hypot's error (under 1 ulp), so it
    cannot be the least; rows where the least square may have underflowed or be near overflow,
    or is NaN, take `np.hypot` whole. The common case, a round where each row has one
    candidate, needs no search for them: each row's least square is its candidate."""
    shape = np.shape(xs)
    if shape != np.shape(ys):  # (np.broadcast_shapes costs more than the rest of a small call)
        shape = np.broadcast_shapes(shape, np.shape(ys))
    if len(shape) < 2 or shape[0] == 0:
        return np.empty(0, dtype=np.float64)
    if shape[0] * shape[1] <= HYPOT_ALL:
        norms: Sums = np.minimum.reduce(np.hypot(xs, ys), axis=1)
        return norms
    squares = np.multiply(xs, xs, out=scratch("nearest_norms", shape))
    squares += np.multiply(ys, ys, out=scratch("nearest_norms.y", shape))
    every = np.arange(len(squares))
    first = squares.argmin(axis=1)  # a row's least (its first NaN, if any)
    least = squares[every, first]
    near = np.less_equal(
        squares, (least * (1.0 + NEAR_REL))[:, None], out=scratch("nearest_norms", shape, np.bool_)
    )
    # every least square a normal number far from overflow (NaN: not so), and squares past
    # overflow (inf) are not near a finite least: no element's square lost its accuracy, then
    low, high = least[least.argmin()], least[least.argmax()]
    if low >= SQUARE_TINY and high <= SQUARE_HUGE and np.count_nonzero(near) == len(squares):
        norms = np.hypot(xs[every, first], ys[every, first])  # each row one candidate: its least
        return norms
    out = np.empty(len(squares), dtype=np.float64)
    plain = (least >= SQUARE_TINY) & (squares.max(axis=1) <= SQUARE_HUGE)  # NaN: not plain
    rows, cols = np.nonzero(near)
    norms = np.hypot(xs[rows, cols], ys[rows, cols])
    out.fill(np.inf)
    np.minimum.at(out, rows, norms)
    for row in np.flatnonzero(~plain).tolist():
        out[row] = np.hypot(xs[row], ys[row]).min()
    return out


__all__ = ["fsum_rows", "nearest_norms"]
