"""orjson's float text against `repr`'s on many drawn values: the referee of
fatswarm/world/float_text.py (the record takes orjson's text only for values in [1e-4, 1e16)).

    python bench/float_text_check.py                  # 10 million values, about a minute
    python bench/float_text_check.py --count 1000000

Prints, for values drawn as bit patterns inside the range (both signs), over every finite float,
and as decimal-looking values (rounded to 1 to 17 digits), how many orjson writes otherwise
than `repr`, and how many of those `floats_text` would have taken (must be 0). Exit 1 if any.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import numpy as np
import orjson

from fatswarm.world.float_text import HIGH, LOW, floats_text

CHUNK = 200_000


def _families(rng: np.random.Generator, count: int) -> dict[str, np.ndarray]:
    bounds = np.array([LOW, HIGH]).view(np.int64)
    inside = rng.integers(bounds[0], bounds[1], count, dtype=np.int64).view(np.float64)
    every = rng.integers(0, 0x7FF0000000000000, count, dtype=np.int64).view(np.float64)
    digits = rng.integers(1, 18, count)
    decimal = np.array(
        [float(f"{m:.{d}e}") for m, d in zip(rng.uniform(1, 10, count), digits, strict=True)]
    ) * 10.0 ** rng.integers(-4, 16, count)
    sign = np.where(rng.random(count) < 0.5, -1.0, 1.0)
    return {
        "bits in [1e-4, 1e16)": inside * sign,
        "every finite float": every * sign,
        "decimal-looking": decimal * sign,
    }


def check(count: int, seed: int = 0) -> int:
    """Print the counts; return how many values `floats_text` took whose text differs."""
    rng = np.random.default_rng(seed)
    wrong_taken = 0
    totals: dict[str, list[int]] = {}
    for start in range(0, count, CHUNK):
        size = min(CHUNK, count - start)
        for name, values in _families(rng, size).items():
            fast = orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY).decode()[1:-1]
            want = [repr(x) for x in values.tolist()]
            differ = np.array([a != b for a, b in zip(fast.split(","), want, strict=True)])
            magnitude = np.abs(values)
            inside = (magnitude == 0) | ((magnitude >= LOW) & (magnitude < HIGH))
            wrong_taken += int(np.count_nonzero(differ & inside))
            total = totals.setdefault(name, [0, 0, 0])
            total[0] += size
            total[1] += int(np.count_nonzero(differ))
            total[2] += int(np.count_nonzero(inside))
        print(f"\r{start + size:,} of {count:,} values a family", end="", file=sys.stderr)
    print(file=sys.stderr)
    for name, (drawn, unlike, inside_count) in totals.items():
        print(
            f"{name:24} {drawn:>12,} values, {inside_count:>12,} in range, "
            f"orjson != repr: {unlike:,}"
        )
    assert floats_text(np.array([0.1])) == "[0.1]", "floats_text's path is off on this install"
    print(f"taken by floats_text and written otherwise than repr: {wrong_taken}")
    return wrong_taken


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--count", type=int, default=10_000_000, help="values a family")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    if args.count <= 0:
        p.error("--count must be positive")
    return 1 if check(args.count, args.seed) else 0


if __name__ == "__main__":
    raise SystemExit(main())
