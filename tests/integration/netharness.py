"""Harness for multi-process swarms on loopback: free ports, no multicast, all stopped after."""

from __future__ import annotations

import contextlib
import io
import os
import secrets
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fatswarm.agent.service import AgentConfig, serve
from fatswarm.deploy.net.children import Children
from fatswarm.deploy.net.zconf import loopback_endpoint, make_config
from fatswarm.domain.seam import Algorithm
from fatswarm.domain.wire import ProtocolError
from fatswarm.world.observers import WorldState
from fatswarm.world.protocol import state_key
from fatswarm.world.record import RecordWriter, RunRecord, result_figures
from fatswarm.world.record_read import read_record

DEADLINE_S = 120.0  # generous: the machine is shared; tests wait on predicates, never on sleeps


class Swarm:
    """Router, world, coordinator and agents as separate processes, plus an observer session."""

    def __init__(
        self, tmp: Path, n: int, seed: int, scheduler: str = "ssync", endpoint: str | None = None
    ) -> None:
        self.tmp, self.n, self.seed, self.scheduler = tmp, n, seed, scheduler
        self.endpoint = endpoint or loopback_endpoint()  # another swarm's: share its router
        self.swarm = f"it-{secrets.token_hex(3)}"
        self.state_path = tmp / "state.jsonl"
        self.children = Children()
        self.session: Any = None
        self.latest: WorldState | None = None
        self._lock = threading.Lock()
        self._here: tuple[threading.Thread, threading.Event] | None = None  # an agent in-process

    # -- processes ------------------------------------------------------------------------------

    def _start(self, name: str, part: str, *flags: str) -> None:
        log = open(self.tmp / f"{name.replace(' ', '-')}.log", "ab")  # noqa: SIM115
        argv = [sys.executable, "-m", "fatswarm.deploy.net.parts", part, *flags]
        self.children.start(name, argv, stdout=log, stderr=log)
        log.close()

    def _net(self) -> list[str]:
        return ["--connect", self.endpoint, "--swarm", self.swarm]

    def start_router(self, name: str = "router") -> None:
        self._start(name, "router", "--listen", self.endpoint, "--log-level", "warning")

    def world_flags(self, state: Path | None = None) -> list[str]:
        return [
            *self._net(),
            "--state",
            str(state or self.state_path),
            "-n",
            str(self.n),
            "--seed",
            str(self.seed),
            "--scheduler",
            self.scheduler,
            "--log-level",
            "info",
        ]

    def coordinator_flags(self, pace: float, move_timeout: float | None = None) -> list[str]:
        """`move_timeout`: the coordinator's --move-timeout (None: its default), how long it waits
        for an agent gone from a round before it plans without it."""
        timeout = [] if move_timeout is None else ["--move-timeout", str(move_timeout)]
        return [
            *self._net(),
            "--seed",
            str(self.seed),
            "--scheduler",
            self.scheduler,
            "--pace",
            str(pace),
            *timeout,
            "--log-level",
            "info",
        ]

    def start_world(self, name: str = "world") -> None:
        self._start(name, "world", *self.world_flags())

    def start_world_router(self, name: str = "world") -> None:
        """The world hosting the router at `endpoint` (as in `fatswarm run`)."""
        flags = self.world_flags()
        at = flags.index("--connect")
        del flags[at : at + 2]  # it listens there instead
        self._start(name, "world", *flags, "--router", "--listen", self.endpoint)

    def start_coordinator(
        self, pace: float, name: str = "coordinator", move_timeout: float | None = None
    ) -> None:
        self._start(name, "coordinator", *self.coordinator_flags(pace, move_timeout))

    def start_agent(self, robot: int, name: str | None = None) -> None:
        self._start(
            name or f"agent {robot}",
            "agent",
            *self._net(),
            "--robot",
            str(robot),
            "--seed",
            str(self.seed),
            "--log-level",
            "info",
        )

    def start_all(
        self,
        pace: float,
        router: bool = True,
        in_world: bool = False,
        move_timeout: float | None = None,
        hosted: bool = False,
        apart: int | None = None,
        apart_here: Algorithm[Any] | None = None,
    ) -> None:
        """Every part (`router=False`: on another swarm's router, given as `endpoint`;
        `in_world`: the world hosts the router, as in `fatswarm run`; `move_timeout`: the
        coordinator's, see coordinator_flags; `hosted`: the agents forked by one `agents` host
        named "agents", as `fatswarm run` starts them, quicker to start than a process each, for
        tests that do not stop or read one agent by its name "agent I"; `apart`: but robot I's
        agent, started alone as "agent I", between hosts of the robots below and above it;
        `apart_here`: robot I's agent runs in this test process instead, with this algorithm
        (`start_agent_here`))."""
        if in_world:
            self.start_world_router()
            self.observe()
        else:
            if router:
                self.start_router()
            self.observe()
            self.start_world()
        self.start_coordinator(pace, move_timeout=move_timeout)
        if not hosted:
            for robot in range(self.n):
                self.start_agent(robot)
            return
        cut = self.n if apart is None else apart
        for name, first, count in (("agents", 0, cut), ("agents above", cut + 1, self.n - cut - 1)):
            if count > 0:
                self.start_agents(first, count, name)
        if apart is not None and apart_here is not None:
            self.start_agent_here(apart, apart_here)
        elif apart is not None:
            self.start_agent(apart)

    def start_agents(self, first: int = 0, count: int | None = None, name: str = "agents") -> None:
        """The agents of robots first..first+count-1 (default: every robot) forked by one `agents`
        host, as `fatswarm run` starts them: quicker to start than a process each."""
        count = self.n - first if count is None else count
        net = [*self._net(), "-n", str(count), "--first", str(first)]
        self._start(name, "agents", *net, "--log-level", "info")

    def start_agent_here(self, robot: int, algorithm: Algorithm[Any]) -> None:
        """Robot `robot`'s agent in this test process: the agent's own loop (`serve`) in a thread,
        on a Zenoh session of its own, with `algorithm` (e.g. one whose compute the test holds,
        so that a round stays open); stopped by `close`. Zenoh's default lease, not an agent's
        2 s: a test process slowed by the load must not be taken for a hung agent."""
        assert self._here is None, "one agent in the test process at a time"
        stop = threading.Event()
        conf = make_config("client", [self.endpoint], shared_memory=False)
        cfg = AgentConfig(self.swarm, robot, algorithm.name)
        thread = threading.Thread(
            target=serve, args=(cfg, conf, stop, None, algorithm), name=f"agent {robot}"
        )
        thread.start()
        self._here = (thread, stop)

    def kill9(self, name: str) -> None:
        import signal

        self.children.stop(name, signal.SIGKILL)
        self.children.procs[name].wait()

    # -- observing ------------------------------------------------------------------------------

    def observe(self) -> None:
        """Subscribe to the world's state stream from this test process (a client session)."""
        import zenoh

        def keep(sample: Any) -> None:
            try:
                state = WorldState.decode(sample.payload.to_bytes())
            except ProtocolError:
                return
            with self._lock:
                self.latest = state

        for _ in range(100):
            try:
                self.session = zenoh.open(make_config("client", [self.endpoint]))
                break
            except zenoh.ZError:
                time.sleep(0.1)
        assert self.session is not None, "router did not come up"
        self.session.declare_subscriber(state_key(self.swarm), keep)

    def state(self) -> WorldState | None:
        with self._lock:
            return self.latest

    def live(self, key: str) -> bool:
        """Whether a liveliness token on `key` is live now (asked from the observer session)."""
        return any(
            reply.ok is not None for reply in self.session.liveliness().get(key, timeout=2.0)
        )

    def log(self, name: str) -> str:
        path = self.tmp / f"{name.replace(' ', '-')}.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def logs(self) -> str:
        return "\n".join(
            f"--- {p.name}\n{p.read_text(errors='replace')[-3000:]}"
            for p in sorted(self.tmp.glob("*.log"))
            if p.stat().st_size
        )

    def wait_for(
        self, what: str, predicate: Callable[[], bool], deadline_s: float = DEADLINE_S
    ) -> None:
        """Poll `predicate` until true; fail with every process's log tail at the deadline."""
        end = time.monotonic() + deadline_s
        while not predicate():
            if time.monotonic() > end:
                pytest.fail(f"timed out waiting for {what}\n{self.logs()}")
            exited = {k: v for k, v in self.children.exited().items() if v not in (0, -9)}
            if exited:
                pytest.fail(f"processes died {exited} while waiting for {what}\n{self.logs()}")
            time.sleep(0.02)

    def wait_done(self) -> WorldState:
        self.wait_for(
            "the run to end", lambda: (s := self.state()) is not None and s.status != "running"
        )
        state = self.state()
        assert state is not None
        return state

    def close(self) -> None:
        here, self._here = self._here, None
        if here is not None:
            here[1].set()  # its Look ends when the world stops (or after LOOK_WAIT_S)
        try:
            self.children.stop_all()
        finally:
            if here is not None:
                here[0].join(DEADLINE_S)
            if self.session is not None:
                self.session.close()
        assert here is None or not here[0].is_alive(), "the agent in the test process went on"


