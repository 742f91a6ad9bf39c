"""Networked emulator benchmark (a script that prints figures, not a test).

Prints: the Zenoh get/reply round-trip floor in the layout the runs use; per size N (fsync, one OS
process per robot, world fsyncing every round): round latency (median, p95), rounds/s and Looks/s
networked vs lockstep, resident memory per agent process, time to start N agents.

    /work/venv/bin/python bench/bench_net.py [--sizes 8,64,128,256,512] [--seed 1]
        [--algorithm gathering]  # a cheap compute shows the emulator's own cost per Look
        [--router-in separate]  # a router process of its own, as across hosts (default: world)
        [--free-rounds 300]  # and the emulator alone: a steady load with no compute at all
        [--threads]  # and each role's CPU and wake-ups per Look by thread name

`--free-rounds R` adds, under each size, the same fsync swarm running an algorithm that computes
nothing (`tests/data/always_right.py` with a 1e-4 step from a spread start: every robot moves, none
collides, the run lasts R rounds): what the emulator costs without the algorithm's compute, the
ceiling any algorithm can reach on the machine.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.net.children import Children, stop_grace_s
from fatswarm.deploy.net.part_agents import agent_command, agents_command
from fatswarm.deploy.net.zconf import loopback_endpoint, make_config
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.domain.wire import ProtocolError
from fatswarm.world.observers import WorldState
from fatswarm.world.protocol import agent_alive_any_key, robot_of_alive_key, state_key

FREE_ALGORITHM = (
    f"{Path(__file__).resolve().parents[1] / 'tests' / 'data' / 'always_right.py'}:ALGORITHM"
)
FREE_WORLD = ["--start", "spread", "--param", "step=0.0001"]  # moves every round, never collides

REPLIER = """
import sys, threading, zenoh
from fatswarm.deploy.net.zconf import make_config
hosted = sys.argv[3] == "world"
endpoints = {"listen": [sys.argv[1]]} if hosted else {"connect": [sys.argv[1]]}
conf = make_config("router" if hosted else "client", **endpoints)
with zenoh.open(conf) as s:
    q = s.declare_queryable("bench/rtt", lambda q: (q.reply(q.key_expr, b"x" * 100), q.drop()))
    t = s.liveliness().declare_token("bench/replier")
    threading.Event().wait(float(sys.argv[2]))
