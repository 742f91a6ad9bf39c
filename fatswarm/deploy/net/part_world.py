"""`fatswarm world`: the world process alone (optionally hosting the Zenoh router), for a swarm
over several hosts; its run record is its durable log, resumed after its last round."""

from __future__ import annotations

import argparse
import json
import logging
import os
import secrets
import sys
from typing import TYPE_CHECKING, Any

from fatswarm.coordinator.schedule import NAMES
from fatswarm.deploy.engine.config import input_errors, resolve_start
from fatswarm.deploy.flags import add_algorithm_arguments
from fatswarm.deploy.net.part_common import (
    DEFAULT_ROUTER_LISTEN,
    GIVES_UP,
    add_common_arguments,
    client_config,
    fail,
    install_stop_signals,
    second_of_role,
    setup_logging,
)
from fatswarm.deploy.net.router import open_router
from fatswarm.deploy.net.zconf import open_client, settle_runtime
from fatswarm.deploy.scenarios.starts import KINDS
from fatswarm.domain.adversary import ASYNC_NAMES
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.seam import AlgorithmFailure
from fatswarm.world.protocol import alive_key
from fatswarm.world.record import RecordFormatError, RecordWriter
from fatswarm.world.record_read import read_record

if TYPE_CHECKING:
    from fatswarm.world.core import WorldCore
    from fatswarm.world.setup import WorldSetup


