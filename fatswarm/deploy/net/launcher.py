"""`fatswarm run` networked: a router here, then world, coordinator and N agent processes.

Every child is its own OS process (`subprocess.Popen` of `sys.executable`, never a fork of a
process with a Zenoh session) in its own process group; whatever happens, `Children` stops them all.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import os
import secrets
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

from fatswarm.deploy.engine.config import RunInputError, RunSetup, input_errors
from fatswarm.deploy.flags import check_seconds
from fatswarm.deploy.net import capacity
from fatswarm.deploy.net.children import STOP_GRACE_S, Children, stop_grace_s
from fatswarm.deploy.net.part_agents import agents_command
from fatswarm.deploy.net.part_common import part_command
from fatswarm.deploy.net.run_flags import live_dashboard, watchable_pace
from fatswarm.deploy.net.zconf import (
    DEFAULT_SWARM,
    ZenohSetupError,
    check_network,
    loopback_endpoint,
    make_config,
    open_client,
    token_held,
)
from fatswarm.deploy.view.stopped import stopped_line
from fatswarm.deploy.view.summary import (
    Outcome,
    counted,
    crashes_in,
    exit_code,
    print_outcome,
    side_of,
    summary,
    unit,
)
from fatswarm.domain.figures import run_derived
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.wire import check_swarm
from fatswarm.world.record import RecordFormatError, RecordWriteError, RecordWriter
from fatswarm.world.record_read import read_record
from fatswarm.world.rejections import tally

Resolver = Callable[[argparse.Namespace, int], RunSetup]  # flags and seed -> the run

log = logging.getLogger("fatswarm.launcher")

STDERR_FD = 2  # a file descriptor, not sys.stderr: that may be an in-process capture
FINAL_STATE_WAIT_S = 5.0  # the dashboard's wait for the final state (re-published every second)
# How a coordinator that ended the run exits: 0 formed, 1 not formed, 2 bad input, 3 collisions
COORDINATOR_ENDS = frozenset(
    {ExitCode.FORMED, ExitCode.NOT_FORMED, ExitCode.BAD_INPUT, ExitCode.FORMED_WITH_COLLISIONS}
)


def _child_endpoint(listen: str) -> str:
    """Where local children reach a router listening on `listen` (wildcard hosts -> loopback)."""
    for wildcard in ("0.0.0.0", "[::]"):
        listen = listen.replace(f"/{wildcard}:", "/127.0.0.1:")
    return listen


# --- the run -------------------------------------------------------------------------------------


def run_networked(args: argparse.Namespace, resolve_run: Resolver) -> int:
    """Run the swarm over Zenoh as `fatswarm run` asks; returns the exit code (`ExitCode`).
    `resolve_run(args, seed)` builds the run from the flags (`deploy.commands.run.resolve_run`)."""
    problem, seed, setup = check_inputs(args, resolve_run)
    if problem is not None:
        print(f"fatswarm run: {problem}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    assert setup is not None
    pace: float = args.pace
    if pace is None:
        pace = watchable_pace(setup.params.n, setup.scheduler.name) if live_dashboard(args) else 0.0
    if setup.outside and not args.quiet:  # the run goes ahead: that is the experiment
        print(f"fatswarm run: {setup.outside}", file=sys.stderr)
    if setup.resumed is None and args.seed is None and not args.quiet:
        print(f"seed {seed} (pass --seed {seed} to repeat this run)", file=sys.stderr)
    cost, machine = capacity.estimate_networked(setup.params.n, args.spawn), capacity.this_machine()
    if not args.quiet and capacity.worth_saying(cost, machine):
        print(capacity.estimate_text(cost, machine), file=sys.stderr, flush=True)
    capacity.raise_open_files(cost)  # the world's router holds a link per agent
    # The world's own router holds one swarm: the default name lets `fatswarm dashboard` attach
    # as is. On a shared router (--connect), a fresh name keeps two runs from mixing messages.
    swarm = args.swarm or (f"run-{secrets.token_hex(4)}" if args.connect else DEFAULT_SWARM)
    with tempfile.TemporaryDirectory(prefix="fatswarm-") as tmp:
        record = args.record or os.path.join(tmp, "record.jsonl")
        if setup.resumed is None:
            try:  # a new run (an existing file only with --force, checked): truncated
                write_header(setup, record, swarm)
            except RecordWriteError as exc:
                print(f"fatswarm run: {exc}", file=sys.stderr)
                return ExitCode.RECORD_FAILED
        return _launch(args, setup, record, pace, swarm)


def check_inputs(
    args: argparse.Namespace, resolve_run: Resolver
) -> tuple[str | None, int, RunSetup | None]:
    """(what to fix or None, the seed, the run): the lockstep run's checks, before any process
    starts; with --resume, the seed and the run are the record's. `resolve_run` builds the run
    from the flags: the same function as the lockstep run's, so both refuse the same input."""
    seed: int = args.seed if args.seed is not None else secrets.randbelow(2**31)
    bad_input: tuple[type[Exception], ...] = (*input_errors(), ValueError)  # ValueError: swarm
    setup = None
    try:
        check_seconds("--move-timeout", args.move_timeout, zero_ok=False)
        if args.pace is not None:
            check_seconds("--pace", args.pace, zero_ok=True)
        setup = resolve_run(args, seed)
        seed = setup.seed
        if args.swarm is not None:
            check_swarm(args.swarm)
        too_big = capacity.problem(
            capacity.estimate_networked(setup.params.n, args.spawn), capacity.this_machine()
        )
        if too_big is not None and not args.force:
            raise RunInputError(too_big)
        check_network(args.connect, args.listen)  # a router answers; --listen well formed, free
        if args.connect and args.swarm is not None:
            check_swarm_free(args.connect, args.swarm)
    except bad_input as exc:
        return str(exc), seed, setup
    return None, seed, setup