def part(name: str, *flags: str) -> list[str]:
    """The argv of `fatswarm <name> <flags>` (one part alone, as the launcher starts it)."""
    return [sys.executable, "-m", "fatswarm.deploy.net.parts", name, *flags]


def run_all(
    *argvs: list[str], deadline_s: float = DEADLINE_S
) -> list[subprocess.CompletedProcess[str]]:
    """Run the commands at once (each waits on its own deadline) and collect their outcomes."""
    procs = [
        subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
        )
        for argv in argvs
    ]
    try:
        done = []
        for argv, proc in zip(argvs, procs, strict=True):
            out, err = proc.communicate(timeout=deadline_s)
            done.append(subprocess.CompletedProcess(argv, proc.returncode, out, err))
        return done
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def fatswarm_runs(*flag_lists: list[str], deadline_s: float = 240.0) -> list[tuple[int, str]]:
    """`fatswarm run FLAGS` for each list, side by side (a networked run and its lock-step twin
    need not wait for each other): exit codes and outputs (stdout and stderr together), in order.
    A networked run is a process in its own process group, killed if still running after
    `deadline_s`; a `--lockstep` run is the command's entry point in this process (cli.main), run
    once every process is started: the same record, without a process's start-up."""
    from fatswarm.deploy import cli

    started: dict[int, tuple[subprocess.Popen[bytes], Any]] = {}
    try:
        for at, flags in enumerate(flag_lists):
            if "--lockstep" in flags:
                continue
            out = tempfile.TemporaryFile()  # noqa: SIM115 (closed below)
            argv = [sys.executable, "-m", "fatswarm.deploy.cli", "run", *flags]
            proc = subprocess.Popen(
                argv, stdout=out, stderr=subprocess.STDOUT, start_new_session=True
            )
            started[at] = (proc, out)
        here: dict[int, tuple[int, str]] = {}
        for at, flags in enumerate(flag_lists):
            if at not in started:
                text = io.StringIO()
                with contextlib.redirect_stdout(text), contextlib.redirect_stderr(text):
                    code = cli.main(["run", *flags])
                here[at] = (code, text.getvalue())
        end = time.monotonic() + deadline_s
        done = []
        for at in range(len(flag_lists)):
            if at in here:
                done.append(here[at])
                continue
            proc, out = started[at]
            proc.wait(timeout=max(0.0, end - time.monotonic()))
            out.seek(0)
            done.append((proc.returncode, out.read().decode(errors="replace")))
        return done
    finally:
        for proc, out in started.values():
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            out.close()


