"""What bodies cost: the four oblot-sim ports run through fatswarm's world (lock step, FSYNC, rigid,
both-axes frames) from the peer's own starts, first as point robots beside the peer's count on the
same starts (and beside the port alone, without the world: `--bodies replay`), then the same
starts with fat bodies (unit discs): goal, rounds, collisions, stalls, the cap.

    python bench/bench_bodies.py                      # both tables of docs/results.md (2 workers)
    python bench/bench_bodies.py --quick              # n = 2, 4, 8 by 3 seeds, in seconds
    python bench/bench_bodies.py --json runs.json     # every run's outcome as well
    python bench/bench_bodies.py --from-json runs.json    # the tables of saved runs, no run
    python bench/bench_bodies.py --workers 1          # in this process (no process started)

Starts: tests/data/oblot/table.json (uniform in [-10, 10]^2, one shared frame each), the ones of
n = 2, 4, 8, 16, 32, 64 by 20 seeds. Each start is mapped into its shared frame S (a both-axes
robot of fatswarm then sees what the peer's robot sees, as tests/unit/test_oblot_world.py does) and
scaled by the smallest power of two that puts every pair of centres at least 2 apart (unit discs
may not overlap at the start); the points run uses the same scaled start. The goal is the peer
table's (`oblot_replay.peer_goal` of the scaled start), judged on the world's positions after each
round: `goal` is the first round after which it holds. Progress goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

import fatswarm
from fatswarm.agent.oblot_replay import PEER_ALGORITHMS, Mover, PeerFrame, peer_goal, simulate
from fatswarm.domain.path import Points
from fatswarm.domain.registry import load_algorithm

TABLE = Path(__file__).resolve().parents[1] / "tests" / "data" / "oblot" / "table.json"
SIZES = (2, 4, 8, 16, 32, 64)
QUICK_SIZES = (2, 4, 8)
SETTING = "FSYNC rigid"  # the peer's own run: every robot active, moves to the end
DEFAULT_CAP = 40
BODIES = ("points", "fat", "replay")  # replay: the port without the world, same start
SETTLED = 1e-6
"""A round in which no centre shifts by more than this is a settled one: what is left is the
world's grid (2^-30) creeping a robot blocked in contact by a step a round."""
CREEP = 5  # a run that reaches the cap after this many settled rounds is stuck, creeping


def load_table() -> dict[str, Any]:
    with open(TABLE, encoding="utf-8") as fh:
        table: dict[str, Any] = json.load(fh)
    return table


def min_distance(points: Points) -> float:
    """The smallest distance between two centres (inf for one robot)."""
    pts = np.asarray(points, dtype=np.float64)
    diff = pts[:, np.newaxis, :] - pts[np.newaxis, :, :]
    dist = np.hypot(diff[..., 0], diff[..., 1])
    np.fill_diagonal(dist, np.inf)
    return float(dist.min())


def spread_of(points: Points) -> float:
    """The largest distance of a centre from the centre of gravity."""
    pts = np.asarray(points, dtype=np.float64)
    return float(np.hypot(*(pts - pts.mean(axis=0)).T).max())


def scaled_start(entry: dict[str, Any]) -> tuple[Points, float]:
    """The start mapped into its shared frame S, scaled by the smallest power of two (>= 1) that
    puts every pair of centres at least 2 apart; and that factor."""
    frame = PeerFrame(float(entry["frame"][0]), float(entry["frame"][1]), bool(entry["frame"][2]))
    mapped = np.asarray(
        [frame.to_local((float(x), float(y)), (0.0, 0.0)) for x, y in entry["start"]],
        dtype=np.float64,
    )
    factor, closest = 1.0, min_distance(mapped)
    while factor * closest < 2.0:
        factor *= 2.0  # exact in floating point: the points run and the fat run share the start
    return mapped * factor, factor


