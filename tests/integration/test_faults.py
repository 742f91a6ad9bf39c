"""The fault campaign, once per role (slow): kill -9 at a random moment and restart; the run still
forms, referee-clean, no round lost or duplicated, no process left behind."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def _campaign() -> ModuleType:
    path = Path(__file__).resolve().parents[2] / "bench" / "bench_faults.py"
    spec = importlib.util.spec_from_file_location("bench_faults", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["bench_faults"] = module
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize(
    "role",
    ["agent", "agents-fork", "agents-exec", "world", "coordinator", "router", "world-router"],
)
@pytest.mark.parametrize("fault", ["kill", "stop"])
def test_a_fault_of_any_role_leaves_a_formed_clean_run_and_nothing_behind(
    role: str, fault: str
) -> None:
    t = _campaign().trial(role, fault, seed=7, stop_s=2.0)
    assert not t.error, t.error
    assert (t.formed, t.clean, t.lost_or_duplicated, t.left) == (True, True, 0, 0), t
