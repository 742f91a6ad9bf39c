"""Work arrays kept from one call to the next: a round's views at n = 256 hold megabytes, and a
fresh array of that size costs a page fault per 4 kB (the allocator hands the memory back between
rounds), more than the arithmetic done in it.

Only for arrays that never leave the function that asks for them: the next call of the same
`slot` in the same thread overwrites it. One buffer per slot, dtype and thread, as large as the
largest array asked of it (a round's active robots vary in number under ssync).
"""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np

_KEPT = threading.local()


def scratch(slot: str, shape: tuple[int, ...], dtype: Any = np.float64) -> np.ndarray:
    """An uninitialised C-contiguous array of `shape` and `dtype` for `slot`: the memory of the
    previous calls' for that slot and dtype (in this thread), grown when too small."""
    kept: dict[tuple[str, np.dtype[Any]], np.ndarray] = _KEPT.__dict__.setdefault("arrays", {})
    kind = np.dtype(dtype)
    size = math.prod(shape)
    buffer = kept.get((slot, kind))
    if buffer is None or len(buffer) < size:
        buffer = kept[slot, kind] = np.empty(size, dtype=kind)
    return buffer[:size].reshape(shape)


__all__ = ["scratch"]
