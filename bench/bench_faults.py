"""Fault campaign: kill -9 or SIGSTOP each role of a networked swarm at a random moment, restart
it, and print a table (a script that prints figures, not a test; a quick run is a slow test).

    python bench/bench_faults.py                     # every role, kill and stop, 5 trials each
    python bench/bench_faults.py --roles world --signals kill --trials 10

Roles: agent (one agent process), agents-fork / agents-exec (a host of agents, killed with them
gone too), world, coordinator, router, and world-router (the world hosting the router, as
`fatswarm run` lays a swarm out: its fault takes the router down with it). A killed part is
restarted at once; a stopped one is continued after --stop-s seconds. For each trial it records
whether the run formed, whether it is referee-clean (no collision along any path, a regular
polygon at the end), whether a committed or announced round was lost or duplicated, the recovery
time (fault, or continue, to the second round committed after it) and the processes left running
once the run is over.
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "integration"))

from netharness import Swarm, descendants_of, running

from fatswarm.agent.geometry import is_formed
from fatswarm.world.record_read import read_record

ROLES = ("agent", "agents-fork", "agents-exec", "world", "coordinator", "router", "world-router")
SIGNALS = ("kill", "stop")
N, PACE_S = 8, 0.1


@dataclass(frozen=True, slots=True)
class Trial:
    """What one fault did to one run."""

    role: str
    signal: str
    formed: bool
    clean: bool
    lost_or_duplicated: int
    recovery_s: float
    left: int
    error: str = ""


def _start(sw: Swarm, role: str) -> None:
    """Router, observer, world, coordinator and the agents (one host of them for agents-*)."""
    if role == "world-router":
        sw.start_world_router()
        sw.observe()
    else:
        sw.start_router()
        sw.observe()
        sw.start_world()
    sw.start_coordinator(PACE_S)
    if role.startswith("agents-"):
        spawn = role.split("-", 1)[1]
        sw._start(
            "agents",
            "agents",
            *sw._net(),
            "-n",
            str(N),
            "--seed",
            str(sw.seed),
            "--spawn",
            spawn,
            "--log-level",
            "warning",
        )
    else:
        for robot in range(N):
            sw.start_agent(robot)


def _victim(role: str) -> str:
    return {
        "agent": "agent 3",
        "agents-fork": "agents",
        "agents-exec": "agents",
        "world-router": "world",
    }.get(role, role)


def _restart(sw: Swarm, role: str) -> None:
    again = f"{_victim(role)} again"
    if role == "agent":
        sw.start_agent(3, again)
    elif role.startswith("agents-"):
        spawn = role.split("-", 1)[1]
        sw._start(
            again,
            "agents",
            *sw._net(),
            "-n",
            str(N),
            "--seed",
            str(sw.seed),
            "--spawn",
            spawn,
            "--log-level",
            "warning",
        )
    elif role == "world":
        sw.start_world(again)
    elif role == "world-router":
        sw.start_world_router(again)
    elif role == "coordinator":
        sw.start_coordinator(PACE_S, again)
    else:
        sw.start_router(again)


def trial(role: str, sig: str, seed: int, stop_s: float) -> Trial:
    """One run with one fault; the figures of what it did."""
    rng = random.Random(seed)
    with tempfile.TemporaryDirectory() as tmp:
        sw = Swarm(Path(tmp), N, seed)
        seen_rounds: list[int] = []
        try:
            _start(sw, role)
            at = rng.randint(2, 6)
            sw.wait_for(
                "the fault's round", lambda: (s := sw.state()) is not None and s.round >= at
            )
            time.sleep(rng.uniform(0.0, PACE_S))
            victim = sw.children.procs[_victim(role)]
            hosted = descendants_of(victim.pid) if role.startswith("agents-") else []
            now_state = sw.state()
            fault_round = now_state.round if now_state is not None else at
            if sig == "kill":
                victim.send_signal(signal.SIGKILL)
                victim.wait()
                t0 = time.monotonic()
                _restart(sw, role)
            else:
                victim.send_signal(signal.SIGSTOP)
                time.sleep(stop_s)
                victim.send_signal(signal.SIGCONT)
                t0 = time.monotonic()
            sw.wait_for(
                "two rounds after the fault",
                lambda: (
                    (s := sw.state()) is not None
                    and (s.round >= fault_round + 2 or s.status != "running")
                ),
            )
            recovery = time.monotonic() - t0
            end = sw.wait_done()
            seen_rounds.append(end.round)
            record = read_record(sw.state_path)
            numbers = [r.round for r in record.rounds]
            lost = (
                len(numbers)
                - len(set(numbers))
                + sum(1 for k, r in enumerate(numbers, start=1) if r != k)
            )
            lost += max(0, end.round - len(numbers))  # announced but not in the record
            final = record.result.positions if record.result else record.rounds[-1].positions
            clean = sum(len(r.collisions) for r in record.rounds) == 0 and is_formed(final, 4.0)
            formed = end.status == "formed"
            error = ""
        except BaseException as exc:  # pytest.fail from the harness, or anything else
            if isinstance(exc, KeyboardInterrupt):
                raise
            formed, clean, lost, recovery, hosted = False, False, 0, float("nan"), []
            error = str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__
        finally:
            sw.close()
        deadline = time.monotonic() + 10
        while any(running(p) for p in hosted) and time.monotonic() < deadline:
            time.sleep(0.1)
        left = sum(1 for p in hosted if running(p))
        for pid in hosted:
            if running(pid):
                os.kill(pid, signal.SIGKILL)
        return Trial(role, sig, formed, clean, lost, recovery, left, error)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--roles", default=",".join(ROLES))
    p.add_argument("--signals", default=",".join(SIGNALS))
    p.add_argument("--trials", type=int, default=5)
    p.add_argument(
        "--stop-s", type=float, default=3.0, help="how long a stopped part stays stopped"
    )
    args = p.parse_args()
    rows: list[list[Trial]] = []
    for role in args.roles.split(","):
        for sig in args.signals.split(","):
            done = [trial(role, sig, seed, args.stop_s) for seed in range(1, args.trials + 1)]
            rows.append(done)
            for t in done:
                if t.error:
                    print(f"  {role} {sig}: {t.error}", file=sys.stderr)
            print(f"{role:<13} {sig:<5} done", file=sys.stderr, flush=True)
    print(
        f"{'role':<13} {'fault':<5} {'trials':>6} {'formed':>6} {'clean':>5} "
        f"{'lost/dup':>8} {'recovery s med / max':>20} {'left':>4}"
    )
    for done in rows:
        times = [t.recovery_s for t in done if t.recovery_s == t.recovery_s]
        med = f"{statistics.median(times):.2f} / {max(times):.2f}" if times else "-"
        print(
            f"{done[0].role:<13} {done[0].signal:<5} {len(done):>6} "
            f"{sum(t.formed for t in done):>6} {sum(t.clean for t in done):>5} "
            f"{sum(t.lost_or_duplicated for t in done):>8} {med:>20} "
            f"{sum(t.left for t in done):>4}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
