"""Adversarial starts: seeded families of near-degenerate configurations that random starts miss.

Each start is deterministic from (family, n, seed) and valid (every pair of centres at least
2 - CONTACT_SLACK apart). The shapes (`shapes.py`) are pure functions of explicit parameters, so the
hypothesis strategies (tests/property/strategies.py) build the same classes without seeds; each
family draws its parameters in `families.py`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Final

import numpy as np

from fatswarm.deploy.scenarios.families import (
    Built,
    ConstructionError,
    Retry,
    draw_cluster,
    draw_exact_symmetric,
    draw_formed,
    draw_lattice,
    draw_near_symmetric,
    draw_near_touching,
    draw_rim,
    draw_rows,
    draw_stacked_rows,
    draw_vertical_line,
)
from fatswarm.deploy.scenarios.shapes import OFFSET_RANGE, exact_translation, min_separation
from fatswarm.domain.draws import ADVERSARIAL_STREAM, CASES_STREAM
from fatswarm.domain.path import Points
from fatswarm.domain.tolerance import CONTACT
from fatswarm.world.physics import CONTACT_SLACK, validate_configuration

SEED_MASK: Final = 0xFFFFFFFF
MAX_N: Final = 400  # largest n any family builds (rejection sampling stays fast up to here)
SIDES: Final = (3.2, 4.0, 6.0)  # a of an adversarial case: just above 3, the default, wide


@dataclass(frozen=True, slots=True)
class Family:
    """One adversarial family: its name, what it stresses, and the n it builds."""

    name: str
    description: str
    n_min: int
    n_max: int = MAX_N
    by_default: bool = True  # drawn when no family is named (hunts, `adversarial_cases`)


FAMILY_TABLE: Final = (
    Family(
        "near-symmetric",
        "mirror symmetric about a vertical line, then 1-3 robots moved by "
        "1e-12..1e-6; some with a pair 1 +- 1e-9..1e-6 from the axis, some with exact ties",
        2,
    ),
    Family(
        "exact-symmetric",
        "exactly mirrored about x = c (c an integer): random, a pair "
        "touching across the axis or 1e-9..1e-6 from touching, exact ties of candidates",
        2,
    ),
    Family(
        "near-touching",
        "clusters and chains with neighbours 2 +- 1e-9..1e-6 apart (never "
        "below 2 - 5e-8), and exactly touching chains",
        2,
    ),
    Family(
        "lattice",
        "square (also Pythagorean-rotated) and hexagonal touching lattices written "
        "to 3-7 decimals, some with one robot nudged by 1e-9..1e-6",
        2,
    ),
    Family(
        "vertical-line",
        "touching robots on x = 0 (y = 0, 2, 4, ...), one moved by "
        "1e-9..1e-6 sideways or along the line",
        2,
    ),
    Family(
        "offset", "another family or a random cluster translated exactly by 1e5..1e6 in x and y", 2
    ),
    Family(
        "rim",
        "robots near one circle of perimeter 1.5-4 x 2n: on it (some touching), in a "
        "thin annulus, on a jittered regular polygon, along a parabola arc",
        3,
    ),
    Family(
        "formed",
        "an already formed regular n-gon of side >= 4, rotated at random, possibly "
        "offset by up to 1e5",
        2,
    ),
    # appended last: the families above keep their index (their seeds), so their draws stay
    Family(
        "rows",
        "1-3 horizontal rows of robots touching (2 apart), near touching or mixed, rows 2-8 "
        "apart, shifted sideways at random",
        2,
        by_default=False,
    ),
    Family(
        "stacked-rows",
        "2 or more rows of touching robots, each row touching the one below: square, brick "
        "wall or slanted stacks, a short top row, some with one robot nudged by 1e-9..1e-6",
        2,
        by_default=False,
    ),
)
FAMILIES: Final[tuple[str, ...]] = tuple(f.name for f in FAMILY_TABLE)
# the families drawn when none is named: those before `rows`, so that earlier hunts and benches
# draw what they always drew (name the newer ones with --starts)
DEFAULT_FAMILIES: Final[tuple[str, ...]] = tuple(f.name for f in FAMILY_TABLE if f.by_default)
DESCRIPTIONS: Final[Mapping[str, str]] = MappingProxyType(
    {f.name: f.description for f in FAMILY_TABLE}
)
OFFSET_BASES: Final = (
    "near-symmetric",
    "exact-symmetric",
    "near-touching",
    "lattice",
    "vertical-line",
    "rim",
    "cluster",
)


@dataclass(frozen=True, slots=True, eq=False)
class AdversarialStart:
    """A built start: (n, 2) positions, which variant of the family, and its mirror axis if any.

    `axis_x` is the x of the vertical mirror line of the (unperturbed) configuration, or None.
    """

    family: str
    variant: str
    n: int
    seed: int
    positions: Points
    axis_x: float | None = None


@dataclass(frozen=True, slots=True)
class Case:
    """One adversarial run: the start (family, n, seed) and the side a it is run with."""

    family: str
    n: int
    seed: int
    a: float

    def start(self) -> Points:
        """The (n, 2) start of this case."""
        return adversarial_start(self.family, self.n, self.seed)


# ---------------------------------------------------------------------------------------------
# The families


def _offset(rng: np.random.Generator, n: int) -> Built:
    bases = [b for b in OFFSET_BASES if b == "cluster" or _family(b).n_min <= n]
    base = bases[int(rng.integers(len(bases)))]
    child = np.random.default_rng(rng.integers(0, 2**63))
    variant, pts, axis = _attempts(_BUILDERS[base], child, n, base)
    off = rng.uniform(*OFFSET_RANGE, size=2) * np.where(rng.random(2) < 0.5, -1.0, 1.0)
    moved, applied = exact_translation(pts, off)
    new_axis = None if axis is None else axis + float(applied[0])  # exact: an integer axis
    return f"{base}:{variant}", moved, new_axis


_BUILDERS: Final[Mapping[str, Callable[[np.random.Generator, int], Built]]] = MappingProxyType(
    {
        "near-symmetric": draw_near_symmetric,
        "exact-symmetric": draw_exact_symmetric,
        "near-touching": draw_near_touching,
        "lattice": draw_lattice,
        "vertical-line": draw_vertical_line,
        "offset": _offset,
        "rim": draw_rim,
        "formed": draw_formed,
        "rows": draw_rows,
        "stacked-rows": draw_stacked_rows,
        "cluster": draw_cluster,
    }
)


def _family(name: str) -> Family:
    for fam in FAMILY_TABLE:
        if fam.name == name:
            return fam
    raise ValueError(f"unknown adversarial family {name!r}; choose one of {', '.join(FAMILIES)}")


def _attempts(
    builder: Callable[[np.random.Generator, int], Built],
    rng: np.random.Generator,
    n: int,
    name: str,
) -> Built:
    for _ in range(50):
        try:
            variant, pts, axis = builder(rng, n)
        except Retry:
            continue
        pts = np.ascontiguousarray(pts, dtype=np.float64)
        if (
            pts.shape == (n, 2)
            and np.isfinite(pts).all()
            and min_separation(pts) >= (CONTACT - CONTACT_SLACK)
        ):
            return variant, pts, axis
    raise ConstructionError(f"could not build a valid {name} start for n={n}")  # pragma: no cover


def family_range(family: str) -> tuple[int, int]:
    """The least and greatest n the family builds."""
    fam = _family(family)
    return fam.n_min, fam.n_max


def build_adversarial(family: str, n: int, seed: int) -> AdversarialStart:
    """The start of (family, n, seed) with its variant and mirror axis; ValueError if n is out of
    the family's range or the family is unknown."""
    fam = _family(family)
    if (
        isinstance(n, bool)
        or not isinstance(n, (int, np.integer))
        or not (fam.n_min <= n <= fam.n_max)
    ):
        raise ValueError(f"family {family!r} builds n from {fam.n_min} to {fam.n_max}, got n={n!r}")
    n = int(n)
    rng = np.random.default_rng([ADVERSARIAL_STREAM, seed & SEED_MASK, n, FAMILIES.index(family)])
    variant, pts, axis = _attempts(_BUILDERS[family], rng, n, family)
    validate_configuration(pts)  # the contract: never an overlapping start
    return AdversarialStart(family, variant, n, seed, pts, axis)


