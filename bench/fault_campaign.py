"""Fault campaign under three robot models: kill each role with SIGKILL mid-run, restart it (the
README's recipe: the same flags, the same --state), and print a table (a script that prints
figures, not a test; tests/integration/test_fault_campaign.py runs one trial of it, slow).

    python bench/fault_campaign.py                              # 3 models x 5 roles x 8 trials
    python bench/fault_campaign.py --models ssync,opaque --trials 2 --roles world,router

Models: `ssync` (the paper's algorithm under ssync), `opaque` (the same, `--visibility opaque
--record-views`), `lights-async` (`--algorithm uniform-circle-lights --lights full --scheduler
async`); `gathering-opaque` is there too, for a model whose opaque runs last longer. Roles: world,
coordinator, router, agent (one agent process), agents (every agent process at once).

Each trial starts router, world, coordinator and one process per robot on loopback (the world
from the header of the model's lock-step record, so it runs exactly that run), kills the role at
a random round (cycle, under async) in the first third of the run, restarts it at once and
follows the run to its end. It records: rounds lost or duplicated (the record numbered 1, 2, ...
with nothing announced missing), whether the record equals the lock-step record (promised for
world, coordinator and router), the recovery time (restart to the second round committed after
the fault), and the processes still running after SIGTERM and a grace of GRACE_S. Every wait is
bounded (--deadline): a run that does not go on is a failure with its reason, never a hang.
"""

from __future__ import annotations

import argparse
import contextlib
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "integration"))

from netharness import Swarm, assert_same_run, descendants_of, running

from fatswarm.world.record import RunRecord
from fatswarm.world.record_read import read_record

N = 8
GRACE_S = 10.0  # after SIGTERM, how long a part may take to stop before it counts as left


@dataclass(frozen=True, slots=True)
class Model:
    """A robot model of the campaign: its `fatswarm run` flags, and the pace of its runs."""

    flags: tuple[str, ...]
    pace: float  # least seconds a round (an instant, under async)

    @property
    def scheduler(self) -> str:
        return self.flags[self.flags.index("--scheduler") + 1]

    @property
    def algorithm(self) -> str | None:
        return self.flags[self.flags.index("--algorithm") + 1] if "--algorithm" in self else None

    def __contains__(self, flag: str) -> bool:
        return flag in self.flags


MODELS = {
    "ssync": Model(("--scheduler", "ssync"), 0.1),
    "opaque": Model(("--scheduler", "ssync", "--visibility", "opaque", "--record-views"), 0.1),
    "lights-async": Model(
        ("--algorithm", "uniform-circle-lights", "--lights", "full", "--scheduler", "async"), 0.02
    ),
    "gathering-opaque": Model(
        (
            "--algorithm",
            "gathering",
            "--scheduler",
            "ssync",
            "--visibility",
            "opaque",
            "--record-views",
        ),
        0.1,
    ),
}
DEFAULT_MODELS = ("ssync", "opaque", "lights-async")
ROLES = ("world", "coordinator", "router", "agent", "agents")
PROMISED = frozenset({"world", "coordinator", "router"})  # equal to the lock step (README)
VICTIM = 3  # the robot whose agent the `agent` role kills


class TrialFailed(Exception):
    """A trial that could not go on (a wait past its deadline, a part that died): why."""


@dataclass(frozen=True, slots=True)
class Trial:
    """What one fault did to one run."""

    model: str
    role: str
    seed: int
    ended: bool  # the run reached its end (formed, stalled, ...)
    lost_or_duplicated: int
    equal: bool  # the record equals the lock-step record
    recovery_s: float  # nan when it did not recover
    left: int  # processes still running after SIGTERM and GRACE_S
    error: str = ""


def lockstep(model: Model, seed: int, path: Path) -> RunRecord:
    """The model's lock-step run of `seed`, as a record (written to `path`)."""
    argv = [sys.executable, "-P", "-m", "fatswarm.deploy.cli", "run", "--lockstep", "-q"]
    argv += ["-n", str(N), "--seed", str(seed), *model.flags, "--record", str(path)]
    subprocess.run(argv, capture_output=True, timeout=600, check=False)
    return read_record(path)


