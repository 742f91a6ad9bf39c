"""Floats as the record writes them, `repr`'s text, made by orjson's compiled formatter where that
is proven to give the same bytes: the round line's floats were most of a recorded round's cost.

JSON (`json.dumps`) writes a float as its `repr`: the shortest digits that read back to the same
float, positional from 1e-4 up to 1e16 and in exponent form outside. orjson writes the same
shortest digits, but moves between the two forms at other magnitudes and writes its exponents its
own way (`0.00003945909461200336` for repr's `3.945909461200336e-05`, `4.33278198636691e-6` for
`4.33278198636691e-06`), so its text is taken only for arrays whose every value is 0 or of
magnitude in [1e-4, 1e16), where both are positional; any other array (NaN, infinity, tiny or
huge values) is left to `repr`. Where the two were compared
(tests/property/test_float_text.py, bench/float_text_check.py) they agreed on every such value;
`AGREES` repeats a sample of that check at import, so that an orjson that formats otherwise turns
this path off instead of changing a record.
"""

from __future__ import annotations

from typing import Any, Final

import numpy as np
import orjson
from numpy.typing import NDArray

LOW: Final = 1e-4
"""The smallest magnitude of a non-zero value taken (repr's positional form starts here)."""
HIGH: Final = 1e16
"""Values of this magnitude or more are not taken (repr's exponent form starts here)."""

_NUMPY: Final = orjson.OPT_SERIALIZE_NUMPY


def _sample() -> NDArray[np.float64]:
    """Values at and beside the bounds, zeros of both signs, short and long digit strings, and
    drawn bit patterns inside the bounds: what `AGREES` checks at import."""
    edges = [LOW, HIGH, 0.1, 0.2, 0.3, 1 / 3, 2 / 3, 1.0, 2.5, 100.0, 123.456, 1e15, 2.0**52]
    near = [float(np.nextafter(e, t)) for e in (LOW, HIGH, 1.0, 1e15) for t in (0.0, np.inf)]
    bounds = np.array([LOW, HIGH]).view(np.int64)  # positive floats order as their bits do
    bits = np.random.default_rng(20261128).integers(bounds[0], bounds[1], 512, dtype=np.int64)
    values = np.concatenate([[0.0], edges, near, bits.view(np.float64)])
    values = values[(values == 0) | ((values >= LOW) & (values < HIGH))]
    return np.concatenate([values, -values])


def _agrees() -> bool:
    """Whether orjson gives `repr`'s text of every value of `_sample` (arrays and lists alike)."""
    values = _sample()
    want = "[" + ",".join(map(repr, values.tolist())) + "]"
    return (
        orjson.dumps(values, option=_NUMPY).decode()
        == want
        == orjson.dumps(values.tolist()).decode()
    )


AGREES: Final = _agrees()
"""orjson formats the sample as `repr` does; if not, `floats_text` always answers None."""


def taken(values: NDArray[np.float64]) -> bool:
    """Whether every value is 0 or of magnitude in [LOW, HIGH) (NaN is not)."""
    if values.size == 0:
        return True
    size = np.abs(values)
    if not size.max() < HIGH:  # (NaN compares False)
        return False
    return bool(size.min() >= LOW) or bool(((size >= LOW) | (size == 0.0)).all())


def floats_text(values: NDArray[Any]) -> str | None:
    """`json.dumps(values.tolist(), separators=(",", ":"))` of a float64 array of any shape, or
    None where that text is not proven: a value outside `taken`'s range, another dtype, or an
    orjson that failed `AGREES`."""
    if not AGREES or values.dtype != np.float64 or not taken(values):
        return None
    return orjson.dumps(np.ascontiguousarray(values), option=_NUMPY).decode()