def adversarial_start(family: str, n: int, seed: int) -> Points:
    """A valid (n, 2) start of the family, the same for the same (family, n, seed)."""
    return build_adversarial(family, n, seed).positions


def adversarial_cases(count: int, seed: int, n_max: int = 40) -> list[Case]:
    """`count` cases spread round-robin over the families, each family's n cycling through a
    shuffled n_min..n_max, a drawn from SIDES (for 'formed' only sides the polygon meets)."""
    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    families = [f for f in FAMILY_TABLE if f.by_default and f.n_min <= min(n_max, f.n_max)]
    if not families:
        raise ValueError(f"n_max must be at least 2 for any family to apply, got {n_max}")
    rng = np.random.default_rng([CASES_STREAM, seed & SEED_MASK])
    queues: dict[str, list[int]] = {f.name: [] for f in families}
    cases: list[Case] = []
    for index in range(count):
        fam = families[index % len(families)]
        queue = queues[fam.name]
        if not queue:
            sizes = np.arange(fam.n_min, min(n_max, fam.n_max) + 1)
            queue.extend(int(v) for v in rng.permutation(sizes))
        n = queue.pop()
        case_seed = int(rng.integers(0, 2**31))
        sides: Sequence[float] = SIDES
        if fam.name == "formed":  # keep it formed: a must not exceed the polygon's side
            side = min_separation(adversarial_start(fam.name, n, case_seed))
            sides = [s for s in SIDES if s <= side + 1e-9]
        cases.append(Case(fam.name, n, case_seed, float(sides[int(rng.integers(len(sides)))])))
    return cases


__all__ = [
    "DEFAULT_FAMILIES",
    "DESCRIPTIONS",
    "FAMILIES",
    "FAMILY_TABLE",
    "SIDES",
    "AdversarialStart",
    "Case",
    "Family",
    "adversarial_cases",
    "adversarial_start",
    "build_adversarial",
    "family_range",
]