def add_world_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm world` (the start flags matter only for a new state file)."""
    add_common_arguments(p, GIVES_UP)
    p.add_argument(
        "--state",
        required=True,
        metavar="PATH",
        help="run record = durable log; an existing one is resumed after its last round",
    )
    p.add_argument("-n", type=int, default=8, metavar="N", help="number of robots (default 8)")
    p.add_argument(
        "-a",
        type=float,
        default=None,
        metavar="A",
        help="the paper's least polygon side (> 3): --param a=A",
    )
    add_algorithm_arguments(p)
    p.add_argument("--seed", type=int, default=0, metavar="S", help="seed of the random start")
    p.add_argument("--init", metavar="PATH", help='JSON {"positions": [[x, y], ...], "a": 4.0}')
    p.add_argument("--start", choices=KINDS, default="clustered", help="kind of random start")
    p.add_argument(
        "--scheduler",
        choices=NAMES,
        default="ssync",
        help="scheduler name written to the record (the coordinator runs it)",
    )
    p.add_argument(
        "--max-rounds",
        type=int,
        default=None,
        metavar="R",
        help="end as max_rounds after R rounds (default: as lockstep)",
    )
    p.add_argument(
        "--header", default=None, metavar="JSON", help=argparse.SUPPRESS
    )  # the launcher's extra header fields (a JSON object)
    p.add_argument(
        "--no-fsync",
        action="store_true",
        help="do not fsync each round (faster; a crash may lose announced rounds)",
    )
    p.add_argument(
        "--router",
        action="store_true",
        help="host the Zenoh router in the world process: it listens on --listen "
        f"(default {DEFAULT_ROUTER_LISTEN}) and links to the routers given with "
        "--connect; the other parts connect to it, so every message to or from the "
        "world crosses one hop less (what `fatswarm run` does). No access control: "
        "not with --config (a secured swarm uses `fatswarm router --config`)",
    )


def main_world(args: argparse.Namespace) -> int:
    """Run the world until SIGTERM/SIGINT."""
    # here, not at the top: the world's shell (and zenoh) load only when it runs
    from fatswarm.world.service import serve

    setup_logging(args, "info")
    stop = install_stop_signals(args.exit_with_parent)
    bad_input: tuple[type[Exception], ...] = (ValueError, RecordFormatError, *input_errors())
    try:
        if args.router and args.config is not None:
            raise ValueError(
                "--router hosts a router without access control: for a secured "
                "swarm run `fatswarm router --config FILE` and connect the world "
                "to it with --config"
            )
        # No shared memory: the world's messages are small, and Zenoh maps a 16 MB segment into
        # it on the first large one a peer sends (measured: 55 -> 75 MB at once, for good)
        conf = None if args.router else client_config(args, shared_memory=False)
        token = alive_key(args.swarm)  # a bad --swarm is said before any wait
        fresh = _fresh_setup(args)
        settle_runtime()
        if args.router:  # listening fails at once (port taken): nothing to wait for
            session = open_router(
                args.listen, args.connect, None, [DEFAULT_ROUTER_LISTEN], shared_memory=False
            )
        else:
            assert conf is not None
            session = open_client(conf, stop)
    except bad_input as exc:
        return fail("world", str(exc))
    if session is None:
        return 0  # stopped before a router answered
    # Nothing visible before this check: no state file created or cut, no token, no state.
    refusal = second_of_role(session, "world", args.swarm, token, stop)
    if refusal is not None or stop.is_set():
        session.close()
        return 0 if refusal is None else fail("world", refusal)
    try:
        core, journal = _open_core(args, fresh)
    except bad_input as exc:
        session.close()
        return fail("world", str(exc))
    except AlgorithmFailure as exc:  # replaying the state file, the goal raised
        session.close()
        print(f"fatswarm world: {exc}", file=sys.stderr)
        return ExitCode.NOT_FORMED
    return serve(core, journal, session, stop)


def _fresh_setup(args: argparse.Namespace) -> WorldSetup | None:
    """The run of a new state file, from the flags; None if the state file holds a run to resume.
    Either way a bad start or a bad state file is said before any wait."""
    if os.path.exists(args.state) and os.path.getsize(args.state) > 0:
        # resume: a bad state file is said before any wait, read only (nothing is cut yet)
        read_record(args.state, allow_torn_end=True)
        return None
    return _make_setup(args)  # a bad start is said before any wait


def _make_setup(args: argparse.Namespace) -> WorldSetup:
    """The run the flags ask for (the start, the algorithm and its parameters, the round cap)."""
    # here, not at the top: the world's cores load only when it runs (not for `fatswarm --help`)
    from fatswarm.deploy.engine.lockstep import default_max_rounds, run_reach
    from fatswarm.world.setup import WorldSetup

    # the same checks and supported range as `fatswarm run`; -n only without --init
    setting, initial = resolve_start(
        args.init,
        None if args.init is not None else args.n,
        args.a,
        args.seed,
        args.start,
        args.algorithm,
        args.param,
    )
    reach = run_reach(setting, initial)  # an async cap scales with it, as `fatswarm run`'s
    max_rounds = args.max_rounds or default_max_rounds(setting.n, args.scheduler, reach)
    return WorldSetup(
        args.swarm,
        setting.n,
        args.seed,
        args.scheduler,
        initial,
        max_rounds,
        algorithm=args.algorithm,
        params=dict(setting.values),
        extra=_header_fields(args.header),
    )


def _open_core(
    args: argparse.Namespace, fresh: WorldSetup | None
) -> tuple[WorldCore, RecordWriter]:
    """The world core of the state file and the record it appends to: `fresh`'s run, or the run
    the file holds (see `world.journal.open_world`)."""
    # here, not at the top: the world's cores load only when it runs (not for `fatswarm --help`)
    from fatswarm.world.journal import open_world

    epoch = secrets.randbelow(2**62) + 1  # this world process's, never 0
    if fresh is None:
        held = read_record(args.state, allow_torn_end=True)
        if held.header.scheduler in ASYNC_NAMES and (held.rounds or held.result is not None):
            return _open_async(args, epoch)
    return open_world(
        args.state,
        (lambda: _make_setup(args)) if fresh is None else (lambda: fresh),
        args.swarm,
        args.max_rounds,
        fsync=not args.no_fsync,
        epoch=epoch,
    )


def _open_async(args: argparse.Namespace, epoch: int) -> tuple[WorldCore, RecordWriter]:
    """The world core of the async run the state file holds, replayed from its start until it
    has made every line of the file again (`lockstep.replay_async`: its lines are ended cycles,
    and what was in flight between them is in none), and the record it appends to. A torn last
    line is cut first, as for a round run. Raises ValueError for a file this run does not make."""
    # here, not at the top: the lock step's bus replays it (only a resumed async world needs it)
    from fatswarm.deploy.engine.lockstep import HistoryMismatchError, replay_async
    from fatswarm.world.journal import cut_torn_line, load_configured
    from fatswarm.world.setup import setup_from_header

    cut_torn_line(args.state)
    record = read_record(args.state)
    setup = setup_from_header(record.header, args.swarm, args.max_rounds)
    journal = RecordWriter(args.state, fsync=not args.no_fsync, append=True)
    logging.getLogger("fatswarm.world").info(
        "replaying the %d cycles of %s from its start (an async record)",
        len(record.rounds),
        args.state,
    )
    try:
        core = replay_async(setup, load_configured(setup), record, journal, epoch)
    except HistoryMismatchError as exc:
        journal.close()
        raise ValueError(f"state file {args.state} cannot be resumed: {exc}") from None
    readout = core.readout
    logging.getLogger("fatswarm.world").info(
        "resumed %s after cycle %d (%s): replayed from its start",
        args.state,
        readout.progress().rounds,
        readout.status,
    )
    return core, journal


def _header_fields(text: str | None) -> dict[str, Any]:
    """The extra header fields the launcher passes (`--header`), as a mapping."""
    if not text:
        return {}
    fields = json.loads(text)
    if not isinstance(fields, dict):
        raise ValueError("--header must be a JSON object")
    return fields
