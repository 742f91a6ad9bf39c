"""The records of a fixed matrix of runs, hashed: code that moves must leave each byte for byte.

Runs the installed `fatswarm` command (so the same script measures any version) over a fixed set of
configurations: every scheduler and async policy, non-rigid moves, crashes, the three algorithms,
lock step and networked, a resumed run and a sweep. Writes each record under OUT and prints one
line per configuration; `--save MANIFEST` keeps the hashes, `--compare MANIFEST` checks them.

    python bench/record_matrix.py /tmp/matrix --save before.json
    python bench/record_matrix.py /tmp/matrix --compare before.json   # exit 1 on any difference

Use the same folder both times: a header keeps the absolute path of an --init or --schedule file.
"""

from __future__ import annotations

import argparse
import csv as csvlib
import hashlib
import json
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Config:
    """One run of the matrix: its name and its `fatswarm run` flags (less --record)."""

    name: str
    flags: tuple[str, ...]


def _configs() -> list[Config]:
    configs: list[Config] = []

    def add(name: str, *flags: str) -> None:
        configs.append(Config(name, flags))

    lock = ("--lockstep",)
    for sched in ("fsync", "ssync", "centralized", "async", "async-slowest"):
        for seed, n in ((1, 6), (2, 9)):
            add(
                f"ls-uc-{sched}-s{seed}",
                *lock,
                "-n",
                str(n),
                "--seed",
                str(seed),
                "--scheduler",
                sched,
            )
    for start in ("dense", "spread", "loose", "clumped"):
        add(f"ls-uc-ssync-{start}", *lock, "-n", "7", "--seed", "4", "--start", start)
    for sched in ("fsync", "ssync", "async", "async-slowest"):
        add(
            f"ls-stepped-{sched}",
            *lock,
            "-n",
            "7",
            "--seed",
            "5",
            "--scheduler",
            sched,
            "--algorithm",
            "uniform-circle-stepped",
        )
    for sched in ("fsync", "ssync", "centralized", "async"):
        add(
            f"ls-gathering-{sched}",
            *lock,
            "-n",
            "6",
            "--seed",
            "6",
            "--scheduler",
            sched,
            "--algorithm",
            "gathering",
        )
    for sched in ("fsync", "ssync", "centralized", "async"):
        add(
            f"ls-nonrigid-{sched}",
            *lock,
            "-n",
            "7",
            "--seed",
            "7",
            "--scheduler",
            sched,
            "--non-rigid",
            "1",
        )
    for sched in ("fsync", "ssync", "centralized", "async-slowest"):
        add(
            f"ls-crash-{sched}",
            *lock,
            "-n",
            "8",
            "--seed",
            "8",
            "--scheduler",
            sched,
            "--crash",
            "2",
        )
    add(
        "ls-nonrigid-crash-ssync",
        *lock,
        "-n",
        "8",
        "--seed",
        "9",
        "--non-rigid",
        "0.5",
        "--crash",
        "1",
    )
    add("ls-fairness-ssync", *lock, "-n", "6", "--seed", "10", "--fairness", "3")
    add("ls-maxrounds-ssync", *lock, "-n", "8", "--seed", "11", "--max-rounds", "7")
    add("ls-param-a", *lock, "-n", "6", "--seed", "12", "-a", "5.5")
    add("ls-init-ssync", *lock, "--init", "@init", "--seed", "13")
    add(
        "ls-scripted",
        *lock,
        "--scheduler",
        "scripted",
        "--schedule",
        "@ls-uc-ssync-s1",
        "-n",
        "6",
        "--seed",
        "1",
    )
    net = ("--no-dashboard", "--pace", "0")
    for sched in ("fsync", "ssync", "centralized", "async"):
        add(f"net-uc-{sched}", *net, "-n", "6", "--seed", "1", "--scheduler", sched)
    add("net-nonrigid-ssync", *net, "-n", "6", "--seed", "7", "--non-rigid", "1")
    add("net-crash-ssync", *net, "-n", "6", "--seed", "8", "--crash", "1")
    add("net-gathering-ssync", *net, "-n", "5", "--seed", "6", "--algorithm", "gathering")
    add(
        "net-stepped-async",
        *net,
        "-n",
        "5",
        "--seed",
        "5",
        "--scheduler",
        "async",
        "--algorithm",
        "uniform-circle-stepped",
    )
    return configs


