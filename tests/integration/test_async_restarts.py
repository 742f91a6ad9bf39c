"""Async runs survive what round runs survive: `fatswarm run --resume` of a cut async record, and
a world, coordinator or router killed with SIGKILL and restarted, each end with the lock-step
record (an async record is resumed by replaying its run from the start: docs/record.md)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from netharness import Swarm, assert_same_run, lockstep_record

from fatswarm.deploy import cli
from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration

SEED = 2  # n = 5 under async: 80-odd cycles, each instant paced so that a kill lands mid-run


def _fatswarm_run(flags: list[str]) -> tuple[int, str]:
    """`fatswarm run FLAGS` in its own process group: exit code and output (killed after 240 s)."""
    argv = [sys.executable, "-m", "fatswarm.deploy.cli", "run", *flags]
    proc = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    try:
        out, _ = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, out.decode(errors="replace")


RESUMED = {
    "async": ["-n", "5", "--seed", "2", "--scheduler", "async"],
    "lights": [
        *("-n", "5", "--seed", "4", "--algorithm", "uniform-circle-lights"),
        *("--lights", "full", "--scheduler", "async"),
    ],
    "opaque-views": [
        *("-n", "6", "--seed", "2", "--scheduler", "async"),
        *("--visibility", "opaque", "--record-views"),
    ],
}


@pytest.mark.parametrize(
    "model",
    [
        "async",
        pytest.param("lights", marks=pytest.mark.slow),
        pytest.param("opaque-views", marks=pytest.mark.slow),
    ],
)
def test_run_resume_continues_a_cut_async_record_networked_and_in_lock_step_byte_for_byte(
    tmp_path: Path, model: str
) -> None:
    # The lock-step runs in this process (cli.main); the networked resume is `fatswarm run`'s.
    whole = tmp_path / "whole.jsonl"
    assert cli.main(["run", "--lockstep", *RESUMED[model], "--record", str(whole), "-q"]) in (0, 1)
    lines = whole.read_text().splitlines(keepends=True)
    k = len(lines) // 3
    for mode in ("networked", "lockstep"):
        cut = tmp_path / f"{mode}.jsonl"
        # the header and k - 1 cycles, and half of the next line: a crash while writing it
        cut.write_text("".join(lines[:k]) + lines[k][:40])
        if mode == "lockstep":
            code = cli.main(["run", "--lockstep", "--record", str(cut), "--resume", "-q"])
            out = ""
        else:
            flags = ["--no-dashboard", "--record", str(cut), "--resume", "-q"]
            code, out = _fatswarm_run(flags)
        assert code in (0, 1), out
        assert cut.read_bytes() == whole.read_bytes(), mode


def _restart(sw: Swarm, role: str, at: int = 8) -> float:
    """Kill `role` with SIGKILL once `at` cycles have ended, and start it again (an agent: robot
    0's; agents: every one); the seconds from the kill to the next cycle ended after it."""
    sw.wait_for(f"cycle {at}", lambda: (s := sw.state()) is not None and s.round >= at)
    state = sw.state()
    assert state is not None
    seen = state.round
    killed = time.monotonic()
    if role == "agent":
        sw.kill9("agent 0")
        sw.start_agent(0, name="agent 0 again")
    elif role == "agents":
        for robot in range(sw.n):
            sw.kill9(f"agent {robot}")
        for robot in range(sw.n):
            sw.start_agent(robot, name=f"agent {robot} again")
    else:
        sw.kill9("world" if role == "world-router" else role)
    if role == "world":
        sw.start_world(name="world again")
    elif role == "world-router":  # the world hosting the router, as `fatswarm run` lays it out
        sw.start_world_router(name="world again")
    elif role == "coordinator":
        sw.start_coordinator(pace=0.02, name="coordinator again")
    elif role == "router":
        sw.start_router("router again")  # on the same endpoint
    sw.wait_for(
        "a cycle after the restart",
        lambda: (s := sw.state()) is not None and (s.round > seen or s.status != "running"),
    )
    return time.monotonic() - killed


@pytest.mark.parametrize("role", ["world", "coordinator", "router"])
def test_an_async_run_outlives_a_restart_of_its_role_and_keeps_the_lockstep_record(
    tmp_path: Path, make_swarm: Callable[..., Swarm], role: str
) -> None:
    sw = make_swarm(5, SEED, "async")
    sw.start_all(pace=0.02, hosted=True)
    _restart(sw, role)
    end = sw.wait_done()
    assert end.status in ("formed", "stalled"), sw.logs()
    rec = read_record(sw.state_path)
    assert [r.round for r in rec.rounds] == list(range(1, len(rec.rounds) + 1))
    if role == "world":
        assert "replayed from its start" in sw.log("world again")
    if role == "coordinator":
        assert "resuming after instant" in sw.log("coordinator again")
    lock = lockstep_record(tmp_path / "lock.jsonl", 5, SEED, "async")
    assert_same_run(rec, lock)  # no cycle lost or repeated, every one the lock step's


@pytest.mark.slow
@pytest.mark.parametrize("trial", range(8))
@pytest.mark.parametrize(
    "role", ["world", "world-router", "coordinator", "router", "agent", "agents"]
)
def test_async_restart_trials_of_every_role(
    tmp_path: Path, make_swarm: Callable[..., Swarm], role: str, trial: int
) -> None:
    # 8 seeds, both async models, kills from cycle 3 to cycle 24: every role's trials print one
    # line (pytest -s): equal to the lock step, cycles lost or repeated, recovery, processes left
    scheduler = ("async", "async-slowest")[trial % 2]
    seed = 1 + trial
    sw = make_swarm(6, seed, scheduler)
    sw.start_all(pace=0.02, in_world=role == "world-router")
    recovery = _restart(sw, role, at=3 + 3 * trial)
    end = sw.wait_done()
    rec = read_record(sw.state_path)
    numbers = [r.round for r in rec.rounds]
    gaps = len(numbers) != len(set(numbers)) or numbers != list(range(1, len(numbers) + 1))
    lock = lockstep_record(tmp_path / "lock.jsonl", 6, seed, scheduler)
    equal = True
    try:
        assert_same_run(rec, lock)
    except AssertionError:
        equal = False
    sw.close()
    left = [name for name, p in sw.children.procs.items() if p.poll() is None]
    print(
        f"TRIAL {role} {scheduler} seed {seed} kill at cycle {3 + 3 * trial}: {end.status}, "
        f"equal {equal}, cycles lost/repeated {int(gaps)}, recovery {recovery:.2f} s, "
        f"left {len(left)}"
    )
    assert not gaps and not left
    if role in ("world", "world-router", "coordinator", "router"):  # what the docs promise
        assert equal, sw.logs()


class ModelSwarm(Swarm):
    """A swarm running the run of a lock-step record's header (another algorithm or robot model):
    its state file starts as that header alone, which the world resumes (as `fatswarm run` lays a
    run out), and its agents run the header's algorithm."""

    def __init__(self, tmp: Path, lock: Path) -> None:
        header = read_record(lock).header
        super().__init__(tmp, header.n, int(header.seed or 0), header.scheduler)
        self.algorithm = header.algorithm_ref
        self.state_path.write_text(lock.read_text().splitlines(keepends=True)[0])

    def start_agent(self, robot: int, name: str | None = None) -> None:
        self._start(
            name or f"agent {robot}",
            "agent",
            *self._net(),
            *("--robot", str(robot), "--seed", str(self.seed), "--algorithm", self.algorithm),
            *("--log-level", "info"),
        )


@pytest.mark.slow
@pytest.mark.parametrize("trial", range(8))
@pytest.mark.parametrize("role", ["world", "coordinator", "router"])
@pytest.mark.parametrize("model", ["lights", "opaque-views"])
def test_async_restart_trials_of_the_luminous_and_opaque_models(
    tmp_path: Path, model: str, role: str, trial: int
) -> None:
    lock = tmp_path / "lock.jsonl"
    code, out = _fatswarm_run(["--lockstep", *RESUMED[model], "--record", str(lock), "-q"])
    assert code in (0, 1), out
    sw = ModelSwarm(tmp_path, lock)
    try:
        sw.start_all(pace=0.02)
        at = 3 + 3 * trial
        recovery = _restart(sw, role, at=at)
        end = sw.wait_done()
        net = read_record(sw.state_path)
        equal = net.rounds and lock.read_text().splitlines()[1:] == [
            line for line in sw.state_path.read_text().splitlines()[1:]
        ]
        print(
            f"TRIAL {model} {role} kill at cycle {at}: {end.status}, equal {bool(equal)}, "
            f"recovery {recovery:.2f} s"
        )
        assert equal, sw.logs()  # every line after the header, byte for byte
    finally:
        sw.close()


def test_a_coordinator_whose_world_never_answers_gives_up_after_its_bound_with_exit_5(
    make_swarm: Callable[..., Swarm],
) -> None:
    sw = make_swarm(5, SEED, "async")
    sw.start_router()
    sw._start("coordinator", "coordinator", *sw.coordinator_flags(0.0), "--give-up", "1.5")
    proc = sw.children.procs["coordinator"]
    assert proc.wait(timeout=60) == 5, sw.logs()  # (the deadline of a shared machine)
    said = [line for line in sw.log("coordinator").splitlines() if "giving up" in line]
    assert len(said) == 1 and "no usable answer for 1.5 s" in said[0], sw.logs()