def check_swarm_free(connect: Sequence[str], swarm: str) -> None:
    """Raise RunInputError if `swarm` already has a world or a coordinator on the router network
    at `connect`: nothing of this run may start then (its display would show the other run, its
    parts would be refused one by one). The parts' own check, asked once here, before anything."""
    # here, not at the top: the roles' key builders, only for a run on a shared router
    from fatswarm.coordinator.protocol import alive_key as coordinator_key
    from fatswarm.world.protocol import alive_key as world_key

    session = open_client(make_config("client", connect=connect))
    try:
        for part, key in (("world", world_key(swarm)), ("coordinator", coordinator_key(swarm))):
            if session is not None and token_held(session, key):
                raise RunInputError(
                    f"swarm {swarm!r} already has a {part} on this router network; stop it "
                    "or pick another --swarm"
                )
    finally:
        if session is not None:
            session.close()


def write_header(setup: RunSetup, record: str, swarm: str) -> None:
    """Start the record of a new run with its header: the world then runs exactly this run (it
    resumes the record, with no round yet), so none of it travels as flags to the world.
    Raises RecordWriteError (a full disk, a permission)."""
    # here, not at the top: only a new networked run needs the world's cores (not `--help`)
    from fatswarm.world.core import WorldCore
    from fatswarm.world.journal import perform

    world = dataclasses.replace(setup.settings, swarm=swarm)
    with RecordWriter(record, fsync=True) as journal:
        perform(WorldCore(world, setup.params).take_effects(), journal)


class StopSignal:
    """Set by SIGTERM or SIGINT (a signal handler); remembers which, for the exit code."""

    def __init__(self) -> None:
        self.event = threading.Event()
        self.signum: int | None = None

    def __call__(self, signum: int, frame: object) -> None:
        del frame
        self.signum = signum
        self.event.set()

    def exit_code(self) -> ExitCode:
        """143 after SIGTERM, 130 after Ctrl-C (SIGINT)."""
        return ExitCode.TERMINATED if self.signum == signal.SIGTERM else ExitCode.INTERRUPTED


