"""The networked `fatswarm run`'s own flags (a lock-step run refuses them) and the default pace
that lets a person follow the run on the live dashboard (deploy/net/launcher.py runs it)."""

from __future__ import annotations

import argparse
import sys

from fatswarm.deploy.engine.estimate import expected_rounds_per_step
from fatswarm.deploy.net.zconf import DEFAULT_SWARM, ROUTER_ENDPOINT_HELP

WATCH_S = 15.0  # a watched run (live dashboard, no --pace) lasts about this long
MIN_WATCH_PACE_S, MAX_WATCH_PACE_S = 0.02, 1.0


def add_network_arguments(p: argparse.ArgumentParser) -> None:
    """The networked run's flags on top of the lockstep ones (a lockstep run refuses them)."""
    g = p.add_argument_group("networked run (default; not with --lockstep)")
    flags = [
        g.add_argument(
            "--connect",
            action="append",
            default=[],
            metavar="ENDPOINT",
            help="use this router instead of the one the world process hosts; "
            f"{ROUTER_ENDPOINT_HELP}",
        ),
        g.add_argument(
            "--listen",
            action="append",
            default=[],
            metavar="ENDPOINT",
            help="endpoint(s) of the router that the world process hosts (default: a "
            "free loopback port)",
        ),
        g.add_argument(
            "--swarm",
            default=None,
            help=f"swarm name, keys under fatswarm/<swarm>/ (default {DEFAULT_SWARM!r} "
            "on the world's own router, a fresh random name with --connect)",
        ),
        g.add_argument(
            "--move-timeout",
            type=float,
            default=5.0,
            metavar="SECONDS",
            help="an active robot that has not moved by then stays put (default 5; finite, > 0)",
        ),
        g.add_argument(
            "--pace",
            type=float,
            default=None,
            metavar="SECONDS",
            help="least time per round, to watch a run unfold (finite, >= 0; 0: full "
            f"speed). Default: with the live dashboard, about {WATCH_S:g} s for a "
            "typical run; else 0",
        ),
        g.add_argument(
            "--spawn",
            choices=("fork", "exec"),
            default="fork",
            help="agent processes forked from one preloaded host process before any "
            "Zenoh session exists (fork, fast) or one fresh interpreter each (exec)",
        ),
    ]
    # what `fatswarm run --lockstep` refuses when given (deploy.run.networked_flags_given)
    p.set_defaults(_networked_flags=tuple((a.option_strings[-1], a.dest, a.default) for a in flags))


def watchable_pace(n: int, scheduler: str) -> float:
    """Seconds per round that make a typical run last about WATCH_S, so a person can follow it
    (the algorithm's steps times the rounds a step takes under `scheduler`), within bounds."""
    rounds = expected_rounds_per_step(n, scheduler) * (n + 2)
    return min(MAX_WATCH_PACE_S, max(MIN_WATCH_PACE_S, WATCH_S / rounds))


def live_dashboard(args: argparse.Namespace) -> bool:
    """Whether this run shows the live dashboard (a terminal, not --no-dashboard or --json)."""
    plain = getattr(args, "no_dashboard", False) or getattr(args, "json", False)
    return not plain and sys.stdout.isatty()