def _wait(what: str, predicate: Callable[[], bool], sw: Swarm, deadline_s: float) -> None:
    """Poll `predicate` until true; TrialFailed at the deadline or when a part exits, but for the
    victim (-9) and a coordinator ending the run (0 formed, 1 not, 3 formed with collisions)."""
    end = time.monotonic() + deadline_s
    while not predicate():
        died = {
            k: v
            for k, v in sw.children.exited().items()
            if v != -9 and not (k.startswith("coordinator") and v in (0, 1, 3))
        }
        if died:
            raise TrialFailed(f"{_names(died)} exited while waiting for {what}")
        if time.monotonic() > end:
            raise TrialFailed(f"no {what} within {deadline_s:g} s")
        time.sleep(0.02)


def _names(codes: dict[str, int]) -> str:
    return ", ".join(f"{name} ({code})" for name, code in codes.items())


def _start_agent(sw: Swarm, model: Model, robot: int, name: str) -> None:
    algorithm = [] if model.algorithm is None else ["--algorithm", model.algorithm]
    sw._start(
        name,
        "agent",
        *sw._net(),
        "--robot",
        str(robot),
        "--seed",
        str(sw.seed),
        "--log-level",
        "warning",
        *algorithm,
    )


def _kill(sw: Swarm, names: list[str]) -> None:
    for name in names:
        sw.children.procs[name].send_signal(signal.SIGKILL)
    for name in names:
        sw.children.procs[name].wait(timeout=10)


def _restart(sw: Swarm, model: Model, role: str, victims: list[str]) -> None:
    """The README's recipe: the part started again with the flags it had."""
    if role == "world":
        sw.start_world("world again")
    elif role == "coordinator":
        sw.start_coordinator(model.pace, "coordinator again")
    elif role == "router":
        sw.start_router("router again")  # on the same endpoint
    else:
        for name in victims:
            _start_agent(sw, model, int(name.split()[1]), f"{name} again")


def _lost_or_duplicated(record: RunRecord, announced: int) -> int:
    numbers = [r.round for r in record.rounds]
    out = len(numbers) - len(set(numbers))
    out += sum(1 for k, r in enumerate(numbers, start=1) if r != k)
    return out + max(0, announced - len(numbers))  # announced but not in the record


def _same(net: RunRecord, lock: RunRecord) -> bool:
    try:
        assert_same_run(net, lock)
    except AssertionError:
        return False
    return True


def _stop(sw: Swarm) -> int:
    """SIGTERM every part, wait up to GRACE_S; how many processes were still running (the rest
    are then killed)."""
    pids = [p.pid for p in sw.children.procs.values() if p.poll() is None]
    pids += [d for pid in pids for d in descendants_of(pid)]
    for name, proc in sw.children.procs.items():
        if proc.poll() is None:
            sw.children.stop(name, signal.SIGTERM)
    end = time.monotonic() + GRACE_S
    while any(running(pid) for pid in pids) and time.monotonic() < end:
        time.sleep(0.05)
    left = sum(1 for pid in pids if running(pid))
    sw.close()  # kills and reaps whatever is left
    return left