def assert_one_line(done: subprocess.CompletedProcess[str], start: str) -> None:
    """Exit 2 with one line on stderr that starts with `start` (no traceback, no Rust path)."""
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(start) and done.stderr.count("\n") == 1, done.stderr
    assert "Traceback" not in done.stderr and ".rs:" not in done.stderr, done.stderr


def lockstep_record(path: Path, n: int, seed: int, scheduler: str = "ssync") -> RunRecord:
    """The lockstep run of the same start, seed and scheduler, as a record."""
    from fatswarm.agent.params import Params
    from fatswarm.coordinator.schedule import make_scheduler
    from fatswarm.deploy.engine.lockstep import run_lockstep
    from fatswarm.deploy.scenarios.starts import random_start

    initial = random_start(n, seed, "clustered", 4.0)
    with RecordWriter(path) as rec:
        run_lockstep(
            initial, Params(n, 4.0), make_scheduler(scheduler, n, seed), seed=seed, record=rec
        )
    return read_record(path)


def assert_same_run(net: RunRecord, lock: RunRecord) -> None:
    """The same run, header aside, with no tolerance: every round's active set, paths, distances,
    positions and contacts, and the result with its figures, equal bit for bit."""
    assert np.array_equal(net.header.initial, lock.header.initial)
    assert (net.header.algorithm, net.header.params) == (lock.header.algorithm, lock.header.params)
    assert len(net.rounds) == len(lock.rounds), (len(net.rounds), len(lock.rounds))
    for a, b in zip(net.rounds, lock.rounds, strict=True):
        assert (a.round, a.active, a.moves, a.collisions, a.extra) == (
            b.round,
            b.active,
            b.moves,
            b.collisions,
            b.extra,
        ), f"round {a.round}"
        assert np.array_equal(a.positions, b.positions), f"round {a.round}"
    assert net.result is not None and lock.result is not None
    assert (net.result.status, net.result.rounds, net.result.extra) == (
        lock.result.status,
        lock.result.rounds,
        lock.result.extra,
    )
    for name in result_figures():  # the result line's figures, typed
        assert getattr(net.result, name) == getattr(lock.result, name), name
    assert np.array_equal(net.result.positions, lock.result.positions)


def descendants_of(pid: int) -> list[int]:
    """Every process below `pid` (children, grandchildren, ...), read from /proc."""
    parent: dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parent[int(stat.parent.name)] = int(stat.read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
    out, frontier = [], [pid]
    while frontier:
        kids = [p for p, pp in parent.items() if pp in frontier]
        out += kids
        frontier = kids
    return out


def running(pid: int) -> bool:
    """Whether process `pid` exists and is not a zombie (read from /proc)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"
