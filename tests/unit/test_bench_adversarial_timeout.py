"""bench/bench_adversarial.py's --run-timeout ends a run whose time runs out inside a robot's
compute as a timeout: the engine must not take the alarm for the algorithm's failure and go on."""

from __future__ import annotations

import functools
import importlib.util
import sys
import time
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from fatswarm.deploy.scenarios.adversarial import FAMILIES, Case

BENCH = Path(__file__).resolve().parents[2] / "bench"


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    sys.path.insert(0, str(BENCH))  # it imports bench_core as a sibling
    try:
        spec = importlib.util.spec_from_file_location(
            "bench_adversarial", BENCH / "bench_adversarial.py"
        )
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules["bench_adversarial"] = module
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(BENCH))
    return module


def _endless(view: Any, params: Any) -> Any:
    """A compute that would take 60 s: the run's time limit falls inside it. (Before the fix,
    the engine took the alarm for this compute's failure and the run went on without a limit;
    the suite's own timeout ended the test.)"""
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:
        pass
    raise AssertionError("the time limit never fell")


def test_a_run_whose_time_runs_out_inside_a_compute_is_an_error_of_its_time_limit(
    bench: ModuleType, monkeypatch: pytest.MonkeyPatch
) -> None:
    slow = functools.partial(bench.run_lockstep, compute=_endless)
    monkeypatch.setattr(bench, "run_lockstep", slow)
    t0 = time.monotonic()
    outcome = bench.run_one((Case(FAMILIES[0], 4, 0, 4.0), "fsync", 0.3))
    assert outcome.status == "error"
    assert outcome.error.startswith("RunTimeout: the run took longer than 0.3 s")
    assert time.monotonic() - t0 < 30.0  # one compute cut short, not one compute per robot
