"""bench/bench_bodies.py on one tiny case (GoToCoG, n = 2, seed 0, in this process), so the script
behind docs/results.md's "What bodies cost" cannot rot."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "bench" / "bench_bodies.py"


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    spec = importlib.util.spec_from_file_location("bench_bodies", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["bench_bodies"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def table(bench: ModuleType) -> dict[str, Any]:
    loaded: dict[str, Any] = bench.load_table()
    return loaded


def _start(table: dict[str, Any], n: int, seed: int) -> dict[str, Any]:
    return next(st for st in table["starts"] if st["n"] == n and st["seed"] == seed)


def test_the_scaled_start_puts_every_pair_of_centres_at_least_2_apart(
    bench: ModuleType, table: dict[str, Any]
) -> None:
    for st in table["starts"]:
        start, factor = bench.scaled_start(st)
        assert bench.min_distance(start) >= 2.0
        assert factor >= 1.0 and (factor == 1.0 or bench.min_distance(start / 2.0) < 2.0)


def test_go_to_cog_gathers_points_in_round_1_and_fat_bodies_collide_and_stall(
    bench: ModuleType, table: dict[str, Any]
) -> None:
    entry = _start(table, 2, 0)
    points = bench.measure("GoToCoG", entry, "points", 10)
    fat = bench.measure("GoToCoG", entry, "fat", 10)
    assert (points["goal_round"], points["status"], points["collisions"]) == (1, "formed", 0)
    assert not points["outside"]  # inside the port's assumptions
    assert fat["goal_round"] is None and fat["status"] == "stalled"
    assert fat["collisions"] > 0 and fat["first_contact"] == 1
    assert abs(fat["final_min_gap"]) < 1e-6  # the two discs touch
    assert "fat" in fat["outside"]
    assert points["factor"] == fat["factor"]


def test_the_tables_show_the_peer_beside_the_world_and_the_goal_fat_bodies_lose(
    bench: ModuleType, table: dict[str, Any]
) -> None:
    entry = _start(table, 2, 0)
    tasks = [("GoToCoG", entry, bodies, 10) for bodies in ("points", "fat", "replay")]
    runs = bench.measure_all(tasks, workers=1)
    text = bench.tables(runs, table, ["GoToCoG"], [2], 10)
    assert "| fatswarm (world) | 1 (1–1) 1/1 |" in text
    assert "| fatswarm port, no world | 1 (1–1) 1/1 |" in text
    assert "| oblot-sim | 1 (1–1) 1/1 |" in text
    assert "goal lost in 1" in text