def measure(peer: str, entry: dict[str, Any], bodies: str, cap: int) -> dict[str, Any]:
    """One world run of the port of `peer` from `entry` (a start of table.json) with `bodies`,
    at most `cap` rounds: the goal's round (None if never), how the world ended it, collisions
    (contacts: a robot stopped by another), the round of the first, refusals, and the final
    min_gap (closest centres minus 2) and spread against the start's."""
    start, factor = scaled_start(entry)
    goal = peer_goal(peer, start)
    head = {
        "cap": cap,
        "peer": peer,
        "n": int(entry["n"]),
        "seed": int(entry["seed"]),
        "bodies": bodies,
        "factor": factor,
    }
    seen: dict[str, Any] = {
        "goal": None,
        "first_contact": None,
        "contact_rounds": 0,
        "last_move": 0,
        "before": start,
    }

    def watch(report: Any) -> None:
        k = int(report.entry.round)
        after = np.asarray(report.entry.positions, dtype=np.float64)
        if float(np.hypot(*(after - seen["before"]).T).max()) > SETTLED:
            seen["last_move"] = k
        seen["before"] = after
        if report.entry.collisions:
            seen["contact_rounds"] += 1
            if seen["first_contact"] is None:
                seen["first_contact"] = k
        if seen["goal"] is None and goal(after):
            seen["goal"] = k

    try:
        result = fatswarm.run(
            len(start),
            algorithm=PEER_ALGORITHMS[peer],
            positions=start,
            seed=int(entry["seed"]),
            scheduler="fsync",
            max_rounds=cap,
            on_round=watch,
            bodies=bodies,
            frames="both-axes",
        )
    except ValueError as exc:  # the port refuses the start (n = 2, odd n): no run
        return {**head, "goal_round": None, "status": "refused", "rounds": 0, "collisions": 0,
                "contact_rounds": 0, "first_contact": None, "last_move": 0, "failures": 0,
                "final_min_gap": min_distance(start) - 2.0, "spread_ratio": 1.0,
                "outside": None, "error": str(exc)}  # fmt: skip
    final = np.asarray(result.positions, dtype=np.float64)
    return {
        **head,
        "goal_round": seen["goal"],
        "status": str(result.status),
        "rounds": int(result.rounds),
        "collisions": int(result.collisions),
        "contact_rounds": seen["contact_rounds"],
        "first_contact": seen["first_contact"],
        "last_move": seen["last_move"],
        "failures": int(fatswarm.summary(result).get("failures") or 0),
        "final_min_gap": min_distance(final) - 2.0,
        "spread_ratio": spread_of(final) / spread_of(start),
        "outside": result.outside,
        "error": None,
    }


def measure_replay(peer: str, entry: dict[str, Any], cap: int) -> dict[str, Any]:
    """The port of `peer` from the same scaled start without the world
    (`oblot_replay.simulate`: exact arithmetic, no grid, point robots, FSYNC rigid, the frame
    the identity as the world's both-axes robots have): where it parts from the world's point
    run, the world's grid (2^-30) decided."""
    start, factor = scaled_start(entry)
    n = len(start)
    outcome = simulate(
        start,
        [PeerFrame(1.0, 0.0, False)] * n,
        load_algorithm(PEER_ALGORITHMS[peer]),
        peer_goal(peer, start),
        False,
        True,
        np.random.default_rng(int(entry["seed"])),
        cap,
        Mover.FATSWARM,
    )
    return {
        "cap": cap,
        "peer": peer,
        "n": n,
        "seed": int(entry["seed"]),
        "bodies": "replay",
        "factor": factor,
        "goal_round": outcome.goal_round,
        "status": outcome.stopped,
        "rounds": outcome.rounds_run,
        "error": outcome.error,
    }


def _measure_task(task: tuple[str, dict[str, Any], str, int]) -> dict[str, Any]:
    peer, entry, bodies, cap = task
    return measure_replay(peer, entry, cap) if bodies == "replay" else measure(*task)


def measure_all(
    tasks: Sequence[tuple[str, dict[str, Any], str, int]], workers: int
) -> list[dict[str, Any]]:
    """Every task's `measure`, in task order; `workers` > 1 runs them in a process pool (the only
    place this script starts processes)."""
    began, out = time.perf_counter(), []
    order = sorted(range(len(tasks)), key=lambda i: -int(tasks[i][1]["n"]))  # big runs first
    if workers > 1:
        import multiprocessing

        with multiprocessing.Pool(workers) as pool:
            done = pool.imap(_measure_task, [tasks[i] for i in order], chunksize=1)
            out = list(_progress(done, len(tasks), began))
    else:
        out = list(_progress((_measure_task(tasks[i]) for i in order), len(tasks), began))
    back = [{}] * len(tasks)  # type: list[dict[str, Any]]
    for i, res in zip(order, out, strict=True):
        back[i] = res
    return back


def _progress(runs: Iterable[dict[str, Any]], total: int, began: float) -> Iterable[dict[str, Any]]:
    for k, res in enumerate(runs, 1):
        if k % 10 and k != total:
            yield res
            continue
        print(
            f"{k}/{total} runs, {time.perf_counter() - began:.0f} s "
            f"(last: {res['peer']} n={res['n']} {res['bodies']})",
            file=sys.stderr,
            flush=True,
        )
        yield res


# --- the tables ----------------------------------------------------------------------------------


def _med(values: Sequence[float]) -> str:
    return "–" if not values else f"{statistics.median(values):g}"


def rounds_cell(goal_rounds: Sequence[int | None], notes: dict[str, int]) -> str:
    """median (min–max) of the rounds to the goal, k/N, then how the others ended."""
    got = [r for r in goal_rounds if r is not None]
    text = "–" if not got else f"{statistics.median(got):g} ({min(got)}–{max(got)})"
    text += f" {len(got)}/{len(goal_rounds)}"
    shown = [f"{v} {k}" for k, v in notes.items() if v]
    return text + (", " + ", ".join(shown) if shown else "")


