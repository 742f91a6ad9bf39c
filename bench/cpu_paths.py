"""Records with numpy's optional CPU paths and OpenBLAS's kernels changed: a record must not
depend on the CPU it was made on (issue 30, item 3).

numpy picks a kernel for `arctan2`, `arccos`, `arcsin`... by the CPU it runs on (AVX-512, AVX2 or
the SSE baseline), and those kernels differ in the last bit of many values. Matrix products (`@`,
`np.dot`, `np.linalg.norm` of one vector) go to OpenBLAS, which picks its kernel by the CPU too:
the Haswell, SkylakeX and Zen kernels fuse multiply and add (FMA), Nehalem and Sandybridge do not,
and a 2-vector dot product differs in the last bit about one time in four. Records are compared
across hosts, so every decision the plan, the physics and the record take must not hang on those
bits. This script runs the same lock-step runs (and, with --plans, bench/plan_digest.py's --quick
collection) in fresh processes: one as the CPU allows, then one per variant: numpy's optional paths
turned off (`NPY_DISABLE_CPU_FEATURES`) and OpenBLAS forced to each kernel (`OPENBLAS_CORETYPE`),
and compares every record's hash (and every plan's digest) with the first.

    python bench/cpu_paths.py                  # the model cases and 300 adversarial cases
    python bench/cpu_paths.py --count 1200     # a wider net (bench/record_digest.py's cases)
    python bench/cpu_paths.py --plans          # also the paper's plan on ~2,800 configurations
    python bench/cpu_paths.py --variants numpy-off,Nehalem   # only these variants

Exit 0 when every record is the same, 1 when one differs (they are named), 2 when no variant
changes the bits of its probe on this CPU (nothing to compare: the check cannot fail here), 3 when
a model case did not run at all.
"""

from __future__ import annotations

import argparse
import contextlib
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
BLAS_KEY = "OPENBLAS_CORETYPE"
SHOWN_PLANS = 12  # differing plans named per variant (every differing record is)
# OpenBLAS kernels (x86-64): the first two without FMA, the others with it
CORETYPES = ("Nehalem", "Sandybridge", "Haswell", "SkylakeX", "Zen")
# Each variant: its name and the environment it sets (on top of the caller's, both keys removed)
VARIANTS: dict[str, dict[str, str]] = {
    "numpy-off": {ENV_KEY: OPTIONAL_PATHS},
    **{core: {BLAS_KEY: core} for core in CORETYPES},
}

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
    """A hash of numpy's inverse trigonometry and of OpenBLAS's 2-vector dot products on a fixed
    sample: it differs between two processes exactly when their kernels differ."""
    import numpy as np

    rng = np.random.default_rng(0)
    y, x = rng.normal(size=(2, 100_000))
    h = hashlib.sha256(np.arctan2(y, x).tobytes())
    h.update(np.arccos(np.clip(y, -1, 1)).tobytes())
    h.update((np.column_stack((x, y)) @ rng.normal(size=2)).tobytes())
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


def plan_digests() -> dict[str, str]:
    """bench/plan_digest.py's --quick collection in this process: every configuration's plan and
    compute digest (the collection itself comes from lock-step runs, so it may differ too)."""
    from plan_digest import collect, digests

    with contextlib.redirect_stdout(sys.stderr):
        configs = collect(quick=True, jobs=1)
        digs = digests(configs, jobs=1)
    return {f"plan {i}": d["plan"] + d["compute"] for i, d in zip(configs.ids, digs, strict=True)}


def hashes(count: int, n_max: int, max_rounds: int, plans: bool) -> dict[str, str]:
    """Every case's record hash in this process (with this process's numpy and BLAS kernels)."""
    sys.path.insert(0, str(Path(__file__).parent))
    from record_digest import case_kwargs

    out = {"probe": probe()}
    for name in MODEL_CASES:
        label, kwargs = _model_case(name)
        out[label] = _digest(label, kwargs, max_rounds)
    for index in range(count):
        label, kwargs = case_kwargs(index, count, n_max)
        out[label] = _digest(label, kwargs, max_rounds)
    if plans:
        out.update(plan_digests())
    return out


def _child(args: argparse.Namespace, variant: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in (ENV_KEY, BLAS_KEY)}
    env.update(VARIANTS.get(variant, {}))
    argv = [sys.executable, __file__, "--child", "--count", str(args.count)]
    argv += ["--n-max", str(args.n_max), "--max-rounds", str(args.max_rounds)]
    argv += ["--plans"] if args.plans else []
    done = subprocess.run(argv, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        sys.exit(
            f"cpu_paths: the child ({variant}) failed: {done.stderr.strip().splitlines()[-1:]}"
        )
    result: dict[str, str] = json.loads(done.stdout)
    return result


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--count", type=int, default=300, help="adversarial cases (default 300)")
    p.add_argument("--n-max", type=int, default=24, help="largest n (default 24)")
    p.add_argument("--max-rounds", type=int, default=400, help="round cap (default 400)")
    p.add_argument("--plans", action="store_true", help="also plan_digest.py's --quick plans")
    p.add_argument(
        "--variants",
        default=",".join(VARIANTS),
        help=f"comma-separated, of {', '.join(VARIANTS)} (default all)",
    )
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.child:
        json.dump(hashes(args.count, args.n_max, args.max_rounds, args.plans), sys.stdout)
        return 0
    variants = [v for v in args.variants.split(",") if v]
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        p.error(f"unknown variant {unknown[0]!r} (known: {', '.join(VARIANTS)})")
    base = _child(args, "default")
    base_probe = base.pop("probe")
    broken = sorted(name for name in MODEL_CASES if base[name].startswith("error"))
    if broken:  # a case that cannot run compares nothing
        print(f"cpu_paths: model cases that did not run: {', '.join(broken)}: {base[broken[0]]}")
        return 3
    records = sum(1 for k in base if not k.startswith("plan "))
    print(
        f"{records} records ({len(MODEL_CASES)} model cases, {args.count} adversarial cases)"
        + (f" and {len(base) - records} plans (--quick)" if args.plans else "")
    )
    compared = failed = 0
    what = " and plan" if args.plans else ""
    for variant in variants:
        other = _child(args, variant)
        setting = " ".join(f"{k}={v!r}" for k, v in VARIANTS[variant].items())
        if other.pop("probe") == base_probe:  # compared all the same, but it proves nothing
            setting += " (probe bits as the default's: the same kernels here)"
        else:
            compared += 1
        differ = sorted(k for k in base.keys() | other.keys() if base.get(k) != other.get(k))
        plans = sum(1 for k in differ if k.startswith("plan "))
        print(
            f"{variant}: {len(differ) - plans} records, {plans} plans differ with {setting}"
            if differ
            else f"{variant}: every record{what} identical with {setting}"
        )
        for label in [k for k in differ if not k.startswith("plan ")] + [
            k for k in differ if k.startswith("plan ")
        ][:SHOWN_PLANS]:
            print(f"  differs: {label}")
        failed += bool(differ)
    if not compared:
        print("no variant changes any kernel's bits on this CPU: nothing compared")
        return 2
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
