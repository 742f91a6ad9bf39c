"""What a networked run of n robots costs this machine before it starts (memory, processes and
threads, sockets, start-up time), from figures measured on agent processes, and whether the
machine can hold it: `fatswarm run` refuses one that it cannot, unless `--force`."""

from __future__ import annotations

import math
import resource
from dataclasses import dataclass
from typing import Final

# Measured on a 2-core, 24 GB VM shared with other work (`fatswarm run -n N --no-dashboard`, the
# proportional set size of each process from /proc/PID/smaps_rollup after a few rounds, and the
# time until the world's state says every agent is alive), issue 21:
#   fork: an agent 5.2-6.3 MB (it shares the preloaded interpreter with its host), 4-5 threads;
#         every agent alive 1.0 s after the router at n = 128, 1.9 s at 256, 5.3 s at 512
#   exec: an agent 22 MB (a fresh interpreter each), 6 threads; 3.7 s at n = 32, 9.5 s at 96
#   the world 30 MB + 0.14 MB an agent (the router's links), the coordinator 23 MB, the agents'
#   host 5 MB (fork) or 21 MB (exec)
# Rounded up: an estimate should not promise what the machine then cannot keep.
AGENT_MB: Final = {"fork": 6.5, "exec": 24.0}
AGENT_START_S: Final = {"fork": 0.011, "exec": 0.11}
AGENT_THREADS: Final = {"fork": 5, "exec": 6}
PARTS_MB: Final = 80.0  # the world, the coordinator and the agents' host, without agents
WORLD_MB_PER_AGENT: Final = 0.2
PARTS_START_S: Final = 1.0  # the world's router listening, the coordinator and host started
PARTS_THREADS: Final = 64  # the world's (its router's runtime grows with load), coordinator, host
FILES_PER_AGENT: Final = 2  # the world's router: the agent's link, and a margin
FILES_SPARE: Final = 256  # the world's own files, the record, the launcher's link
ESTIMATE_FROM_N: Final = 200  # a run this large says what it costs before it starts (as lock step)
ESTIMATE_FROM_S: Final = 5.0  # ... as does one whose agents take this long to start
ESTIMATE_FROM_SHARE: Final = 0.5  # ... or one taking this share of the memory available


@dataclass(frozen=True, slots=True)
class NetEstimate:
    """What a networked run of `n` robots needs on this machine (the agents all run here)."""

    n: int
    spawn: str
    processes: int  # world, coordinator, the agents' host and n agents
    memory_mb: float
    startup_s: float  # until every agent is up
    threads: int
    files: int  # open files the world (hosting the router) needs


@dataclass(frozen=True, slots=True)
class Machine:
    """What this machine has to give (None where it cannot be read)."""

    memory_mb: float | None  # available memory (the cgroup's limit, if lower)
    threads: int | None  # tasks (processes and threads) that may still start
    files: tuple[int, int]  # the open-files limit (soft, hard) children inherit


def estimate_networked(n: int, spawn: str) -> NetEstimate:
    """The cost of a networked run of `n` agent processes started by `spawn` (fork or exec)."""
    return NetEstimate(
        n=n,
        spawn=spawn,
        processes=n + 3,
        memory_mb=PARTS_MB + n * (AGENT_MB[spawn] + WORLD_MB_PER_AGENT),
        startup_s=PARTS_START_S + n * AGENT_START_S[spawn],
        threads=PARTS_THREADS + n * AGENT_THREADS[spawn],
        files=FILES_SPARE + n * FILES_PER_AGENT,
    )


def this_machine() -> Machine:
    """Read what this machine (Linux: /proc, the cgroup, the resource limits) has to give."""
    return Machine(_available_mb(), _free_tasks(), resource.getrlimit(resource.RLIMIT_NOFILE))


