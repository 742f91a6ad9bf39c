"""The one place that builds Zenoh configurations: mode, endpoints, no multicast scouting, lease.

Defaults changed between Zenoh releases, so every setting the services rely on is explicit here.
"""

from __future__ import annotations

import argparse
import json
import socket
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import zenoh

DEFAULT_SWARM = "default"
# Agents announce a short lease so a hung (SIGSTOPped) agent is declared gone within ~2 s; a killed
# one is seen at once through its closed TCP link (see shared zenoh notes: 1.7 s at 2000 ms).
AGENT_LEASE_MS = 2000
ROUTER_ENDPOINT_HELP = "Zenoh endpoint, e.g. tcp/127.0.0.1:7447"


def make_config(
    mode: str,
    connect: Sequence[str] = (),
    listen: Sequence[str] = (),
    lease_ms: int | None = None,
    shared_memory: bool = True,
) -> zenoh.Config:
    """A Zenoh config with multicast (and gossip) scouting off and the given endpoints."""
    import zenoh

    if mode not in ("client", "peer", "router"):
        raise ValueError(f"mode must be client, peer or router, got {mode!r}")
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(mode))
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("connect/endpoints", json.dumps(list(connect)))
    conf.insert_json5("listen/endpoints", json.dumps(list(listen)))
    if not shared_memory:
        # Agents send and receive small messages only; no 16 MB SHM pool per process.
        conf.insert_json5("transport/shared_memory/enabled", "false")
    if lease_ms is not None:
        conf.insert_json5("transport/link/tx/lease", str(int(lease_ms)))
    return conf


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port that was free a moment ago on `host` (the OS picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        port: int = s.getsockname()[1]
        return port


def loopback_endpoint() -> str:
    """`tcp/127.0.0.1:<free port>`."""
    return f"tcp/127.0.0.1:{free_port()}"


def add_zenoh_arguments(p: argparse.ArgumentParser, listen_default: Sequence[str] = ()) -> None:
    """`--connect`, `--listen` (repeatable) and `--swarm`, shared by every networked command."""
    p.add_argument(
        "--connect",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help=f"router to connect to (repeatable); {ROUTER_ENDPOINT_HELP}",
    )
    p.add_argument(
        "--listen",
        action="append",
        default=list(listen_default),
        metavar="ENDPOINT",
        help="endpoint to listen on (repeatable)",
    )
    p.add_argument(
        "--swarm",
        default=DEFAULT_SWARM,
        help=f"swarm name: all keys live under fatswarm/<swarm>/ (default {DEFAULT_SWARM!r})",
    )