def _launch(args: argparse.Namespace, setup: RunSetup, record: str, pace: float, swarm: str) -> int:
    """Start the world (hosting the router, unless --connect), the coordinator and the agents for
    the resolved run `setup`; follow it; the exit code."""
    stop = StopSignal()
    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    listen: list[str] = []  # where the world hosts the router; none with --connect
    if args.connect:
        endpoints = list(args.connect)
    else:
        listen = list(args.listen) or [loopback_endpoint()]
        endpoints = [_child_endpoint(listen[0])]
    try:
        if not args.quiet:
            print(
                f"swarm {swarm!r} on {endpoints[0]} (watch from elsewhere: fatswarm dashboard "
                f"--connect {endpoints[0]} --swarm {swarm})",
                file=sys.stderr,
            )
        code, followed, refused = _run_parts(
            args, setup, record, pace, swarm, (endpoints, listen), stop
        )
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if code in (ExitCode.FORMED, ExitCode.NOT_FORMED):
        code = _report(args, record, code, followed)
    elif code in (ExitCode.INTERRUPTED, ExitCode.TERMINATED, ExitCode.RECORD_FAILED):
        print(_stopped(code, record, args.record, setup), file=sys.stderr)  # below the last frame
    if refused and not args.json:
        print(refused_line(refused), file=sys.stdout if code in _ENDED else sys.stderr)
    return code


_ENDED = (
    ExitCode.FORMED,
    ExitCode.NOT_FORMED,
    ExitCode.FORMED_WITH_COLLISIONS,
)  # a summary was printed


def refused_line(refused: dict[str, int]) -> str:
    """The summary's line of what the world refused or dropped (rogue or late messages), by
    kind; printed only when it refused something."""
    return f"refused: {sum(refused.values()):,} messages ({tally(refused)})"


def _stopped(code: int, record: str, given: str | None, setup: RunSetup) -> str:
    """`stopped_line` for the run of the record at `record` (`given`: as --record named it, else
    None), read once every part has stopped: after a signal, or a record the world could not
    write (the lock step's words: "the run stopped after round N; once that is fixed, ...")."""
    failed = code == ExitCode.RECORD_FAILED
    word = {ExitCode.TERMINATED: "terminated", ExitCode.RECORD_FAILED: "stopped"}.get(
        ExitCode(code), "interrupted"
    )
    scheduler = setup.scheduler.name
    try:
        rec = read_record(record, allow_torn_end=True)
    except (RecordFormatError, OSError):  # (the header is written before any part starts)
        return f"{word} before the run started"
    if rec.result is not None:  # the signal came as the display waited for the final state
        rounds = counted(rec.result.rounds, unit(scheduler))
        return f"{word} after the run ended ({rec.result.status} after {rounds})"
    line = stopped_line(
        word, len(rec.rounds), record=given, scheduler=scheduler, seed=setup.seed, fix=failed
    )
    return f"fatswarm run: the run {line}" if failed else line


def _run_parts(
    args: argparse.Namespace,
    setup: RunSetup,
    record: str,
    pace: float,
    swarm: str,
    network: tuple[Sequence[str], Sequence[str]],
    stop: StopSignal,
) -> tuple[int, bool, dict[str, int]]:
    """Run every part until the run ends or a signal comes, the live display following it;
    `network`: (the endpoints the parts connect to, where the world hosts the router, if it does).
    (The exit code, whether a display followed the run, what the world refused by kind.)"""
    endpoints, listen = network
    watcher = session = None
    followed = False  # a display followed the run (it saves --svg)
    refused: dict[str, int] = {}
    try:
        # the agents host needs its own grace first, to stop its agents one by one
        with Children(stop_grace_s(setup.params.n) + STOP_GRACE_S) as children:
            _start_world(setup, record, swarm, endpoints, listen, children)
            if listen:
                session = _await_router(endpoints[0], children, stop)
            if session is not None or not listen:
                watcher = _follow(args, swarm, session, endpoints[0])
                followed = watcher is not None
                code = _run_children(args, setup, pace, swarm, endpoints, children, stop)
            else:
                code = _world_gone(children) if "world" in children.exited() else stop.exit_code()
            if (
                watcher is not None
                and code in (ExitCode.FORMED, ExitCode.NOT_FORMED)
                and not _part_died(children)
            ):
                _await_final_state(watcher, FINAL_STATE_WAIT_S)
            if watcher is not None:
                watcher.stop()  # before the world (and with it the router) goes
                refused = watcher.refused
                watcher = None
    finally:
        if watcher is not None:
            watcher.stop()
        if session is not None:
            session.close()
    return code, followed, refused