def trial(model_name: str, role: str, seed: int, lock_path: Path, deadline_s: float) -> Trial:
    """One run of `model_name` with `role` killed and restarted once, against the lock-step record
    at `lock_path` (of the same model and seed); the figures of what it did."""
    model = MODELS[model_name]
    lock = read_record(lock_path)
    rng = random.Random(f"{model_name} {role} {seed}")
    with tempfile.TemporaryDirectory() as tmp:
        sw = Swarm(Path(tmp), N, seed, model.scheduler)
        with open(lock_path, encoding="utf-8") as f:  # the world runs the lock step's run,
            sw.state_path.write_text(f.readline())  # from its header (a new run: no rounds yet)
        ended, lost, equal, recovery, left, error = False, 0, False, float("nan"), 0, ""
        try:
            sw.start_router()
            sw.observe()
            sw.start_world()
            sw.start_coordinator(model.pace)
            for robot in range(N):
                _start_agent(sw, model, robot, f"agent {robot}")
            at = rng.randint(2, max(2, len(lock.rounds) // 3))
            _wait(
                f"round {at}",
                lambda: (s := sw.state()) is not None and s.round >= at,
                sw,
                deadline_s,
            )
            time.sleep(rng.uniform(0.0, model.pace))
            now = sw.state()
            fault_round = now.round if now is not None else at
            victims = {
                "world": ["world"],
                "coordinator": ["coordinator"],
                "router": ["router"],
                "agent": [f"agent {VICTIM}"],
                "agents": [f"agent {r}" for r in range(N)],
            }[role]
            _kill(sw, victims)
            t0 = time.monotonic()
            _restart(sw, model, role, victims)
            _wait(
                "two rounds after the fault",
                lambda: (
                    (s := sw.state()) is not None
                    and (s.round >= fault_round + 2 or s.status != "running")
                ),
                sw,
                deadline_s,
            )
            recovery = time.monotonic() - t0
            _wait(
                "the run's end",
                lambda: (s := sw.state()) is not None and s.status != "running",
                sw,
                deadline_s,
            )
            end = sw.state()
            assert end is not None
            ended = True
            record = read_record(sw.state_path)
            lost = _lost_or_duplicated(record, end.round)
            equal = _same(record, lock)
        except (TrialFailed, AssertionError, OSError, ValueError, subprocess.TimeoutExpired) as exc:
            error = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
            with contextlib.suppress(OSError, ValueError):  # what the record holds still counts
                lost = _lost_or_duplicated(read_record(sw.state_path, allow_torn_end=True), 0)
        finally:
            left = _stop(sw)
        return Trial(model_name, role, seed, ended, lost, equal, recovery, left, error)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", default=",".join(DEFAULT_MODELS), help=f"of {', '.join(MODELS)}")
    p.add_argument("--roles", default=",".join(ROLES), help=f"of {', '.join(ROLES)}")
    p.add_argument("--trials", type=int, default=8, help="trials of each model and role")
    p.add_argument(
        "--deadline", type=float, default=60.0, help="seconds any one wait of a trial may take"
    )
    args = p.parse_args()
    models, roles = args.models.split(","), args.roles.split(",")
    unknown = [m for m in models if m not in MODELS] + [r for r in roles if r not in ROLES]
    if unknown:
        p.error(f"unknown model or role: {', '.join(unknown)}")
    rows: list[list[Trial]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for model in models:
            locks = {}
            for seed in range(1, args.trials + 1):
                locks[seed] = Path(tmp) / f"{model}-{seed}.jsonl"
                lockstep(MODELS[model], seed, locks[seed])
            for role in roles:
                done = []
                for seed in range(1, args.trials + 1):
                    t = trial(model, role, seed, locks[seed], args.deadline)
                    done.append(t)
                    if t.error:
                        print(f"  {model} {role} seed {seed}: {t.error}", file=sys.stderr)
                rows.append(done)
                print(f"{model} {role} done", file=sys.stderr, flush=True)
    print_table(rows)
    return 0


def print_table(rows: list[list[Trial]]) -> None:
    """One line per model and role: trials, failures, lost/duplicated, equal, recovery, left."""
    print(
        f"{'model':<16} {'role':<11} {'trials':>6} {'failed':>6} {'ended':>5} {'lost/dup':>8} "
        f"{'equal':>9} {'recovery s med / max':>20} {'left':>4}"
    )
    for done in rows:
        t0 = done[0]
        times = [t.recovery_s for t in done if t.recovery_s == t.recovery_s]
        med = f"{statistics.median(times):.2f} / {max(times):.2f}" if times else "-"
        equal = f"{sum(t.equal for t in done)}{'' if t0.role in PROMISED else ' (np)'}"
        print(
            f"{t0.model:<16} {t0.role:<11} {len(done):>6} {sum(bool(t.error) for t in done):>6} "
            f"{sum(t.ended for t in done):>5} "
            f"{sum(t.lost_or_duplicated for t in done):>8} {equal:>9} {med:>20} "
            f"{sum(t.left for t in done):>4}"
        )
    print(
        "failed: trials that did not go on (their reasons above, on stderr); equal: records equal"
        " to the lock step's; (np): not promised for this role; recovery: restart to the second "
        "round after the fault; left: processes running after SIGTERM and "
        f"{GRACE_S:g} s",
        flush=True,
    )


if __name__ == "__main__":
    raise SystemExit(main())