"""


def pct(values: list[float], p: float) -> float:
    return float(np.percentile(values, p)) if values else float("nan")


def rtt_floor(endpoint: str, samples: int, router_in: str) -> list[float]:
    """Bare get/reply round trips (seconds) between two processes: clients of the router on
    `endpoint` (`separate`), or a client of the router that the replier hosts (`world`)."""

    from fatswarm.deploy.net.zconf import open_client

    env = dict(os.environ, PYTHONPATH=os.getcwd())
    replier = subprocess.Popen([sys.executable, "-c", REPLIER, endpoint, "120", router_in], env=env)
    try:
        with open_client(make_config("client", [endpoint]), deadline_s=30) as s:
            deadline = time.monotonic() + 30
            while not list(s.liveliness().get("bench/replier", timeout=1.0)):
                if time.monotonic() > deadline:
                    raise RuntimeError("replier did not come up")
                time.sleep(0.05)
            querier = s.declare_querier("bench/rtt", timeout=5.0)
            out = []
            for i in range(samples + 100):
                t0 = time.perf_counter()
                replies = list(querier.get())
                dt = time.perf_counter() - t0
                if i >= 100 and replies:
                    out.append(dt)
            return out
    finally:
        replier.terminate()
        replier.wait()


@dataclass
class NetRun:
    n: int
    status: str
    rounds: int
    start_s: float  # Popen of the first agent -> all N liveliness tokens visible
    wall_s: float  # all agents alive -> final state received
    intervals: list[float]  # time between consecutive committed rounds
    memory_mb: list[tuple[float, float, float]]  # per agent process: RSS, PSS, private
    cpu_s: dict[str, float]  # CPU seconds by role (router: this process, with the observer)
    threads: dict[str, dict[str, tuple[float, int]]]  # by role, by thread name: CPU s, switches


def _memory_mb(pid: int) -> tuple[float, float, float]:
    """(RSS, PSS, private) of a process in MB: shared library pages count fully only in RSS."""
    fields: dict[str, int] = {}
    try:
        with open(f"/proc/{pid}/smaps_rollup", encoding="ascii") as f:
            for line in f:
                parts = line.split()
                if len(parts) >= 2 and parts[1].isdigit():
                    fields[parts[0].rstrip(":")] = int(parts[1])
    except OSError:
        return (float("nan"),) * 3
    private = fields.get("Private_Clean", 0) + fields.get("Private_Dirty", 0)
    return fields.get("Rss", 0) / 1024, fields.get("Pss", 0) / 1024, private / 1024


def _agent_pids(children: Children) -> list[int]:
    """Agent processes: started directly, or forked by the `agents` host process."""
    direct = [p.pid for k, p in children.procs.items() if k.startswith("agent ")]
    host = children.procs.get("agents")
    if host is None:
        return direct
    forked = []
    for stat in os.listdir("/proc"):
        if stat.isdigit():
            try:
                with open(f"/proc/{stat}/stat", encoding="ascii") as f:
                    ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            if ppid == host.pid:
                forked.append(int(stat))
    return direct + forked


def _cpu_s(pids: list[int]) -> float:
    """User + system CPU seconds used so far by these processes."""
    total = 0
    for pid in pids:
        try:
            with open(f"/proc/{pid}/stat", encoding="ascii") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])
        except (OSError, ValueError, IndexError):
            continue
    return total / os.sysconf("SC_CLK_TCK")


def _threads(pids: list[int]) -> dict[str, tuple[float, int]]:
    """By thread name, over these processes: CPU seconds used so far and voluntary context
    switches (each one a sleep, then a wake-up)."""
    out: dict[str, tuple[float, int]] = {}
    tick = os.sysconf("SC_CLK_TCK")
    for pid in pids:
        try:
            tids = os.listdir(f"/proc/{pid}/task")
        except OSError:
            continue
        for tid in tids:
            try:
                with open(f"/proc/{pid}/task/{tid}/stat", encoding="ascii") as f:
                    text = f.read()
                with open(f"/proc/{pid}/task/{tid}/status", encoding="ascii") as f:
                    switches = next(
                        int(line.split()[1]) for line in f if line.startswith("voluntary_ctxt")
                    )
            except (OSError, ValueError, StopIteration):
                continue
            name = text[text.index("(") + 1 : text.rindex(")")]
            fields = text.rsplit(")", 1)[1].split()
            cpu, was = (int(fields[11]) + int(fields[12])) / tick, out.get(name, (0.0, 0))
            out[name] = (was[0] + cpu, was[1] + switches)
    return out


def _delta(
    after: dict[str, tuple[float, int]], before: dict[str, tuple[float, int]]
) -> dict[str, tuple[float, int]]:
    """`_threads` over a window (threads born in it count from zero)."""
    out = {}
    for name, (cpu, switches) in after.items():
        cpu0, switches0 = before.get(name, (0.0, 0))
        out[name] = (cpu - cpu0, switches - switches0)
    return out


def networked(
    session: Any,
    endpoint: str,
    n: int,
    seed: int,
    tmp: str,
    spawn: str = "fork",
    algorithm: str = "uniform-circle",
    router_in: str = "world",
    world_extra: tuple[str, ...] = (),
) -> NetRun:
    """One fsync run with N agent processes; timings seen from a client in this process (`session`
    on the separate router; None: a session of its own on the router the world hosts).
    `world_extra`: more flags for the world (start, parameters, round cap)."""
    swarm = f"bench-{n}-{seed}-{time.monotonic_ns() % 10**6}"
    alive: set[int] = set()
    commits: list[tuple[float, int]] = []
    final: list[WorldState] = []
    lock = threading.Lock()
    all_alive = threading.Event()
    done = threading.Event()

    def on_alive(sample: Any) -> None:
        robot = robot_of_alive_key(str(sample.key_expr))
        if robot is not None:
            with lock:
                alive.add(robot)
                if len(alive) == n:
                    all_alive.set()

    def on_state(sample: Any) -> None:
        now = time.perf_counter()
        try:
            st = WorldState.decode(sample.payload.to_bytes())
        except ProtocolError:
            return
        with lock:
            if st.round and (not commits or commits[-1][1] != st.round):
                commits.append((now, st.round))
            if st.status != "running":
                final.append(st)
                done.set()

    net = ["--connect", endpoint, "--swarm", swarm, "--log-level", "error"]
    world_net = ["--router", "--listen", endpoint, *net[2:]] if router_in == "world" else net
    state = os.path.join(tmp, f"{swarm}.jsonl")
    own = None
    with Children(stop_grace_s(n)) as children:  # the agents host stops its n agents first
        part = [sys.executable, "-m", "fatswarm.deploy.net.parts"]
        children.start(
            "world",
            [
                *part,
                "world",
                *world_net,
                "--state",
                state,
                "-n",
                str(n),
                "--seed",
                str(seed),
                "--scheduler",
                "fsync",
                "--algorithm",
                algorithm,
                *world_extra,
            ],
        )
        if session is None:
            from fatswarm.deploy.net.zconf import open_client

            session = own = open_client(make_config("client", [endpoint]), deadline_s=60)
        subs = [
            session.liveliness().declare_subscriber(
                agent_alive_any_key(swarm), on_alive, history=True
            ),
            session.declare_subscriber(state_key(swarm), on_state),
        ]
        children.start(
            "coordinator",
            [
                *part,
                "coordinator",
                *net,
                "--seed",
                str(seed),
                "--scheduler",
                "fsync",
                "--start-timeout",
                "600",
                "--move-timeout",
                "30",
            ],
        )
        t0 = time.perf_counter()
        if spawn == "fork":
            children.start(
                "agents", agents_command(n, swarm, [endpoint], "error", algorithm=algorithm)
            )
        else:
            for robot in range(n):
                children.start(
                    f"agent {robot}",
                    agent_command(robot, swarm, [endpoint], "error", algorithm=algorithm),
                )
        if not all_alive.wait(600):
            raise RuntimeError(f"only {len(alive)} of {n} agents came up")
        t_alive = time.perf_counter()
        roles = _roles(children)
        cpu0 = {role: _cpu_s(pids) for role, pids in roles.items()}
        threads0 = {role: _threads(pids) for role, pids in roles.items()}
        rss: list[tuple[float, float, float]] = []
        while not done.wait(0.25):
            if not rss and len(commits) > 2:  # measure memory once the agents have computed
                rss = [_memory_mb(pid) for pid in _agent_pids(children)]
            if time.perf_counter() - t_alive > 1800:
                raise RuntimeError("run did not end in 30 minutes")
        t_end = time.perf_counter()
        cpu1 = {role: _cpu_s(pids) for role, pids in roles.items()}
        threads1 = {role: _threads(pids) for role, pids in roles.items()}
        if not rss:
            rss = [_memory_mb(pid) for pid in _agent_pids(children)]
        for sub in subs:
            sub.undeclare()
        if own is not None:
            own.close()
    times = [t for t, _ in commits]
    return NetRun(
        n=n,
        status=final[0].status,
        rounds=final[0].round,
        start_s=t_alive - t0,
        wall_s=t_end - t_alive,
        intervals=[b - a for a, b in itertools.pairwise(times)],
        memory_mb=[m for m in rss if m[0] == m[0]],
        cpu_s={role: cpu1[role] - cpu0[role] for role in roles},
        threads={role: _delta(threads1[role], threads0[role]) for role in roles},
    )


def _roles(children: Children) -> dict[str, list[int]]:
    """The processes of each role; "router" is this process: the observer, and the router when it
    runs separately (else the world's process hosts it)."""
    host = children.procs.get("agents")
    return {
        "agents": _agent_pids(children) + ([host.pid] if host is not None else []),
        "world": [children.procs["world"].pid],
        "router": [os.getpid()],
        "coordinator": [children.procs["coordinator"].pid],
    }


def lockstep(n: int, seed: int, algorithm: str) -> tuple[str, int, int, float, float]:
    from fatswarm.deploy.engine.lockstep import run_lockstep
    from fatswarm.domain.registry import load_algorithm
    from fatswarm.domain.seam import Configured

    initial = random_start(n, seed, "clustered", 4.0)
    setting: Params | Configured = Params(n, 4.0)
    if algorithm != "uniform-circle":
        setting = Configured.of(load_algorithm(algorithm), n, {})
    t0, c0 = time.perf_counter(), time.process_time()
    res = run_lockstep(initial, setting, make_scheduler("fsync", n, seed), seed=seed)
    return res.status, res.rounds, res.looks, time.perf_counter() - t0, time.process_time() - c0


def _nothing() -> contextlib.nullcontext[None]:
    return contextlib.nullcontext()


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="8,64,128,256,512")
    p.add_argument(
        "--algorithm",
        default="uniform-circle",
        help="a registered algorithm (gathering: a cheap compute)",
    )
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--rtt-samples", type=int, default=2000)
    p.add_argument(
        "--spawn",
        choices=("fork", "exec"),
        default="fork",
        help="agents forked from one preloaded host (as fatswarm run) or one exec each",
    )
    p.add_argument(
        "--latency-runs",
        type=int,
        default=3,
        help="runs at the smallest N pooled for the round-latency figure",
    )
    p.add_argument(
        "--router-in",
        choices=("world", "separate"),
        default="world",
        help="the router in the world's process, as `fatswarm run` (default), or in "
        "a process of its own (here, this one), as across hosts",
    )
    p.add_argument(
        "--free-rounds",
        type=int,
        default=0,
        metavar="R",
        help="also run each size R rounds with an algorithm that computes nothing: "
        "the emulator's own cost (default 0: not run)",
    )
    p.add_argument(
        "--threads",
        action="store_true",
        help="under each run, its CPU and wake-ups (voluntary context switches) per Look by "
        "role and thread name",
    )
    args = p.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]

    import zenoh

    endpoint = loopback_endpoint()
    separate = args.router_in == "separate"
    with (
        tempfile.TemporaryDirectory() as tmp,
        zenoh.open(make_config("router", listen=[endpoint])) if separate else _nothing(),
        zenoh.open(make_config("client", [endpoint])) if separate else _nothing() as session,
    ):
        rtt = rtt_floor(endpoint, args.rtt_samples, args.router_in)
        floor = statistics.median(rtt)
        print(
            f"agents started by: {args.spawn}; algorithm: {args.algorithm}; fsync; router in "
            f"{'a process of its own' if separate else 'the world process'}"
        )
        layout = (
            "2 client processes, 1 router"
            if separate
            else "a client and the process hosting the router"
        )
        print(
            f"zenoh get/reply round trip ({layout}): median "
            f"{floor * 1e3:.3f} ms  p95 {pct(rtt, 95) * 1e3:.3f} ms  ({len(rtt)} samples)"
        )
        print(
            f"{'N':>4} {'status':>8} {'rounds':>6} {'round ms med':>12} {'p95':>7} "
            f"{'x floor':>7} {'net rounds/s':>12} {'net Looks/s':>11} {'lock rounds/s':>13} "
            f"{'lock Looks/s':>12} {'agent MB RSS/PSS/priv':>21} {'start s':>7} "
            f"{'CPU ms/Look net':>15} {'lock':>5}  CPU ms/Look by role"
        )
        for n in sizes:
            runs = [
                networked(
                    session,
                    endpoint,
                    n,
                    args.seed + k,
                    tmp,
                    args.spawn,
                    args.algorithm,
                    args.router_in,
                )
                for k in range(args.latency_runs if n == sizes[0] else 1)
            ]
            run = runs[0]
            intervals = [x for r in runs for x in r.intervals]
            med = statistics.median(intervals) if intervals else float("nan")
            l_status, l_rounds, l_looks, l_wall, l_cpu = lockstep(n, args.seed, args.algorithm)
            mem = [statistics.median(col) for col in zip(*run.memory_mb, strict=True)]
            looks = run.rounds * n
            mem_text = "/".join(f"{m:.1f}" for m in mem) if mem else "?"
            print(
                f"{n:>4} {run.status:>8} {run.rounds:>6} {med * 1e3:>12.2f} "
                f"{pct(intervals, 95) * 1e3:>7.2f} {med / floor:>7.1f} "
                f"{run.rounds / run.wall_s:>12.1f} {run.rounds * n / run.wall_s:>11.0f} "
                f"{l_rounds / l_wall:>13.1f} {l_looks / l_wall:>12.0f} {mem_text:>21} "
                f"{run.start_s:>7.2f} {1e3 * sum(run.cpu_s.values()) / looks:>15.2f} "
                f"{1e3 * l_cpu / l_looks:>5.2f}  "
                + " ".join(f"{role} {1e3 * cpu / looks:.2f}" for role, cpu in run.cpu_s.items()),
                flush=True,
            )
            if l_status != run.status or l_rounds != run.rounds:
                print(f"     (lockstep: {l_status} after {l_rounds} rounds)")
            if args.threads:
                _print_threads(run)
            if args.free_rounds > 0:
                free = networked(
                    session,
                    endpoint,
                    n,
                    args.seed,
                    tmp,
                    args.spawn,
                    FREE_ALGORITHM,
                    args.router_in,
                    (*FREE_WORLD, "--max-rounds", str(args.free_rounds)),
                )
                _print_free(free)
                if args.threads:
                    _print_threads(free)
    return 0


def _print_free(run: NetRun) -> None:
    """The line of the emulator alone (no compute) under its size's line."""
    looks = run.rounds * run.n
    med = statistics.median(run.intervals) if run.intervals else float("nan")
    print(
        f"     emulator alone (no compute, {run.rounds} rounds): round med {med * 1e3:.2f} ms, "
        f"{looks / run.wall_s:.0f} Looks/s, CPU ms/Look "
        f"{1e3 * sum(run.cpu_s.values()) / looks:.2f}: "
        + " ".join(f"{role} {1e3 * cpu / looks:.2f}" for role, cpu in run.cpu_s.items()),
        flush=True,
    )


def _print_threads(run: NetRun) -> None:
    """A run's CPU (µs) and wake-ups per Look by role and thread name, busiest first."""
    looks = run.rounds * run.n
    for role, threads in run.threads.items():
        busiest = sorted(threads.items(), key=lambda kv: -kv[1][0])
        print(
            f"       {role}: "
            + ", ".join(
                f"{name} {1e6 * cpu / looks:.0f} µs {switches / looks:.2f} wake"
                for name, (cpu, switches) in busiest
                if cpu > 0 or switches > 0
            ),
            flush=True,
        )


if __name__ == "__main__":
    sys.exit(main())
