"""`fatswarm coordinator`: the coordinator process alone (it decides who is active in each round),
for a swarm over several hosts."""

from __future__ import annotations

import argparse

from fatswarm.coordinator.protocol import alive_key
from fatswarm.coordinator.schedule import NAMES, ScheduleError, Scheduler, make_scheduler
from fatswarm.deploy.net.part_common import (
    GIVES_UP,
    add_common_arguments,
    client_config,
    fail,
    install_stop_signals,
    second_of_role,
    setup_logging,
)
from fatswarm.deploy.net.zconf import open_client


def add_coordinator_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm coordinator` (n comes from the world)."""
    add_common_arguments(p, GIVES_UP)
    p.add_argument("--seed", type=int, default=0, metavar="S", help="seed of the scheduler")
    p.add_argument("--scheduler", choices=NAMES, default="ssync", help="who is active each round")
    p.add_argument("--schedule", metavar="PATH", help="scripted scheduler's JSON or run record")
    p.add_argument(
        "--fairness",
        type=int,
        default=None,
        metavar="K",
        help="every robot active at least once in every K rounds (default 2n)",
    )
    p.add_argument(
        "--move-timeout",
        type=float,
        default=5.0,
        metavar="SECONDS",
        help="an active robot that has not moved by then stays put (default 5)",
    )
    p.add_argument(
        "--start-timeout",
        type=float,
        default=120.0,
        metavar="SECONDS",
        help="wait this long for all n agents before round 1 (default 120)",
    )
    p.add_argument(
        "--give-up",
        type=float,
        default=120.0,
        metavar="SECONDS",
        help="when the world has given no usable answer for this long (gone for good), say so "
        "in one line and exit with 5 (default 120; a world restarted on a long async record "
        "replays it before it answers)",
    )
    p.add_argument(
        "--pace",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="least time per round, to watch a run unfold (default 0: full speed)",
    )


def main_coordinator(args: argparse.Namespace) -> int:
    """Run rounds until the run ends; exit 0 formed, 1 not formed, 3 formed with collisions,
    5 the world gave no usable answer for --give-up seconds."""
    # here, not at the top: the coordinator's shell (and zenoh) load only when it runs
    from fatswarm.coordinator.service import Coordinator, CoordinatorConfig

    setup_logging(args, "info")
    stop = install_stop_signals(args.exit_with_parent)

    def scheduler_for(n: int) -> Scheduler:
        return make_scheduler(args.scheduler, n, args.seed, args.schedule, args.fairness)

    try:
        conf = client_config(args)
        if args.move_timeout <= 0 or args.start_timeout < 0 or args.pace < 0:
            raise ValueError("--move-timeout must be > 0, --start-timeout and --pace >= 0")
        if not args.give_up > 0:
            raise ValueError(f"--give-up must be > 0 seconds, got {args.give_up}")
        cfg = CoordinatorConfig(
            args.swarm,
            args.move_timeout,
            args.start_timeout,
            args.pace,
            scheduler=args.scheduler,
            give_up_s=args.give_up,
        )
        token = alive_key(args.swarm)  # a bad --swarm is said before any wait
        session = open_client(conf, stop)
        if session is None:
            return 1  # stopped before a router answered: not formed
        refusal = second_of_role(session, "coordinator", args.swarm, token, stop)
        if refusal is not None or stop.is_set():
            session.close()
            return 1 if refusal is None else fail("coordinator", refusal)
        return Coordinator(cfg, scheduler_for, stop).run(session)
    except (ValueError, ScheduleError) as exc:
        return fail("coordinator", str(exc))
