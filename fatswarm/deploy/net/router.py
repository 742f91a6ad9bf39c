"""A Zenoh router in a Python process (the wheel embeds the Rust router; no zenohd needed)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Sequence
from typing import Any

from fatswarm.deploy.net.zconf import (
    ZenohSetupError,
    explain_zenoh_error,
    listen_endpoints,
    make_config,
)

log = logging.getLogger("fatswarm.router")


def router_config(
    listen: Sequence[str],
    connect: Sequence[str] = (),
    config: str | None = None,
    default_listen: Sequence[str] = (),
    shared_memory: bool = True,
) -> Any:
    """The router's Zenoh config: listening on `listen`, linked to the routers in `connect`.

    `config`: Zenoh's configuration file to start from (`--config`, see `zconf.make_config`); its
    endpoints count where `listen` or `connect` give none, then `default_listen`.
    Raises ZenohSetupError (a ValueError) for a malformed endpoint or file, ValueError if it would
    listen nowhere.
    """
    conf = make_config(
        "router",
        connect=connect,
        listen=listen,
        config_file=config,
        default_listen=default_listen,
        shared_memory=shared_memory,
    )
    if not listen_endpoints(conf):
        raise ValueError("a router needs at least one --listen endpoint, e.g. tcp/127.0.0.1:7447")
    return conf


def open_router(
    listen: Sequence[str],
    connect: Sequence[str] = (),
    config: str | None = None,
    default_listen: Sequence[str] = (),
    shared_memory: bool = True,
) -> Any:
    """An open router session (see `router_config`).

    Raises ZenohSetupError (a ValueError) for a malformed endpoint or one it cannot listen on, and
    for access control that the file sets up wrong.
    """
    return _open(router_config(listen, connect, config, default_listen, shared_memory), config)


def _open(conf: Any, config: str | None) -> Any:
    import zenoh  # the CLI imports this module for the router's flags: zenoh loads when one opens

    try:
        return zenoh.open(conf)
    except zenoh.ZError as exc:  # routers retry their --connect links: this is about listening
        why = explain_zenoh_error(exc)
        if why.startswith("access control"):  # the file's ACL does not hold together
            why = f"--config {config}: {why}"
        elif not why.startswith("cannot listen on "):
            why = f"cannot listen on {', '.join(listen_endpoints(conf))}: {why}"
        raise ZenohSetupError(why) from None


def run_router(
    listen: Sequence[str],
    connect: Sequence[str],
    stop: threading.Event,
    config: str | None = None,
    default_listen: Sequence[str] = (),
) -> int:
    """Route until `stop` is set; returns an exit code."""
    conf = router_config(listen, connect, config, default_listen)
    with _open(conf, config):
        log.info("router listening on %s", ", ".join(listen_endpoints(conf)))
        while not stop.wait(0.5):
            pass
    return 0
