"""The flags and helpers `fatswarm sweep` and `fatswarm hunt` share (each a grid or a search of
lock-step runs on worker processes): the algorithm's parameters, the sizes, the schedulers, the
adversary's lists, the round cap, the workers and quiet, the worker count, and the signal guard of
the pool loop. Each command adds its own words to a flag's help where they differ; a list flag
refuses an empty item (`flags.comma_list`)."""

from __future__ import annotations

import argparse
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

from fatswarm.deploy.flags import comma_list
from fatswarm.deploy.sweep.executor import add_cluster_argument
from fatswarm.deploy.sweep.grid import SweepInputError


def add_param_argument(p: argparse.ArgumentParser, whose: str) -> None:
    """`--param NAME=VALUE` (repeatable): one of `whose` parameters, the same in every run."""
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help=f"a parameter of {whose}, the same in every run (repeatable)",
    )


def add_sizes_argument(p: argparse.ArgumentParser, what: str, default: str) -> None:
    """`-n`/`--n SIZES`: numbers of robots (lists and LOW..HIGH[:STEP] ranges)."""
    p.add_argument(
        "-n",
        "--n",
        action="append",
        type=comma_list("-n"),
        default=[],
        metavar="SIZES",
        dest="n",
        help=f"numbers of robots {what} (default {default})",
    )


def add_scheduler_argument(p: argparse.ArgumentParser, what: str, usable: str) -> None:
    """`--scheduler NAMES`: the schedulers (models) the runs are under."""
    p.add_argument(
        "--scheduler",
        action="append",
        type=comma_list("--scheduler"),
        default=[],
        metavar="NAMES",
        help=f"schedulers (models) {what}: {usable} (default: all of them)",
    )


def add_adversary_arguments(p: argparse.ArgumentParser, *, lists: bool) -> None:
    """`--non-rigid` and `--crash`: lists of the adversary's settings (`lists`: an axis of a
    sweep) or one value taken by every run (a hunt)."""
    p.add_argument(
        "--non-rigid",
        action="append",
        type=comma_list("--non-rigid"),
        default=[],
        metavar="DELTAS" if lists else "DELTA",
        help="non-rigid adversaries' deltas (> 0, robot radii) and/or 'rigid', e.g. "
        "rigid,1,0.1 (default rigid: rigid moves only)"
        if lists
        else "non-rigid moves in every run: the adversary may stop a move after DELTA (> 0, "
        "robot radii), or 'rigid' (default rigid: rigid moves)",
    )
    p.add_argument(
        "--crash",
        action="append",
        type=comma_list("--crash"),
        default=[],
        metavar="COUNTS" if lists else "F",
        help="crash counts F (F robots crash for good, 0 < F < n; a cell with F >= n "
        "is left out) and/or 0 or 'none', e.g. 0,1,2 (default none)"
        if lists
        else "F robots crash for good in every run (n is then drawn above F), or 0 or 'none' "
        "(default none)",
    )


def add_max_rounds_argument(p: argparse.ArgumentParser) -> None:
    """`--max-rounds R`: the round cap of every run."""
    p.add_argument(
        "--max-rounds",
        type=int,
        default=None,
        metavar="R",
        help="round cap of every run (default: the scheduler's for n, as fatswarm run)",
    )


def add_jobs_argument(p: argparse.ArgumentParser) -> None:
    """`--jobs J` and `--cluster`: where the runs go."""
    p.add_argument(
        "--jobs",
        type=int,
        default=None,
        metavar="J",
        help="worker processes (default: one per core)",
    )
    add_cluster_argument(p)


def add_quiet_argument(p: argparse.ArgumentParser) -> None:
    """`-q`/`--quiet`: no progress while running."""
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no progress while running (the summary is still printed)",
    )


def jobs_of(given: int | None) -> int:
    """The worker processes `--jobs` asks for (default: the cores this process may use);
    SweepInputError for fewer than 1."""
    if given is None:
        affinity = getattr(os, "sched_getaffinity", None)
        return len(affinity(0)) if affinity is not None else (os.cpu_count() or 1)
    if given < 1:
        raise SweepInputError(f"--jobs must be at least 1, got {given}")
    return int(given)


@contextmanager
def stop_on_signals() -> Iterator[list[int | None]]:
    """While inside, Ctrl-C and SIGTERM only set the flag yielded (`[signal number]`), so the
    pool loop stops at a step of its own choosing: no row is half written, no worker left."""
    stopped: list[int | None] = [None]
    if threading.current_thread() is not threading.main_thread():
        yield stopped
        return

    def note(signum: int, frame: FrameType | None) -> None:
        stopped[0] = stopped[0] or signum

    previous = {sig: signal.signal(sig, note) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stopped
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


__all__ = [
    "add_adversary_arguments",
    "add_jobs_argument",
    "add_max_rounds_argument",
    "add_param_argument",
    "add_quiet_argument",
    "add_scheduler_argument",
    "add_sizes_argument",
    "jobs_of",
    "stop_on_signals",
]