def points_table(
    peer: str,
    runs: Sequence[dict[str, Any]],
    peer_runs: Sequence[dict[str, Any]],
    sizes: Sequence[int],
) -> list[str]:
    """Table 1 for `peer`: the world's point runs and the peer's, per n."""
    lines = [
        f"**{PEER_ALGORITHMS[peer]}** (fatswarm, world, point bodies) beside **{peer}** "
        "(oblot-sim), FSYNC rigid",
        "",
        "| | " + " | ".join(f"n={n}" for n in sizes) + " |",
        "|---|" + "---|" * len(sizes),
    ]
    ours, theirs, free = [], [], []
    for n in sizes:
        alone = [r for r in runs if r["n"] == n and r["bodies"] == "replay"]
        free.append(
            rounds_cell(
                [r["goal_round"] for r in alone],
                {
                    "err": sum(r["status"] == "error" for r in alone),
                    "cap": sum(r["status"] == "cap" for r in alone),
                },
            )
        )
        mine = [r for r in runs if r["n"] == n and r["bodies"] == "points"]
        ours.append(
            rounds_cell(
                [r["goal_round"] for r in mine],
                {
                    "refused": sum(r["status"] == "refused" for r in mine),
                    "stalled": sum(
                        r["goal_round"] is None and r["status"] == "stalled" for r in mine
                    ),
                    "cap": sum(
                        r["goal_round"] is None and r["status"] == "max_rounds" for r in mine
                    ),
                },
            )
        )
        peers = [p for p in peer_runs if p["n"] == n]
        theirs.append(
            rounds_cell(
                [p["goal_round"] for p in peers],
                {
                    "err": sum(p["stopped"] == "error" for p in peers),
                    "cap": sum(p["stopped"] == "cap" for p in peers),
                },
            )
        )
    lines.append("| fatswarm (world) | " + " | ".join(ours) + " |")
    if any(r["bodies"] == "replay" for r in runs):
        lines.append("| fatswarm port, no world | " + " | ".join(free) + " |")
    lines.append("| oblot-sim | " + " | ".join(theirs) + " |")
    return lines


def fat_table(
    peer: str, runs: Sequence[dict[str, Any]], sizes: Sequence[int], cap: int
) -> list[str]:
    """Table 2 for `peer`: per n, points against fat on the same scaled starts."""
    lines = [
        f"**{PEER_ALGORITHMS[peer]}**, points against fat bodies (FSYNC rigid, cap {cap})",
        "",
        "| n | scale | points: goal | fat: goal | fat: ended | fat: rounds run | fat: last move | "
        "collisions / run | runs with contact | first contact | final min_gap | spread / start "
        "| extra rounds |",
        "|--:|---|---|---|---|---|---|--:|--:|--:|--:|--:|---|",
    ]
    for n in sizes:
        pts = {r["seed"]: r for r in runs if r["n"] == n and r["bodies"] == "points"}
        fat = {r["seed"]: r for r in runs if r["n"] == n and r["bodies"] == "fat"}
        if not fat:
            continue
        factors = sorted({r["factor"] for r in fat.values()})
        scale = f"{factors[0]:g}" + (f"–{factors[-1]:g}" if len(factors) > 1 else "")
        ended = {
            "goal, then stalled": sum(
                r["goal_round"] is not None and r["status"] == "stalled" for r in fat.values()
            ),
            "stalled": sum(
                r["goal_round"] is None and r["status"] == "stalled" for r in fat.values()
            ),
            "cap, still moving": sum(
                r["status"] == "max_rounds" and r["rounds"] - r["last_move"] < CREEP
                for r in fat.values()
            ),
            "cap, creeping": sum(
                r["status"] == "max_rounds" and r["rounds"] - r["last_move"] >= CREEP
                for r in fat.values()
            ),
            "refused": sum(r["status"] == "refused" for r in fat.values()),
            "formed": sum(r["status"] == "formed" for r in fat.values()),
        }
        ended_text = ", ".join(f"{v} {k}" for k, v in ended.items() if v) or "–"
        extra = [
            fat[s]["goal_round"] - pts[s]["goal_round"]
            for s in fat
            if s in pts and fat[s]["goal_round"] is not None and pts[s]["goal_round"] is not None
        ]
        lost = sum(
            1
            for s in fat
            if s in pts and fat[s]["goal_round"] is None and pts[s]["goal_round"] is not None
        )
        extra_text = (
            "–" if not extra else f"{statistics.median(extra):g} ({min(extra)}–{max(extra)})"
        )
        if lost:
            extra_text = ("" if not extra else extra_text + "; ") + f"goal lost in {lost}"
        firsts = [r["first_contact"] for r in fat.values() if r["first_contact"] is not None]
        lines.append(
            f"| {n} | {scale} "
            f"| {rounds_cell([r['goal_round'] for r in pts.values()], {})} "
            f"| {rounds_cell([r['goal_round'] for r in fat.values()], {})} "
            f"| {ended_text} "
            f"| {_range([r['rounds'] for r in fat.values()])} "
            f"| {_range([r['last_move'] for r in fat.values()])} "
            f"| {_med([r['collisions'] for r in fat.values()])} "
            f"| {sum(r['collisions'] > 0 for r in fat.values())}/{len(fat)} "
            f"| {_med(firsts)} "
            f"| {_gap([r['final_min_gap'] for r in fat.values()])} "
            f"| {_med([round(r['spread_ratio'], 3) for r in fat.values()])} "
            f"| {extra_text} |"
        )
    return lines


