"""A Zenoh router in a Python process (the wheel embeds the Rust router; no zenohd needed)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Sequence
from typing import Any

from fatswarm.deploy.zconf import ZenohSetupError, explain_zenoh_error, make_config

log = logging.getLogger("fatswarm.router")


def open_router(listen: Sequence[str], connect: Sequence[str] = ()) -> Any:
    """An open router session listening on `listen` (and linked to the routers in `connect`).

    Raises ZenohSetupError (a ValueError) for a malformed endpoint or one it cannot listen on.
    """
    import zenoh

    if not listen:
        raise ValueError("a router needs at least one --listen endpoint, e.g. tcp/127.0.0.1:7447")
    conf = make_config("router", connect=connect, listen=listen)
    try:
        return zenoh.open(conf)
    except zenoh.ZError as exc:  # routers retry their --connect links: this is about listening
        why = explain_zenoh_error(exc)
        if not why.startswith("cannot listen on "):
            why = f"cannot listen on {', '.join(listen)}: {why}"
        raise ZenohSetupError(why) from None


def run_router(listen: Sequence[str], connect: Sequence[str], stop: threading.Event) -> int:
    """Route until `stop` is set; returns an exit code."""
    with open_router(listen, connect):
        log.info("router listening on %s", ", ".join(listen))
        while not stop.wait(0.5):
            pass
    return 0
