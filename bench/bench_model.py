"""What each robot-model axis costs (issue 19): Looks per second in lock step, and seconds of a
networked run, for the paper's model and each axis on its own. A script that prints figures.

    python bench/bench_model.py                 # lock step, n = 16 and 64, fsync
    python bench/bench_model.py --networked     # also a networked run per axis (n = 12)

Every lock-step run goes through `fatswarm.run` (start-up excluded); the algorithm is `gathering`
(every robot computes alone: the paper's algorithm shares one plan per round only in the paper's
model, so it would measure its planner, not the axis) and `tests/data/lit_spread.py` for lights.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import fatswarm

LIT = str(Path(__file__).resolve().parents[1] / "tests" / "data" / "lit_spread.py") + ":ALGORITHM"
AXES: dict[str, dict[str, object]] = {
    "paper model": {},
    "--sight 8": {"sight": 8.0},
    "--visibility opaque-centres": {"visibility": "opaque-centres"},
    "--visibility opaque": {"visibility": "opaque"},
    "--frames chirality": {"frames": "chirality"},
    "--frames disoriented --frame-change every-look": {
        "frames": "disoriented",
        "frame_change": "every-look",
    },
    "--record-views": {"record_views": True},
}
FLAGS = {
    "paper model": [],
    "--sight 8": ["--sight", "8"],
    "--visibility opaque-centres": ["--visibility", "opaque-centres"],
    "--visibility opaque": ["--visibility", "opaque"],
    "--frames chirality": ["--frames", "chirality"],
    "--frames disoriented --frame-change every-look": [
        "--frames",
        "disoriented",
        "--frame-change",
        "every-look",
    ],
    "--record-views": ["--record-views"],
}


def looks_per_second(n: int, algorithm: str, model: dict[str, object], rounds: int) -> float:
    """Looks per second of an fsync lock-step run of `rounds` rounds (best of 3)."""
    best = 0.0
    for _ in range(3):
        t0 = time.perf_counter()
        result = fatswarm.run(
            n,
            algorithm=algorithm,
            seed=1,
            start="spread",
            scheduler="fsync",
            max_rounds=rounds,
            **model,  # type: ignore[arg-type]
        )
        best = max(best, result.looks / (time.perf_counter() - t0))
    return best


def networked_seconds(flags: list[str], n: int) -> float:
    """Wall seconds of a networked `fatswarm run` of gathering, 30 fsync rounds."""
    with tempfile.TemporaryDirectory() as tmp:
        argv = [sys.executable, "-m", "fatswarm.deploy.cli", "run", "-n", str(n), "--seed", "1"]
        argv += ["--algorithm", "gathering", "--scheduler", "fsync", "--start", "spread"]
        argv += ["--max-rounds", "30", "-q", "--no-dashboard", "--record"]
        argv += [os.path.join(tmp, "r.jsonl"), *flags]
        t0 = time.perf_counter()
        subprocess.run(argv, check=False, capture_output=True, timeout=600)
        return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--networked", action="store_true", help="also time networked runs")
    parser.add_argument("--rounds", type=int, default=40, help="rounds per lock-step run")
    args = parser.parse_args()
    print(f"{'axis':48} {'n=16 Looks/s':>13} {'n=64 Looks/s':>13}")
    for label, model in AXES.items():
        rates = [looks_per_second(n, "gathering", model, args.rounds) for n in (16, 64)]
        print(f"{label:48} {rates[0]:13.0f} {rates[1]:13.0f}", flush=True)
    lit: dict[str, dict[str, object]] = {
        "lights full (lit-spread)": {},
        "lights internal": {"lights": "internal"},
    }
    for label, model in lit.items():
        rates = [looks_per_second(n, LIT, model, args.rounds) for n in (16, 64)]
        print(f"{label:48} {rates[0]:13.0f} {rates[1]:13.0f}", flush=True)
    if args.networked:
        print(f"\n{'axis (networked, gathering, n=12, 30 fsync rounds)':52} {'seconds':>8}")
        for label, flags in FLAGS.items():
            print(f"{label:52} {networked_seconds(flags, 12):8.2f}", flush=True)


if __name__ == "__main__":
    main()