def _report(args: argparse.Namespace, record: str, code: int, followed: bool) -> int:
    """Print the outcome of a run that ended (formed or not) as its record says; the exit code."""
    # the record, not the coordinator's 0/1, says whether robots collided on the way
    outcome = read_outcome(record)
    if outcome is not None:
        code = exit_code(outcome)
    print_outcome(
        outcome,
        code,
        sys.stdout,
        as_json=args.json,
        record=args.record,
        svg=getattr(args, "svg", None) if followed else None,
    )
    return code


def _await_router(endpoint: str, children: Children, stop: StopSignal) -> Any:
    """A client session to the router the world hosts, once it listens; None if the world exited
    or a signal came first (a world that loads a large record may take a while)."""
    while not stop.event.is_set() and "world" not in children.exited():
        try:
            return open_client(make_config("client", [endpoint]), stop.event, deadline_s=0.5)
        except ZenohSetupError:  # not listening yet: look again
            stop.event.wait(0.05)
    return None


def _follow(args: argparse.Namespace, swarm: str, session: Any, endpoint: str) -> Any:
    """The dashboard (on a terminal, not with --json) or progress lines on stderr, from the
    world's state stream: standard output carries only the summary."""
    try:  # here: a run goes on without its display if the dashboard cannot be loaded
        from fatswarm.deploy.net.watch import follow
    except ImportError:
        return None
    if session is not None:
        return follow(args, swarm, session=session, progress=_to_stderr)
    return follow(args, swarm, connect=endpoint, progress=_to_stderr)


def _to_stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def _await_final_state(watcher: Any, timeout_s: float) -> None:
    """Let the display see the world's final state before the world is stopped.

    The world answers the last commit before it publishes the state, so the coordinator may be
    gone before the state arrives; the world, still up, re-publishes it every second.
    """
    deadline = time.monotonic() + timeout_s
    while not (watcher.ended.is_set() or watcher.finished.is_set()):
        if time.monotonic() >= deadline:
            log.warning("the display did not see the run's final state within %g s", timeout_s)
            return
        watcher.ended.wait(0.05)


def _start_world(
    setup: RunSetup,
    record: str,
    swarm: str,
    endpoints: Sequence[str],
    listen: Sequence[str],
    children: Children,
) -> None:
    """Start the world from the record's header; with `listen`, hosting the router there."""
    net = ["--swarm", swarm, *_quiet()]
    if listen:
        net.append("--router")
        for ep in listen:
            net += ["--listen", ep]
    else:
        for ep in endpoints:
            net += ["--connect", ep]
    # the parts' standard output joins ours on stderr (fd 2): stdout carries only the summary
    children.start("world", part_command("world", *net, "--state", record), stdout=STDERR_FD)


def _quiet() -> list[str]:
    """The flags of every part started here: warnings only, in plain lines; gone with us."""
    return ["--log-level", "warning", "--plain-log", "--exit-with-parent", str(os.getpid())]


def _run_children(
    args: argparse.Namespace,
    setup: RunSetup,
    pace: float,
    swarm: str,
    endpoints: Sequence[str],
    children: Children,
    stop: StopSignal,
) -> int:
    """Start the coordinator and the agents, configured from the resolved run, and wait until the
    coordinator or the world ends or a signal comes."""
    net = ["--swarm", swarm]
    for ep in endpoints:
        net += ["--connect", ep]
    coord = _coordinator_flags(args, setup, pace)
    children.start(
        "coordinator", part_command("coordinator", *net, *_quiet(), *coord), stdout=STDERR_FD
    )
    children.start(
        "agents",
        [
            *agents_command(
                setup.params.n,
                swarm,
                endpoints,
                "warning",
                args.spawn,
                algorithm=setup.algorithm_ref,
            ),
            "--exit-with-parent",
            str(os.getpid()),
            "--plain-log",
        ],
        stdout=STDERR_FD,
    )
    return _await_end(children, stop)


def _coordinator_flags(args: argparse.Namespace, setup: RunSetup, pace: float) -> list[str]:
    """The coordinator's flags of the resolved run: seed, scheduler, move timeout, pace, and its
    schedule file and fairness bound if it has them."""
    seed, scheduler = setup.seed, setup.scheduler
    coord = [
        "--seed",
        str(seed),
        "--scheduler",
        scheduler.name,
        "--move-timeout",
        repr(args.move_timeout),
        "--pace",
        repr(pace),
    ]
    script = args.schedule or _schedule_of(setup)
    if script is not None:
        coord += ["--schedule", script]
    fairness = getattr(scheduler, "fairness", None)
    if isinstance(fairness, int):
        coord += ["--fairness", str(fairness)]
    return coord


