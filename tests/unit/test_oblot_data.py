"""The oblot-sim peer's recorded runs (tests/data/oblot/) keep the schema their README declares."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

DATA = Path(__file__).resolve().parents[1] / "data" / "oblot"
ALGORITHMS = ("GoToCoG", "GoToRightMost", "GatheringWithMultiplicity", "MoveAlongSEC")
COMMIT = "db477c8d65df30180a08d8e4bd515ce88f72aada"
SCHEDULERS = {"FSYNC", "SSYNC"}
MOVEMENTS = {"rigid", "non-rigid"}
STOPS = {"goal", "cap", "error"}


def _load(name: str) -> dict[str, Any]:
    with (DATA / name).open(encoding="utf-8") as handle:
        doc: dict[str, Any] = json.load(handle)
    return doc


def _is_point(p: Any) -> bool:
    return (
        isinstance(p, list)
        and len(p) == 2
        and all(v is None or (isinstance(v, float) and math.isfinite(v)) for v in p)
    )


def _is_frame(f: Any) -> bool:
    return (
        isinstance(f, list)
        and len(f) == 3
        and 0.5 <= f[0] < 2.5
        and -math.pi <= f[1] < math.pi
        and isinstance(f[2], bool)
    )


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_case_file_names_the_peer_and_holds_at_least_20_cases(algorithm: str) -> None:
    doc = _load(f"{algorithm}.json")
    assert doc["peer"] == {"repository": "github:werner291/oblot-sim", "commit": COMMIT}
    assert doc["algorithm"] == algorithm and doc["schema"] == 1
    assert len(doc["cases"]) >= 20
    sizes = {len(case["start"]) for case in doc["cases"]}
    assert min(sizes) == 2 and max(sizes) == 64


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_every_case_is_well_formed(algorithm: str) -> None:
    for case in _load(f"{algorithm}.json")["cases"]:
        n = len(case["start"])
        assert case["scheduler"] in SCHEDULERS and case["movement"] in MOVEMENTS
        assert case["stopped"] in STOPS
        assert (case["error"] is not None) == (case["stopped"] == "error"), case["id"]
        assert all(_is_point(p) for p in case["start"] + case["final_positions"])
        assert len(case["final_positions"]) == n
        assert case["frames_mode"] in {"shared", "per-robot"}
        assert len(case["frames"]) == (1 if case["frames_mode"] == "shared" else n)
        assert all(_is_frame(f) for f in case["frames"])
        assert 0 <= case["rounds_run"] <= case["cap"]
        assert len(case["rounds"]) == min(case["rounds_run"], case["stored_rounds"])
        if case["goal_round"] is not None:
            assert 1 <= case["goal_round"] <= case["rounds_run"]
        check = case["sec_seed_check"]
        assert 0 <= check["agreeing_stored_rounds"] <= len(case["rounds"])
        for k, rnd in enumerate(case["rounds"], start=1):
            assert rnd["round"] == k
            assert len(rnd["positions"]) == n and all(_is_point(p) for p in rnd["positions"])
            active = rnd["active"]
            assert active == sorted(set(active)) and all(0 <= i < n for i in active)
            if case["scheduler"] == "FSYNC":
                assert active == list(range(n))
            else:
                assert 1 <= len(active) <= max(1, n - 1)
            assert rnd["move_time"] >= 1.0 - 1e-9  # a difference of two event times


def test_fsync_rigid_go_to_cog_gathers_in_one_round_as_recorded() -> None:
    for case in _load("GoToCoG.json")["cases"]:
        if case["scheduler"] == "FSYNC" and case["movement"] == "rigid":
            assert case["goal_round"] == 1, case["id"]
            xs = [p[0] for p in case["start"]]
            ys = [p[1] for p in case["start"]]
            centre = (math.fsum(xs) / len(xs), math.fsum(ys) / len(ys))
            for p in case["rounds"][0]["positions"]:
                assert math.dist(p, centre) <= 1e-12 * max(1.0, max(map(abs, xs + ys)))


def test_table_covers_20_seeds_per_n_for_every_algorithm() -> None:
    doc = _load("table.json")
    assert doc["peer"]["commit"] == COMMIT
    starts = doc["starts"]
    by_n: dict[int, int] = {}
    for st in starts:
        assert len(st["start"]) == st["n"] and _is_frame(st["frame"])
        by_n[st["n"]] = by_n.get(st["n"], 0) + 1
    assert min(by_n) == 2 and max(by_n) == 64 and set(by_n.values()) == {20}
    assert set(doc["results"]) == set(ALGORITHMS)
    for per_setting in doc["results"].values():
        assert set(per_setting) == {f"{s} {m}" for s in SCHEDULERS for m in MOVEMENTS}
        for runs in per_setting.values():
            assert len(runs) == len(starts)
            for run in runs:
                assert run["stopped"] in STOPS
                assert (run["goal_round"] is not None) == (run["stopped"] == "goal")
                assert run["rounds_run"] <= doc["cap"]
