"""What every robot is told before the run: the number of robots n and the side length a."""

from __future__ import annotations

import math
from dataclasses import dataclass

from fatswarm.domain.seam import AlgorithmParamsError

MIN_SIDE = 3.0  # the paper requires a > 3 (robots are unit discs, so centres 2 apart touch)


class ParamsError(AlgorithmParamsError):
    """n or a is outside what the algorithm accepts."""


def check_count(n: object, error: type[AlgorithmParamsError] = AlgorithmParamsError) -> None:
    """Refuse an n that is not a whole number >= 1 (`error`, one line); None (not given) passes."""
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
        raise error(f"n must be a whole number >= 1, got {n!r}")


def check_tolerance(tol: object, *, zero_ok: bool) -> None:
    """Refuse a tolerance that is not a finite number > 0 (>= 0 with `zero_ok`)."""
    if (
        isinstance(tol, bool)
        or not isinstance(tol, (int, float))
        or not (math.isfinite(tol) and (tol >= 0.0 if zero_ok else tol > 0.0))
    ):
        bound = ">= 0" if zero_ok else "> 0"
        raise AlgorithmParamsError(f"tolerance must be finite and {bound}, got {tol!r}")


@dataclass(frozen=True, slots=True)
class Params:
    """The algorithm's inputs besides the snapshot: n robots, polygon side at least a."""

    n: int
    a: float = 4.0

    def __post_init__(self) -> None:
        if self.n is None:
            raise ParamsError("n must be a whole number >= 1, got None")
        check_count(self.n, ParamsError)
        if not isinstance(self.a, (int, float)) or not math.isfinite(self.a):
            raise ParamsError(f"a must be a finite number, got {self.a!r}")
        if self.a <= MIN_SIDE:
            raise ParamsError(f"a must be > {MIN_SIDE:g} (the paper's bound), got {self.a:g}")
