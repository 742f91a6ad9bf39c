"""Rounds to the goal against n for the four oblot-sim ports, beside oblot-sim's own count on the
same starts (tests/data/oblot/table.json: n = 2, 3, 4, 8, 16, 32, 64 by 20 seeds, one shared frame
per start, cap 500), without the world (fatswarm/agent/oblot_replay.py, `simulate`).

    python bench/bench_oblot.py                       # the four tables of docs/ports.md
    python bench/bench_oblot.py --algorithms GoToCoG --cap 100
    python bench/bench_oblot.py --json runs.json      # every run's outcome as well

FSYNC with rigid moves is the peer's very run (every robot active, no draw). FSYNC non-rigid and
SSYNC draw of the peer's kind, seeded here (`--seed`): a subset of 1 to n - 1 robots a round, one
distance in [1, 5) a round; not the peer's draws, which its table does not keep. Moves follow the
port's path at unit speed as fatswarm's world does (the peer's quirks are in docs/ports.md).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fatswarm.agent.oblot_replay import (
    PEER_ALGORITHMS,
    Mover,
    Outcome,
    PeerFrame,
    peer_goal,
    simulate,
)
from fatswarm.domain.registry import load_algorithm

TABLE = Path(__file__).resolve().parents[1] / "tests" / "data" / "oblot" / "table.json"
SETTINGS = ("FSYNC rigid", "FSYNC non-rigid", "SSYNC rigid", "SSYNC non-rigid")


def cell(outcomes: Sequence[dict[str, Any]]) -> str:
    """median (min-max) of the rounds to the goal, then k/N, errors and caps when not all."""
    rounds = [o["goal_round"] for o in outcomes if o["goal_round"] is not None]
    text = "–" if not rounds else f"{statistics.median(rounds):g} ({min(rounds)}–{max(rounds)})"
    errors = sum(1 for o in outcomes if o["stopped"] == "error")
    caps = sum(1 for o in outcomes if o["stopped"] == "cap")
    if len(rounds) < len(outcomes):
        text += f" {len(rounds)}/{len(outcomes)}"
        text += f", {errors} err" if errors else ""
        text += f", {caps} cap" if caps else ""
    return text


def run(
    peer: str, setting: str, starts: list[dict[str, Any]], seed: int, cap: int
) -> list[Outcome]:
    """The port of `peer` from every start under `setting`."""
    algorithm = load_algorithm(PEER_ALGORITHMS[peer])
    ssync, rigid = setting.startswith("SSYNC"), setting.endswith(" rigid")
    out = []
    for index, st in enumerate(starts):
        start = np.asarray(st["start"], dtype=np.float64)
        frame = PeerFrame(float(st["frame"][0]), float(st["frame"][1]), bool(st["frame"][2]))
        rng = np.random.default_rng([seed, index, SETTINGS.index(setting)])
        out.append(
            simulate(
                start,
                [frame] * len(start),
                algorithm,
                peer_goal(peer, start),
                ssync,
                rigid,
                rng,
                cap,
                Mover.FATSWARM,
            )
        )
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--algorithms", default=",".join(PEER_ALGORITHMS), help="peer class names")
    parser.add_argument("--settings", default=",".join(SETTINGS), help="e.g. 'FSYNC rigid'")
    parser.add_argument("--cap", type=int, default=500, help="rounds at most (the peer's: 500)")
    parser.add_argument("--seed", type=int, default=0, help="seeds the SSYNC and non-rigid draws")
    parser.add_argument("--json", type=Path, help="write every outcome here")
    args = parser.parse_args(argv)
    with open(TABLE, encoding="utf-8") as fh:
        table = json.load(fh)
    starts = table["starts"]
    sizes = sorted({st["n"] for st in starts})
    dump: dict[str, dict[str, list[dict[str, Any]]]] = {}
    began = time.perf_counter()
    for peer in args.algorithms.split(","):
        print(f"\n**{PEER_ALGORITHMS[peer]}** (fatswarm port) beside **{peer}** (oblot-sim)\n")
        print("| scheduler, movement | " + " | ".join(f"n={n}" for n in sizes) + " |")
        print("|---|" + "---|" * len(sizes))
        for setting in args.settings.split(","):
            ours = [
                {"goal_round": o.goal_round, "stopped": o.stopped, "error": o.error}
                for o in run(peer, setting, starts, args.seed, args.cap)
            ]
            theirs = table["results"][peer][setting]
            dump.setdefault(peer, {})[setting] = ours
            for who, outcomes in (("fatswarm", ours), ("oblot-sim", theirs)):
                cells = [
                    cell([o for o, st in zip(outcomes, starts, strict=True) if st["n"] == n])
                    for n in sizes
                ]
                print(f"| {setting}, {who} | " + " | ".join(cells) + " |")
            sys.stdout.flush()
    print(f"\n({time.perf_counter() - began:.0f} s)", file=sys.stderr)
    if args.json:
        args.json.write_text(json.dumps(dump, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
