"""bench/fault_campaign.py once per role under the paper's model (slow): killed with SIGKILL and
restarted, the run goes on with no round lost or duplicated, equal to the lock step where the
README promises it, nothing left running."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def _campaign() -> ModuleType:
    path = Path(__file__).resolve().parents[2] / "bench" / "fault_campaign.py"
    spec = importlib.util.spec_from_file_location("fault_campaign", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["fault_campaign"] = module
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("role", ["world", "coordinator", "router", "agent", "agents"])
def test_a_killed_and_restarted_role_loses_no_round_and_leaves_nothing(
    tmp_path: Path, role: str
) -> None:
    campaign = _campaign()
    lock = tmp_path / "lock.jsonl"
    campaign.lockstep(campaign.MODELS["ssync"], 2, lock)
    t = campaign.trial("ssync", role, 2, lock, deadline_s=90.0)
    assert not t.error, t.error
    assert (t.ended, t.lost_or_duplicated, t.left) == (True, 0, 0), t
    if role in campaign.PROMISED:
        assert t.equal, t
