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

Rows = NDArray[np.float64]  # (k, m)
Sums = NDArray[np.float64]  # (k,)

UNIT: Final = 2.0**-53  # the unit roundoff of float64
TINY: Final = 2.0**-900  # rows whose largest value is below this go to math.fsum (no underflow)
HUGE: Final = 2.0**900  # rows whose largest value is above this go to math.fsum (no overflow)


def fsum_rows(values: Rows) -> Sums:
    """`math.fsum` along axis 1 of `values` (k, m) or (k, m, d): (k,) or (k, d), bit for bit
    (0.0 for an empty or all-zero row, as `math.fsum`). Rows of non-finite values go to
    `math.fsum` too (its answer, or its exception)."""
    x = np.asarray(values, dtype=np.float64)
    m = x.shape[1]
    out = np.zeros(x.shape[:1] + x.shape[2:], dtype=np.float64)
    if m == 0 or out.size == 0:
        return out
    amax = np.maximum(x.max(axis=1), -x.min(axis=1))  # NaN propagates: not `ok` below
    ok = (amax >= TINY) & (amax <= HUGE)
    # sigma = 2^(M + e) with 2^e > amax and 2^M >= m + 2: (x + sigma) - sigma is exact, x less it
    # is exact, and the parts are multiples of 2^-53 sigma below sigma / 2^M in size, so their
    # sum is exact in any order (ExtractVector's lemma)
    _, exps = np.frexp(np.where(ok, amax, 1.0))
    sigma = np.ldexp(1.0, exps + math.ceil(math.log2(m + 2)))
    high = x + sigma[:, None]
    high -= sigma[:, None]
    rest = x - high  # exact; |rest| <= 2^-53 sigma, so sum|rest| <= m 2^-53 sigma
    exact = high.sum(axis=1)
    approx = rest.sum(axis=1)
    # |approx - sum(rest)| <= (m - 1) u / (1 - (m - 1) u) * sum|rest|: doubled for the rounding
    # of the bound's own computation
    bound = (2.0 * m * UNIT) * (m * UNIT) * sigma
    total = exact + approx
    back = total - exact  # TwoSum: total + err == exact + approx, exactly
    err = (exact - (total - back)) + (approx - back)
    gap = np.minimum(np.nextafter(total, np.inf) - total, total - np.nextafter(total, -np.inf))
    room = 0.5 * gap - np.abs(err)  # how far the exact sum may stray and still round to total
    proved = ok & (total != 0.0) & (bound * 1.01 < room * 0.99)
    out[proved] = total[proved]
    for at in zip(*np.nonzero(~proved), strict=True):
        if ok[at] or amax[at] != 0.0:  # an all-zero row sums to 0.0 (NaN: fsum)
            column = x[(at[0], slice(None), *at[1:])]
            out[at] = math.fsum(column.tolist())
    return out


__all__ = ["fsum_rows"]
