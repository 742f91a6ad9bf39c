"""Work arrays kept from one call to the next: a round's views at n = 256 hold megabytes, and a
fresh array of that size costs a page fault per 4 kB (the allocator hands the memory back between
rounds), more than the arithmetic done in it.

Only for arrays that never leave the function that asks for them: the next call of the same
`slot` in the same thread overwrites it. One buffer per slot, dtype and thread, as large as the
largest array asked of it (a round's active robots vary in number under ssync); the array of
each shape asked is kept too, so a round that asks what the last one asked gets it back at once.
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
    try:
        shaped: dict[tuple[str, tuple[int, ...], Any], np.ndarray] = _KEPT.shaped
    except AttributeError:
        shaped = _KEPT.shaped = {}
        _KEPT.buffers = {}
    got = shaped.get((slot, shape, dtype))
    if got is not None:
        return got
    return _shaped(shaped, slot, shape, dtype)


def _shaped(
    shaped: dict[tuple[str, tuple[int, ...], Any], np.ndarray],
    slot: str,
    shape: tuple[int, ...],
    dtype: Any,
) -> np.ndarray:
    """`scratch` the first time `slot` is asked for `shape` and `dtype` since its buffer grew."""
    buffers: dict[tuple[str, np.dtype[Any]], np.ndarray] = _KEPT.buffers
    kind = np.dtype(dtype)
    size = math.prod(shape)
    buffer = buffers.get((slot, kind))
    if buffer is None or len(buffer) < size:
        buffer = buffers[slot, kind] = np.empty(size, dtype=kind)
        for key in [key for key in shaped if key[0] == slot and np.dtype(key[2]) == kind]:
            del shaped[key]  # arrays of the old buffer: asked again, they come from the new one
    got = shaped[slot, shape, dtype] = buffer[:size].reshape(shape)
    return got


__all__ = ["scratch"]
