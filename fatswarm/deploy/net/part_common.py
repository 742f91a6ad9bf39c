"""What every networked part (deploy/net/parts.py) shares: stop signals, logging, the common
flags, the client configuration, and the check that a swarm has one world and one coordinator."""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
from typing import Any

from fatswarm.deploy.net.zconf import (
    CONNECT_DEADLINE_S,
    add_zenoh_arguments,
    connect_endpoints,
    make_config,
    token_held,
)
from fatswarm.domain.outcome import ExitCode

DEFAULT_ROUTER_LISTEN = "tcp/127.0.0.1:7447"
PARENT_POLL_S = 0.5
MAX_LOG_CHARS = 300  # a log message longer than this is cut (ShortLines)


def part_command(*args: str) -> list[str]:
    """The argv that starts a part as a child: `python -P -m fatswarm.deploy.net.parts ARGS`. -P:
    the child imports fatswarm as installed, never a `fatswarm` folder of the current directory,
    which `-m` alone puts first on sys.path (a run started from the parent of a clone)."""
    return [sys.executable, "-P", "-m", "fatswarm.deploy.net.parts", *args]


def install_stop_signals(parent: int | None = None) -> threading.Event:
    """An event set by SIGTERM or SIGINT (or when process `parent` is gone), so a part closes its
    session and exits cleanly; the parent watch makes a killed launcher leave nothing behind."""
    stop = threading.Event()

    def handler(signum: int, frame: object) -> None:
        del signum, frame
        stop.set()

    signal.signal(signal.SIGTERM, handler)
    signal.signal(signal.SIGINT, handler)
    if parent is not None:

        def watch() -> None:
            while not stop.wait(PARENT_POLL_S):
                if os.getppid() != parent:  # as a signal: it also ends a wait in the main thread
                    os.kill(os.getpid(), signal.SIGTERM)
                    return

        threading.Thread(target=watch, name="parent-watch", daemon=True).start()
    return stop


class ShortLines(logging.Filter):
    """Cuts a log message to MAX_LOG_CHARS, saying how much was cut: a peer's garbage quoted in a
    refusal must not become megabytes of log in every process that receives it."""

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        if len(message) > MAX_LOG_CHARS:
            record.msg = (
                f"{message[:MAX_LOG_CHARS]}... ({len(message) - MAX_LOG_CHARS} more characters cut)"
            )
            record.args = None
        return True


class PlainLines(logging.Formatter):
    """A log message as one plain line for a person, "fatswarm world: <message>": the format of
    a part that `fatswarm run` started, whose stderr is the user's terminal (`--plain-log`)."""

    def formatMessage(self, record: logging.LogRecord) -> str:
        return f"{record.name.replace('.', ' ')}: {record.getMessage()}"


LOG_FORMAT = "%(asctime)s %(name)s[%(process)d] %(levelname)s %(message)s"


def setup_logging(args: argparse.Namespace, default: str) -> None:
    """Log to stderr at --log-level (else `default`), each message cut by ShortLines, in plain
    lines with `--plain-log` (the launcher's), else with time, process and level."""
    level = getattr(args, "log_level", None) or default
    logging.basicConfig(level=level.upper(), format=LOG_FORMAT, stream=sys.stderr)
    for handler in logging.getLogger().handlers:
        handler.addFilter(ShortLines())
        if getattr(args, "plain_log", False):
            handler.setFormatter(PlainLines())


def fail(part: str, message: str) -> int:
    """Say `message` on stderr as the `part`'s one line; exit 2 (bad input)."""
    print(f"fatswarm {part}: {message}", file=sys.stderr)
    return ExitCode.BAD_INPUT


def second_of_role(
    session: Any, part: str, swarm: str, key: str, stop: threading.Event
) -> str | None:
    """The line refusing a second `part` (world, coordinator) on `swarm`, or None if it is alone.

    Asked before this one declares its own liveliness token `key` or does anything visible: two
    worlds or coordinators on one swarm would mix their rounds silently and report false collisions.
    """
    if not token_held(session, key, stop):
        return None
    return (
        f"swarm {swarm!r} already has a {part} on this router network; stop it or pick "
        "another --swarm"
    )


GIVES_UP = f"; if no router answers within {CONNECT_DEADLINE_S:g} s, it says so and exits with 2"
KEEPS_WAITING = "; until a router answers it keeps retrying and says so every {:g} s on stderr"


ROBOT_PLACEHOLDER = "{robot}"  # in an agent's --config, replaced by its robot id


def add_common_arguments(
    p: argparse.ArgumentParser, connect_note: str = "", config_note: str = "", *, swarm: bool = True
) -> None:
    """The flags every part takes: Zenoh's (`--connect`, `--listen`, `--swarm`), `--config`,
    `--log-level` and the launcher's hidden `--exit-with-parent` and `--plain-log`."""
    add_zenoh_arguments(p, connect_note=connect_note, swarm=swarm)
    p.add_argument(
        "--config",
        default=None,
        metavar="FILE",
        help="Zenoh's own configuration file (JSON5, JSON or YAML), e.g. one written by "
        "`fatswarm secure` (TLS, access control); relative certificate paths in it are "
        "read from its folder. On top of it this part sets its mode, multicast "
        "scouting off, message size limit and lease, and the --connect/--listen "
        "endpoints given (the file's stay where none are given); the file wins for "
        "everything else" + config_note,
    )
    p.add_argument(
        "--log-level",
        choices=("debug", "info", "warning", "error"),
        default=None,
        help="log level on stderr",
    )
    p.add_argument(
        "--exit-with-parent", type=int, default=None, metavar="PID", help=argparse.SUPPRESS
    )  # the launcher's pid: stop when it is gone
    p.add_argument(
        "--plain-log", action="store_true", help=argparse.SUPPRESS
    )  # the launcher's: log lines as `fatswarm world: ...`, for the person at its terminal


def client_config(
    args: argparse.Namespace,
    lease_ms: int | None = None,
    shared_memory: bool = True,
    robot: int | None = None,
) -> Any:
    """The part's client config; raises ValueError (ZenohSetupError) saying what to fix."""
    config = config_for(args.config, robot)
    if not args.connect and config is None:
        raise ValueError("give the router to use with --connect ENDPOINT (e.g. tcp/127.0.0.1:7447)")
    conf = make_config(
        "client",
        connect=args.connect,
        listen=args.listen,
        lease_ms=lease_ms,
        shared_memory=shared_memory,
        config_file=config,
    )
    if not connect_endpoints(conf):
        raise ValueError(
            f"give the router to use with --connect ENDPOINT (--config {config} "
            "names none in connect/endpoints)"
        )
    return conf


def config_for(config: str | None, robot: int | None) -> str | None:
    """An agent's --config file: ROBOT_PLACEHOLDER replaced by its robot id."""
    if config is None or robot is None:
        return config
    return config.replace(ROBOT_PLACEHOLDER, str(robot))