def _resolve(flags: tuple[str, ...], out: Path) -> list[str]:
    """Flags with `@name` standing for another configuration's record or a prepared file."""
    resolved = []
    for flag in flags:
        if flag == "@init":
            init = out / "init.json"
            init.write_text(
                json.dumps(
                    {
                        "positions": [[0, 0], [2.0, 0], [4.5, 0.5], [1, 3], [-3, 1], [0.5, -2.5]],
                        "a": 4.0,
                    }
                )
            )
            resolved.append(init.name)
        elif flag.startswith("@"):
            resolved.append(f"{flag[1:]}.jsonl")
        else:
            resolved.append(flag)
    return resolved


def _fatswarm() -> list[str]:
    exe = shutil.which("fatswarm", path=str(Path(sys.executable).parent))
    return [exe] if exe else [sys.executable, "-m", "fatswarm.deploy.cli"]


def _run(argv: list[str], out: Path) -> int:
    """`fatswarm ARGV` run in `out`, so that the command a record's header keeps is the same in
    every folder (paths relative to it)."""
    done = subprocess.run(
        [*_fatswarm(), *argv], capture_output=True, text=True, timeout=600, check=False, cwd=out
    )
    if done.returncode not in (0, 1, 3):
        sys.exit(f"record_matrix: {' '.join(argv)} exited {done.returncode}: {done.stderr.strip()}")
    return done.returncode


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def run_matrix(out: Path) -> dict[str, str]:
    """Every configuration's record hash (and the exit code), keyed by name."""
    out = out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    hashes: dict[str, str] = {}
    for config in _configs():
        record = out / f"{config.name}.jsonl"
        record.unlink(missing_ok=True)
        code = _run(["run", *_resolve(config.flags, out), "-q", "--record", record.name], out)
        if not record.exists():
            sys.exit(f"record_matrix: {config.name} wrote no record (exit {code})")
        hashes[config.name] = f"{_digest(record)} exit {code}"
        print(f"{config.name:28} {hashes[config.name]}", flush=True)
    # A resumed run: the ssync record cut after 5 rounds, continued.
    whole = (out / "ls-uc-ssync-s2.jsonl").read_text().splitlines(keepends=True)
    part = out / "ls-resumed-ssync.jsonl"
    part.write_text("".join(whole[:6]))
    code = _run(["run", "--lockstep", "--record", part.name, "--resume", "-q"], out)
    hashes["ls-resumed-ssync"] = f"{_digest(part)} exit {code}"
    print(f"{'ls-resumed-ssync':28} {hashes['ls-resumed-ssync']}", flush=True)
    # A sweep's CSV, less its wall-clock column.
    csv = out / "sweep.csv"
    csv.unlink(missing_ok=True)
    _run(
        [
            "sweep",
            "-n",
            "5,7",
            "--seeds",
            "2",
            "--scheduler",
            "ssync,fsync,async",
            "--crash",
            "0,1",
            "--jobs",
            "1",
            "--out",
            csv.name,
            "-q",
        ],
        out,
    )
    table = list(csvlib.reader(csv.read_text().splitlines()))
    if "wall_s" not in table[0]:
        sys.exit("record_matrix: the sweep's table has no wall_s column")
    # wall_s differs from run to run; min_gap, failures and first_failure, columns added since,
    # are left out so that a manifest saved before them still compares (their cells are checked
    # by tests/unit/test_min_gap.py and tests/unit/test_compute_failures.py)
    added = ("wall_s", "min_gap", "failures", "first_failure")
    keep = [i for i, column in enumerate(table[0]) if column not in added]
    rows = [[row[i] for i in keep] for row in table]
    hashes["sweep"] = hashlib.sha256(json.dumps(rows).encode()).hexdigest()
    print(f"{'sweep':28} {hashes['sweep']}", flush=True)
    return hashes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="folder for the records")
    parser.add_argument("--save", type=Path, help="write the hashes to this JSON file")
    parser.add_argument("--compare", type=Path, help="compare with the hashes of this JSON file")
    args = parser.parse_args(argv)
    hashes = run_matrix(args.out)
    print(f"{len(hashes)} records")
    if args.save:
        args.save.write_text(json.dumps(hashes, indent=1) + "\n")
    if args.compare:
        before = json.loads(args.compare.read_text())
        differ = sorted(k for k in before.keys() | hashes.keys() if before.get(k) != hashes.get(k))
        print(
            f"{len(hashes) - len(differ)} of {len(before)} identical"
            + (f"; differ: {', '.join(differ)}" if differ else "")
        )
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
