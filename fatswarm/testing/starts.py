"""The views checked: every robot's Look at starts of `fatswarm hunt`'s start families that the
algorithm accepts, drawn from the seed (a luminous robot's with colours too)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np

from fatswarm.deploy.engine.config import DEFAULT_A, input_errors
from fatswarm.deploy.hunt.search import start_families
from fatswarm.deploy.scenarios.adversarial import FAMILIES, adversarial_start, family_range
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.domain.lights import Glance
from fatswarm.domain.path import Points
from fatswarm.domain.seam import Configured
from fatswarm.testing.look import Look
from fatswarm.testing.subject import Subject
from fatswarm.world.physics import validate_configuration

STARTS_PER_FAMILY: Final = 2  # starts each family gives the checks of views
SHUFFLE_STREAM: Final = 0x7E57  # the views' shuffles, apart from every other seeded stream


def _start(setting: Configured, family: str, n: int, seed: int) -> Points:
    """A start of the family (`fatswarm hunt`'s), random kinds at the algorithm's scale `a`."""
    if family in FAMILIES:
        return adversarial_start(family, n, seed)
    scale = setting.values.get("a", DEFAULT_A)
    assert isinstance(scale, (int, float))
    return random_start(n, seed, family, float(scale))


def _family_sizes(family: str, sizes: Sequence[int]) -> list[int]:
    lo, hi = family_range(family) if family in FAMILIES else (2, max(sizes))
    return [n for n in sizes if max(lo, 2) <= n <= hi]


def _starts(subject: Subject, seed: int, sizes: Sequence[int]) -> list[Points]:
    """STARTS_PER_FAMILY starts of every start family, n drawn from `sizes`, that the algorithm
    accepts; raises ValueError if it accepts none."""
    rng = np.random.default_rng([SHUFFLE_STREAM, seed & 0xFFFFFFFF])
    starts: list[Points] = []
    refusals: list[str] = []
    for family in start_families():
        usable = _family_sizes(family, sizes)
        for _ in range(STARTS_PER_FAMILY if usable else 0):
            n = usable[int(rng.integers(len(usable)))]
            start_seed = int(rng.integers(2**31))
            setting = subject.setting(n)
            if setting is None:
                refusals.append(f"n = {n}: {subject.refusals[n]}")
                continue
            try:
                positions = validate_configuration(_start(setting, family, n, start_seed))
                setting.check_start(positions)
            except input_errors() as exc:
                refusals.append(f"n = {n}, {family}: {exc}")
                continue
            starts.append(positions)
    if not starts:
        raise ValueError(
            f"algorithm {subject.name} refuses every start drawn with n in {list(sizes)} "
            f"({refusals[0] if refusals else 'none'}); pass sizes= with the n it supports"
        )
    return starts


def draw_looks(subject: Subject, seed: int, sizes: Sequence[int]) -> list[Look]:
    """Every robot's look at each start, in the paper's frame; a luminous robot's twice: at the
    start (every colour the first) and with colours drawn from the seed."""
    rng = np.random.default_rng([SHUFFLE_STREAM, seed & 0xFFFFFFFF, 1])
    looks: list[Look] = []
    for positions in _starts(subject, seed, sizes):
        for robot in range(len(positions)):
            view = np.delete(positions, robot, axis=0) - positions[robot]
            if not subject.colours:
                looks.append(Look(view))
                continue
            first, k = subject.colours[0], len(view)
            drawn = [
                subject.colours[int(i)] for i in rng.integers(len(subject.colours), size=k + 1)
            ]
            looks.append(Look(view, Glance(first, (first,) * k)))
            looks.append(Look(view, Glance(drawn[0], tuple(drawn[1:]))))
    return looks
