"""Records of many adversarial lock-step runs, hashed: engine code that moves must leave each
byte for byte (a wider net than record_matrix.py's 46 runs, in process, without the CLI).

    python bench/record_digest.py --save before.json            # in the old checkout
    python bench/record_digest.py --compare before.json         # exit 1 on any difference
    PYTHONPATH=/old/tree python /new/tree/bench/record_digest.py --save old.json   # any checkout

Case i is adversarial case i of `adversarial_cases(COUNT, 0, N_MAX)` (every default family, n up to
N_MAX) run under scheduler i mod 5 (fsync, ssync, centralized, async, async-slowest), seed i; every
7th non-rigid (delta 0.5), every 11th with one crash, every 13th with `gathering`, every 17th with
the paper's algorithm under `--record-views`. Runs are capped at --max-rounds. Asserts nothing.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import multiprocessing as mp
import os
import sys
import tempfile
from collections.abc import Sequence
from typing import Any

SCHEDULERS = ("fsync", "ssync", "centralized", "async", "async-slowest")


def case_kwargs(index: int, count: int, n_max: int) -> tuple[str, dict[str, Any]]:
    """Case `index`'s label and its `fatswarm.run` keywords (less the record)."""
    from fatswarm.deploy.scenarios.adversarial import adversarial_cases

    case = adversarial_cases(count, 0, n_max)[index]
    kwargs: dict[str, Any] = {
        "positions": case.start(),
        "params": {"a": case.a},
        "seed": index,
        "scheduler": SCHEDULERS[index % len(SCHEDULERS)],
    }
    if index % 7 == 0:
        kwargs["non_rigid"] = 0.5
    if index % 11 == 0 and case.n > 2:
        kwargs["crash"] = 1
    if index % 13 == 0:
        kwargs["algorithm"], kwargs["params"] = "gathering", None
    elif index % 17 == 0:
        kwargs["record_views"] = True
    label = f"{index}:{case.family}:n{case.n}:{kwargs['scheduler']}"
    return label, kwargs


def digest(job: tuple[int, int, int, int]) -> tuple[str, str]:
    """(label, sha256 of the record or the error) of one case."""
    import fatswarm

    index, count, n_max, max_rounds = job
    label, kwargs = case_kwargs(index, count, n_max)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "r.jsonl")
        try:
            fatswarm.run(record=path, max_rounds=max_rounds, **kwargs)
        except Exception as exc:  # a finding, hashed like a record: the same in both trees
            return label, f"error {type(exc).__name__}: {exc}"
        with open(path, "rb") as f:
            return label, hashlib.sha256(f.read()).hexdigest()


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--count", type=int, default=1200, help="cases (default 1200)")
    p.add_argument("--n-max", type=int, default=24, help="largest n (default 24)")
    p.add_argument("--max-rounds", type=int, default=400, help="round cap (default 400)")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="worker processes")
    p.add_argument("--save", metavar="FILE", help="write the hashes to FILE (JSON)")
    p.add_argument(
        "--compare", metavar="FILE", help="compare with FILE's hashes; exit 1 if any differ"
    )
    args = p.parse_args(argv)
    jobs = [(i, args.count, args.n_max, args.max_rounds) for i in range(args.count)]
    hashes: dict[str, str] = {}
    with mp.get_context("spawn").Pool(args.jobs) as pool:
        for done, (label, value) in enumerate(pool.imap(digest, jobs, chunksize=4), start=1):
            hashes[label] = value
            if done % 100 == 0 or done == len(jobs):
                print(f"{done}/{len(jobs)} runs", file=sys.stderr, flush=True)
    import fatswarm

    print(f"{len(hashes)} records of {os.path.dirname(fatswarm.__file__)}")
    if args.save:
        with open(args.save, "w") as f:
            json.dump(hashes, f, indent=0)
    if args.compare:
        with open(args.compare) as f:
            before = json.load(f)
        differ = [k for k in before.keys() | hashes.keys() if before.get(k) != hashes.get(k)]
        print(f"{len(hashes) - len(differ)} of {len(before)} identical")
        for label in sorted(differ)[:10]:
            print(f"  differs: {label}")
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