def _range(values: Sequence[int]) -> str:
    return "–" if not values else f"{statistics.median(values):g} ({min(values)}–{max(values)})"


def _gap(values: Sequence[float]) -> str:
    if not values:
        return "–"
    med = statistics.median(values)
    return "0" if abs(med) < 1e-6 else f"{med:.3g}"


def factors_table(runs: Sequence[dict[str, Any]], sizes: Sequence[int]) -> list[str]:
    """The scale factor of every start (the same for every algorithm and both bodies)."""
    lines = [
        "The scale factor of each start (seed 0, 1, ...): its centres then are >= 2 apart.",
        "",
    ]
    lines += ["| n | factor by seed |", "|--:|---|"]
    for n in sizes:
        by_seed = {r["seed"]: r["factor"] for r in runs if r["n"] == n}
        lines.append(f"| {n} | " + ", ".join(f"{by_seed[s]:g}" for s in sorted(by_seed)) + " |")
    return lines


def tables(
    runs: Sequence[dict[str, Any]],
    table: dict[str, Any],
    peers: Sequence[str],
    sizes: Sequence[int],
    cap: int,
) -> str:
    """Both tables as Markdown: every algorithm's points table, then every fat table."""
    starts = table["starts"]
    out = ["### Point bodies: rounds to the goal beside the peer", ""]
    for peer in peers:
        peer_runs = [
            {**res, "n": st["n"]}
            for res, st in zip(table["results"][peer][SETTING], starts, strict=True)
            if st["n"] in sizes and st["seed"] in {r["seed"] for r in runs}
        ]
        mine = [r for r in runs if r["peer"] == peer]
        out += [*points_table(peer, mine, peer_runs, sizes), ""]
    out += [*factors_table(runs, sizes), ""]
    out += ["### Fat bodies against points, same starts", ""]
    for peer in peers:
        out += [*fat_table(peer, [r for r in runs if r["peer"] == peer], sizes, cap), ""]
    return "\n".join(out)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--algorithms", default=",".join(PEER_ALGORITHMS), help="peer class names")
    parser.add_argument("--sizes", default=",".join(map(str, SIZES)), help="n values of table.json")
    parser.add_argument("--seeds", type=int, default=20, help="the first k seeds of each n")
    parser.add_argument("--cap", type=int, default=DEFAULT_CAP, help="rounds at most per run")
    parser.add_argument("--bodies", default=",".join(BODIES), help="points, fat, replay")
    parser.add_argument("--workers", type=int, default=2, help="processes (1: none started)")
    parser.add_argument("--quick", action="store_true", help="n = 2, 4, 8 by 3 seeds")
    parser.add_argument("--json", type=Path, help="write every run's outcome here")
    parser.add_argument("--from-json", type=Path, help="print the tables of a --json file, no run")
    args = parser.parse_args(argv)
    sizes = QUICK_SIZES if args.quick else tuple(int(s) for s in args.sizes.split(","))
    seeds = 3 if args.quick else args.seeds
    peers = args.algorithms.split(",")
    table = load_table()
    if args.from_json:
        saved = json.loads(args.from_json.read_text(encoding="utf-8"))
        saved = [r for r in saved if r["n"] in sizes and r["seed"] < seeds and r["peer"] in peers]
        print(tables(saved, table, peers, sizes, max(r.get("cap", args.cap) for r in saved)))
        return 0
    chosen = [st for st in table["starts"] if st["n"] in sizes and st["seed"] < seeds]
    tasks = [(p, st, b, args.cap) for p in peers for st in chosen for b in args.bodies.split(",")]
    began = time.perf_counter()
    runs = measure_all(tasks, args.workers)
    print(tables(runs, table, peers, sizes, args.cap))
    print(f"({len(runs)} runs, {time.perf_counter() - began:.0f} s)", file=sys.stderr)
    if args.json:
        args.json.write_text(json.dumps(runs, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
