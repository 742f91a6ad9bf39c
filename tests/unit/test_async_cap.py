"""The async models' default cap grows with the run's distances: a start or target circle of radius
1e4 needs moves of about 2e4 while the other robots keep cycling; ordinary runs keep their cap."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fatswarm.deploy.engine.config import RunConfig
from fatswarm.deploy.engine.estimate import estimate_lockstep
from fatswarm.deploy.engine.lockstep import (
    ASYNC_REACH_UNIT,
    NON_RIGID_UNIT,
    default_max_rounds,
    run_reach,
)


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized", "async", "async-slowest"])
def test_an_ordinary_run_keeps_its_cap(scheduler: str) -> None:
    setup = RunConfig(n=8, seed=1, scheduler=scheduler).resolve()
    assert setup.max_rounds == default_max_rounds(8, scheduler)
    if scheduler.startswith("async"):
        assert setup.max_rounds == 40 * 8 * (8 + 10)


def test_the_async_cap_grows_with_the_reach_and_the_round_caps_do_not() -> None:
    assert default_max_rounds(8, "async", ASYNC_REACH_UNIT) == 5760
    assert default_max_rounds(8, "async", 1e4) == 5760 * 250
    assert default_max_rounds(8, "async-slowest", 100.0) == 5760 * 3
    assert default_max_rounds(8, "ssync", 1e4) == default_max_rounds(8, "ssync")


def test_a_target_radius_of_1e4_gives_the_cap_its_run_needs() -> None:
    a = 2e4 * math.sin(math.pi / 8) * 0.9995  # a target circle of radius about 1e4
    setup = RunConfig(n=8, seed=1, scheduler="async", params={"a": a}).resolve()
    reach = run_reach(setup.params, setup.initial)
    assert reach == pytest.approx(9995.0, rel=1e-3)
    # seed 1 formed in 302,547 ended cycles (measured), where the plain cap was 5,760
    assert setup.max_rounds == 5760 * 250 > 302_547
    forecast = estimate_lockstep(8, "async", setup.max_rounds, reach=reach)
    assert 100_000 < forecast.rounds < 1_000_000


def test_the_reach_is_the_larger_of_the_start_and_the_target_circle() -> None:
    setup = RunConfig(n=6, seed=1, scheduler="async").resolve()
    angle = 2 * np.pi * np.arange(6) / 6
    wide = np.column_stack([300 * np.cos(angle), 300 * np.sin(angle)])
    assert run_reach(setup.params, wide) == pytest.approx(300.0)
    assert run_reach(setup.params, setup.initial) == pytest.approx(4.0)  # the target: a = 4, n = 6


@pytest.mark.parametrize(
    ("delta", "factor"), [(None, 1), (1.0, 1), (0.5, 1), (0.25, 2), (0.1, 5), (0.05, 10)]
)
@pytest.mark.parametrize("scheduler", ["async", "async-slowest"])
def test_the_async_cap_grows_as_the_non_rigid_delta_shrinks(
    scheduler: str, delta: float | None, factor: int
) -> None:
    # --non-rigid 0.05 runs were cut by the plain cap while still progressing (all formed with 5
    # times it); from NON_RIGID_UNIT (0.5) up, caps and records stay as they were
    assert NON_RIGID_UNIT == 0.5
    assert default_max_rounds(8, scheduler, 0.0, delta) == 5760 * factor
    assert default_max_rounds(8, scheduler, 100.0, delta) == 5760 * 3 * factor
    setup = RunConfig(n=8, seed=1, scheduler=scheduler, non_rigid=delta).resolve()
    assert setup.max_rounds == 5760 * factor


@pytest.mark.parametrize("scheduler", ["fsync", "ssync", "centralized"])
def test_the_round_caps_do_not_grow_with_the_non_rigid_delta(scheduler: str) -> None:
    assert default_max_rounds(8, scheduler, 0.0, 0.05) == default_max_rounds(8, scheduler)
