"""Work arrays kept between calls (`fatswarm.domain.scratch`): one buffer per slot and dtype,
grown when too small, and the array of a shape asked before handed back at once."""

from __future__ import annotations

import numpy as np

from fatswarm.domain.scratch import scratch


def test_a_shape_asked_again_is_the_same_array_on_the_same_memory() -> None:
    first = scratch("test-again", (3, 4))
    first[...] = 7.0
    again = scratch("test-again", (3, 4))
    assert again is first and again.shape == (3, 4) and again.flags.c_contiguous
    other = scratch("test-again", (2, 6))  # another shape of the slot: the same buffer
    assert np.shares_memory(other, first) and other.shape == (2, 6)


def test_a_larger_shape_grows_the_buffer_and_smaller_ones_then_come_from_it() -> None:
    small = scratch("test-grow", (2, 2))
    large = scratch("test-grow", (10, 10))
    assert large.shape == (10, 10) and not np.shares_memory(large, small)
    again = scratch("test-grow", (2, 2))  # asked before the buffer grew: from the new one now
    assert again is not small and np.shares_memory(again, large)


def test_dtypes_and_slots_have_buffers_of_their_own() -> None:
    floats = scratch("test-kinds", (4,))
    flags = scratch("test-kinds", (4,), np.bool_)
    other = scratch("test-kinds-other", (4,))
    assert floats.dtype == np.float64 and flags.dtype == np.bool_
    assert not np.shares_memory(floats, flags) and not np.shares_memory(floats, other)