def _await_end(children: Children, stop: StopSignal) -> int:
    """Wait until the coordinator or the world ends, the agents' process exits or a signal comes;
    the run's exit code, said on stderr unless the coordinator ended the run."""
    while not stop.event.wait(0.1):
        gone = children.exited()
        if "coordinator" in gone:
            ended = gone["coordinator"]  # 0 formed, 1 not formed, 2 bad input, 3 collisions
            if ended in COORDINATOR_ENDS:
                return ExitCode(ended)
            print(
                f"fatswarm run: the coordinator process exited with code {ended}; stopping the "
                "run (its record keeps every committed round)",
                file=sys.stderr,
            )
            return ExitCode.NOT_FORMED
        if "world" in gone:
            return _world_gone(children)
        if "agents" in gone:  # every robot with it: no round can be run any more
            print(
                f"fatswarm run: the agents' process exited with code {gone['agents']}; "
                "stopping the run (its record keeps every committed round)",
                file=sys.stderr,
            )
            return ExitCode.NOT_FORMED
    code = stop.exit_code()
    # at once (stopping many agents takes a while); how far the run got once all have stopped
    print(
        f"{'terminated' if code == ExitCode.TERMINATED else 'interrupted'}: stopping every "
        "process started",
        file=sys.stderr,
    )
    return code


def _part_died(children: Children) -> bool:
    """Whether the run ended because a part died (no final state will come): the world or the
    agents exited, or the coordinator exited without ending the run."""
    gone = children.exited()
    return (
        "world" in gone
        or "agents" in gone
        or gone.get("coordinator", ExitCode.FORMED) not in COORDINATOR_ENDS
    )


def _world_gone(children: Children) -> ExitCode:
    """The run's exit code once the world process has exited (it says why on its own)."""
    code = children.exited()["world"]
    if code != ExitCode.RECORD_FAILED:  # (that one: the run's last line says how to go on)
        print(f"fatswarm run: the world process exited with code {code}", file=sys.stderr)
    said = (ExitCode.BAD_INPUT, ExitCode.RECORD_FAILED)  # its own line says why
    return ExitCode(code) if code in said else ExitCode.NOT_FORMED


def _schedule_of(setup: RunSetup) -> str | None:
    """The schedule file of a scripted run: the one asked for, or the one its record names."""
    return setup.settings.schedule


def print_summary(record: str, out: Any) -> Outcome | None:
    """Print the same summary as a lockstep run, read back from the record; the outcome, None if
    the record holds no result (the run did not end)."""
    outcome = read_outcome(record)
    if outcome is not None:
        print(summary(outcome), file=out)
    return outcome


def read_outcome(record: str) -> Outcome | None:
    """How the run of this record ended; None (said on stderr) if unreadable or unfinished."""
    try:
        rec = read_record(record)
    except RecordFormatError as exc:
        print(f"no summary: {exc}", file=sys.stderr)
        return None
    h, res = rec.header, rec.result
    if res is None:
        done = counted(len(rec.rounds), unit(h.scheduler))  # cycles under an async model
        print(f"unfinished: n={h.n} after {done}", file=sys.stderr)
        return None
    return Outcome(
        status=res.status,
        rounds=res.rounds,
        # the world writes the count; else the rounds' own collisions say it
        collisions=(
            res.collisions
            if res.collisions is not None
            else sum(len(r.collisions) for r in rec.rounds)
        ),
        n=h.n,
        a=side_of(h.params),
        seed=h.seed,
        scheduler=h.scheduler,
        epochs=res.epochs,
        moves=res.moves or 0,
        total_distance=res.total_distance or 0.0,
        algorithm=h.algorithm,
        params=dict(h.params),
        time=res.time,
        crashes=crashes_in(rec.rounds),  # (an async record's: the first cycle line after each)
        derived=run_derived(rec.rounds),
    ).noted(h.extra)


__all__ = [
    "StopSignal",
    "check_swarm_free",
    "read_outcome",
    "run_networked",
    "stopped_line",
]
