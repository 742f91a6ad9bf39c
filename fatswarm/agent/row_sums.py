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


def fsum_rows(values: Rows) -> Sums:
    """`math.fsum` along axis 1 of `values` (k, m) or (k, m, d): (k,) or (k, d), bit for bit
    (0.0 for an empty or all-zero row, as `math.fsum`). Rows of non-finite values go to
    `math.fsum` too (its answer, or its exception)."""
    x = np.asarray(values, dtype=np.float64)
    m = x.shape[1]
    out = np.zeros(x.shape[:1] + x.shape[2:], dtype=np.float64)
    if m == 0 or out.size == 0:
        return out
    # one sigma for every row: a power of two 2^(M + e) with 2^e > max|x| and 2^M >= m + 2.
    # (x + sigma) - sigma is then exact, x less it is exact, and the parts are multiples of
    # 2^-53 sigma below sigma / 2^M in size, so each row's sum of them is exact in any order
    # (Rump, Ogita and Oishi's ExtractVector)
    amax = max(float(x.max()), -float(x.min()))  # NaN: not finite, every row to math.fsum
    if amax == 0.0:  # every value a zero: every sum 0.0
        return out
    if not TINY <= amax <= HUGE:
        return _fsum_each(x, out, np.ones(out.shape, dtype=np.bool_))
    sigma = math.ldexp(1.0, math.frexp(amax)[1] + math.ceil(math.log2(m + 2)))
    high = np.add(x, sigma, out=scratch("fsum_rows", x.shape))
    high -= sigma
    exact = high.sum(axis=1)
    if np.array_equal(high, x):  # every value its own high part (all on a common grid): the sum
        out += exact  # is exact; 0.0 + s is s, and a zero sum +0.0, as math.fsum has it
        return out
    rest = np.subtract(x, high, out=high)  # exact; |rest| <= 2^-53 sigma: sum <= m 2^-53 sigma
    approx = rest.sum(axis=1)
    # |approx - sum(rest)| <= (m - 1) u / (1 - (m - 1) u) * sum|rest|: doubled for the rounding
    # of the bound's own computation
    bound = (2.0 * m * UNIT) * (m * UNIT) * sigma
    total = exact + approx
    back = total - exact  # TwoSum: total + err == exact + approx, exactly
    err = (exact - (total - back)) + (approx - back)
    gap = np.minimum(np.nextafter(total, np.inf) - total, total - np.nextafter(total, -np.inf))
    room = 0.5 * gap - np.abs(err)  # how far the exact sum may stray and still round to total
    proved = (total != 0.0) & (bound * 1.01 < room * 0.99)
    out[proved] = total[proved]
    return _fsum_each(x, out, ~proved)


def _fsum_each(x: Rows, out: Sums, rows: NDArray[np.bool_]) -> Sums:
    """`out` with `math.fsum` of each of `rows` of `x` (along axis 1) filled in."""
    for at in zip(*np.nonzero(rows), strict=True):
        column = x[(at[0], slice(None), *at[1:])]
        out[at] = math.fsum(column.tolist())
    return out


def nearest_norms(xs: Rows, ys: Rows) -> Sums:
    """(k,) `np.hypot(xs[i], ys[i]).min()` of every row, bit for bit, for (k, m) coordinates
    (m >= 1): `np.hypot` only on each row's candidates, the elements whose x^2 + y^2 is within
    NEAR_REL of the row's least. Outside that margin an element's norm is larger by far more than
    np.hypot's error (under 1 ulp), so it cannot be the least; rows where squares could underflow
    or overflow, or hold NaN, take `np.hypot` whole. The common case, a round where each row has
    one candidate, needs no search for them: each row's least square is its candidate."""
    shape = np.broadcast_shapes(np.shape(xs), np.shape(ys))
    squares = np.multiply(xs, xs, out=scratch("nearest_norms", shape))
    squares += np.multiply(ys, ys, out=scratch("nearest_norms.y", shape))
    if len(squares) == 0:
        return np.empty(0, dtype=np.float64)
    every = np.arange(len(squares))
    first = squares.argmin(axis=1)  # a row's least (its first NaN, if any)
    least = squares[every, first]
    near = np.less_equal(
        squares, (least * (1.0 + NEAR_REL))[:, None], out=scratch("nearest_norms", shape, np.bool_)
    )
    if (
        bool((least >= SQUARE_TINY).all())
        and float(squares.max()) <= SQUARE_HUGE  # NaN: not so
        and np.count_nonzero(near) == len(squares)  # every row one candidate: its least
    ):
        norms: Sums = np.hypot(xs[every, first], ys[every, first])
        return norms
    out = np.empty(len(xs), dtype=np.float64)
    plain = (least >= SQUARE_TINY) & (squares.max(axis=1) <= SQUARE_HUGE)  # NaN: not plain
    rows, cols = np.nonzero(near)
    norms = np.hypot(xs[rows, cols], ys[rows, cols])
    out.fill(np.inf)
    np.minimum.at(out, rows, norms)
    for row in np.flatnonzero(~plain).tolist():
        out[row] = np.hypot(xs[row], ys[row]).min()
    return out


__all__ = ["fsum_rows", "nearest_norms"]
