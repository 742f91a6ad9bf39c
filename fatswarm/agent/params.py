"""What every robot is told before the run: the number of robots n and the side length a."""

from __future__ import annotations

import math
from dataclasses import dataclass

from fatswarm.domain.seam import AlgorithmParamsError

MIN_SIDE = 3.0  # the paper requires a > 3 (robots are unit discs, so centres 2 apart touch)


class ParamsError(AlgorithmParamsError):
    """n or a is outside what the algorithm accepts."""


@dataclass(frozen=True, slots=True)
class Params:
    """The algorithm's inputs besides the snapshot: n robots, polygon side at least a."""

    n: int
    a: float = 4.0

    def __post_init__(self) -> None:
        if isinstance(self.n, bool) or not isinstance(self.n, int) or self.n < 1:
            raise ParamsError(f"n must be a whole number >= 1, got {self.n!r}")
        if not isinstance(self.a, (int, float)) or not math.isfinite(self.a):
            raise ParamsError(f"a must be a finite number, got {self.a!r}")
        if self.a <= MIN_SIDE:
            raise ParamsError(f"a must be > {MIN_SIDE:g} (the paper's bound), got {self.a:g}")
