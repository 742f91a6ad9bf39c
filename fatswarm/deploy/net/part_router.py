"""`fatswarm router`: a Zenoh router alone (deploy/net/router.py), for a swarm over hosts."""

from __future__ import annotations

import argparse

from fatswarm.deploy.net.part_common import (
    DEFAULT_ROUTER_LISTEN,
    add_common_arguments,
    fail,
    install_stop_signals,
    setup_logging,
)
from fatswarm.deploy.net.router import run_router


def add_router_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm router` (no --swarm: a router routes every swarm)."""
    add_common_arguments(p, swarm=False)


def main_router(args: argparse.Namespace) -> int:
    """Run a router until SIGTERM/SIGINT."""
    setup_logging(args, "info")
    stop = install_stop_signals(args.exit_with_parent)
    try:
        return run_router(args.listen, args.connect, stop, args.config, [DEFAULT_ROUTER_LISTEN])
    except ValueError as exc:
        return fail("router", str(exc))
