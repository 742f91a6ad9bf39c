"""Records with numpy's optional CPU paths on and off: a record must not depend on the CPU it was
made on (issue 30, item 3).

numpy picks a kernel for `arctan2`, `arccos`, `arcsin`... by the CPU it runs on (AVX-512, AVX2 or
the SSE baseline), and those kernels differ in the last bit of many values. Records are compared
across hosts, so every decision the plan, the physics and the record take must not hang on those
bits. This script runs the same lock-step runs twice, in two fresh processes, one with numpy's
optional paths as the CPU allows and one with them turned off (`NPY_DISABLE_CPU_FEATURES`), and
compares the records' hashes.

    python bench/cpu_paths.py                  # the model cases and 300 adversarial cases
    python bench/cpu_paths.py --count 1200     # a wider net (bench/record_digest.py's cases)

Exit 0 when every record is the same, 1 when one differs (they are named), 2 when this CPU has no
optional path whose bits differ (nothing to compare: the check cannot fail here), 3 when a model
case did not run at all.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

# numpy 2's dispatch targets above the x86-64-v2 baseline; unknown names are ignored by numpy
OPTIONAL_PATHS = "X86_V3 X86_V4 AVX512_ICL AVX512_SPR AVX512_SKX AVX2 FMA3 AVX512F"
ENV_KEY = "NPY_DISABLE_CPU_FEATURES"

# A part of bench/record_matrix.py's lock-step configurations, plus the model family's axes,
# as `fatswarm.run` keywords.
MODEL_CASES: dict[str, dict[str, Any]] = {
    **{
        f"uc-{s}": {"n": 9, "seed": 2, "scheduler": s}
        for s in ("fsync", "ssync", "centralized", "async", "async-slowest")
    },
    "uc-dense": {"n": 7, "seed": 4, "start": "dense"},
    "stepped-async": {
        "n": 7,
        "seed": 5,
        "scheduler": "async",
        "algorithm": "uniform-circle-stepped",
    },
    "gathering-async": {"n": 6, "seed": 6, "scheduler": "async", "algorithm": "gathering"},
    "nonrigid-ssync": {"n": 7, "seed": 7, "non_rigid": 1.0},
    "crash-slowest": {"n": 8, "seed": 8, "scheduler": "async-slowest", "crash": 2},
    "lights-async": {
        "n": 7,
        "seed": 3,
        "scheduler": "async",
        "algorithm": "uniform-circle-lights",
        "lights": "full",
    },
    "opaque-views": {
        "n": 8,
        "seed": 1,
        "algorithm": "gathering",
        "visibility": "opaque",
        "record_views": True,
    },
    "sight-frames": {
        "n": 8,
        "seed": 9,
        "algorithm": "gathering",
        "sight": 6.0,
        "frames": "disoriented",
        "frame_change": "every-look",
    },
    "noise": {"n": 6, "seed": 11, "noise": 0.02},
    "cog-points": {"n": 8, "seed": 12, "algorithm": "oblot-go-to-cog", "bodies": "points"},
}


def probe() -> str:
    """A hash of numpy's inverse trigonometry on a fixed sample: it differs between two processes
    exactly when their kernels differ."""
    import numpy as np

    rng = np.random.default_rng(0)
    y, x = rng.normal(size=(2, 100_000))
    h = hashlib.sha256(np.arctan2(y, x).tobytes())
    h.update(np.arccos(np.clip(y, -1, 1)).tobytes())
    return h.hexdigest()


def _model_case(name: str) -> tuple[str, dict[str, Any]]:
    return name, dict(MODEL_CASES[name])


def _digest(label: str, kwargs: dict[str, Any], max_rounds: int) -> str:
    import fatswarm

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "r.jsonl")
        try:
            fatswarm.run(record=path, max_rounds=max_rounds, **kwargs)
        except Exception as exc:  # a finding, hashed like a record: the same on both paths
            return f"error {type(exc).__name__}: {exc}"
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def hashes(count: int, n_max: int, max_rounds: int) -> dict[str, str]:
    """Every case's record hash in this process (with this process's numpy paths)."""
    sys.path.insert(0, str(Path(__file__).parent))
    from record_digest import case_kwargs

    out = {"probe": probe()}
    for name in MODEL_CASES:
        label, kwargs = _model_case(name)
        out[label] = _digest(label, kwargs, max_rounds)
    for index in range(count):
        label, kwargs = case_kwargs(index, count, n_max)
        out[label] = _digest(label, kwargs, max_rounds)
    return out


def _child(args: argparse.Namespace, disable: bool) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != ENV_KEY}
    if disable:
        env[ENV_KEY] = OPTIONAL_PATHS
    argv = [sys.executable, __file__, "--child", "--count", str(args.count)]
    argv += ["--n-max", str(args.n_max), "--max-rounds", str(args.max_rounds)]
    done = subprocess.run(argv, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        sys.exit(
            f"cpu_paths: the child ({ENV_KEY}={'set' if disable else 'unset'}) failed: "
            f"{done.stderr.strip().splitlines()[-1:]}"
        )
    result: dict[str, str] = json.loads(done.stdout)
    return result


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--count", type=int, default=300, help="adversarial cases (default 300)")
    p.add_argument("--n-max", type=int, default=24, help="largest n (default 24)")
    p.add_argument("--max-rounds", type=int, default=400, help="round cap (default 400)")
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.child:
        json.dump(hashes(args.count, args.n_max, args.max_rounds), sys.stdout)
        return 0
    on = _child(args, disable=False)
    off = _child(args, disable=True)
    if on.pop("probe") == off.pop("probe"):
        print(f"this CPU has no optional numpy path whose bits differ ({ENV_KEY} changes nothing)")
        return 2
    differ = sorted(k for k in on if on[k] != off.get(k))
    broken = sorted(name for name in MODEL_CASES if on[name].startswith("error"))
    if broken:  # a case that cannot run compares nothing
        print(f"cpu_paths: model cases that did not run: {', '.join(broken)}: {on[broken[0]]}")
        return 3
    print(f"numpy's arctan2/arccos bits differ with {ENV_KEY}={OPTIONAL_PATHS!r}")
    print(
        f"{len(on) - len(differ)} of {len(on)} records identical "
        f"({len(MODEL_CASES)} model cases, {args.count} adversarial cases)"
    )
    for label in differ:
        print(f"  differs: {label}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