def problem(est: NetEstimate, machine: Machine) -> str | None:
    """Why this machine cannot hold the run (one line, what to do), or None."""
    what = f"-n {est.n} starts {est.processes:,} processes"
    instead = "use fewer robots or --lockstep (one process), or pass --force to start it anyway"
    if machine.memory_mb is not None and est.memory_mb > machine.memory_mb:
        return (
            f"{what}, about {_size(est.memory_mb)} of memory, and only "
            f"{_size(machine.memory_mb)} is available: {instead}"
        )
    if machine.threads is not None and est.threads > machine.threads:
        return (
            f"{what} of about {est.threads:,} threads, and only {machine.threads:,} more may "
            f"start here (pid_max, threads-max, ulimit -u): {instead}"
        )
    hard = machine.files[1]
    if hard != resource.RLIM_INFINITY and est.files > hard:
        return (
            f"{what}: the router needs about {est.files:,} open files, and `ulimit -Hn` allows "
            f"{hard:,}: {instead}"
        )
    return None


def worth_saying(est: NetEstimate, machine: Machine) -> bool:
    """Whether the run is large or long enough to print its estimate before it starts."""
    share = machine.memory_mb is not None and est.memory_mb >= ESTIMATE_FROM_SHARE * (
        machine.memory_mb
    )
    return est.n >= ESTIMATE_FROM_N or est.startup_s >= ESTIMATE_FROM_S or share


def estimate_text(est: NetEstimate, machine: Machine) -> str:
    """The line a large networked run prints before it starts (to stderr)."""
    free = "" if machine.memory_mb is None else f" of {_size(machine.memory_mb)} available"
    return (
        f"estimate for n={est.n} networked (measured per agent, not a promise): "
        f"{est.processes:,} processes ({est.spawn}), ~{_size(est.memory_mb)} of memory{free}, "
        f"agents up in ~{_seconds(est.startup_s)}"
    )


def raise_open_files(est: NetEstimate) -> None:
    """Raise this process's soft open-files limit (children inherit it) as far as the run needs
    and the hard limit allows: a 1024 default would stop the router at about 1,000 agents."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft == resource.RLIM_INFINITY or soft >= est.files:
        return
    wanted = est.files if hard == resource.RLIM_INFINITY else min(est.files, hard)
    if wanted > soft:
        resource.setrlimit(resource.RLIMIT_NOFILE, (wanted, hard))


def _available_mb() -> float | None:
    """MemAvailable, or what the cgroup (v2) still allows if less; None off Linux."""
    meminfo = _read("/proc/meminfo")
    available = None
    for line in meminfo.splitlines():
        if line.startswith("MemAvailable:"):
            available = int(line.split()[1]) / 1024
    limit, used = _read("/sys/fs/cgroup/memory.max"), _read("/sys/fs/cgroup/memory.current")
    if limit.strip().isdigit() and used.strip().isdigit():
        left = (int(limit) - int(used)) / 2**20
        available = left if available is None else min(available, left)
    return available


def _free_tasks() -> int | None:
    """How many more tasks (processes and threads) may start: the least of pid_max, threads-max
    and the user's process limit, less the tasks running now (/proc/loadavg); None off Linux."""
    loadavg = _read("/proc/loadavg").split()
    if len(loadavg) < 4 or "/" not in loadavg[3]:
        return None
    running = int(loadavg[3].split("/")[1])
    limits = [
        int(text)
        for text in (_read("/proc/sys/kernel/pid_max"), _read("/proc/sys/kernel/threads-max"))
        if text.strip().isdigit()
    ]
    nproc = resource.getrlimit(resource.RLIMIT_NPROC)[0]
    if nproc != resource.RLIM_INFINITY:
        limits.append(nproc)
    return min(limits) - running if limits else None


def _read(path: str) -> str:
    try:
        with open(path, encoding="ascii") as fh:
            return fh.read()
    except (OSError, UnicodeDecodeError):
        return ""


def _size(mb: float) -> str:
    return f"{mb / 1024:.1f} GB" if mb >= 1024 else f"{max(1, math.ceil(mb))} MB"


def _seconds(seconds: float) -> str:
    return f"{seconds / 60:.1f} min" if seconds >= 90 else f"{max(1, round(seconds))} s"


__all__ = [
    "Machine",
    "NetEstimate",
    "estimate_networked",
    "estimate_text",
    "problem",
    "raise_open_files",
    "this_machine",
    "worth_saying",
]
