"""Each networked part alone (`fatswarm router|world|coordinator|agent|agents`), for several hosts.

Also the entry point the launcher spawns (`python -m deploy.net.parts <part> ...`): it parses only
the part's own flags, so starting 128 agents does not import every subcommand of the CLI.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import secrets
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

from fatswarm.deploy.flags import add_algorithm_arguments
from fatswarm.deploy.net.zconf import (
    AGENT_LEASE_MS,
    CONNECT_DEADLINE_S,
    add_zenoh_arguments,
    check_endpoints,
    connect_endpoints,
    make_config,
    open_client,
    token_held,
)
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM

DEFAULT_ROUTER_LISTEN = "tcp/127.0.0.1:7447"
PARENT_POLL_S = 0.5
MAX_LOG_CHARS = 300  # a log message longer than this is cut (ShortLines)


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


def _logging(args: argparse.Namespace, default: str) -> None:
    level = getattr(args, "log_level", None) or default
    logging.basicConfig(
        level=level.upper(),
        format="%(asctime)s %(name)s[%(process)d] %(levelname)s %(message)s",
        stream=sys.stderr,
    )
    for handler in logging.getLogger().handlers:
        handler.addFilter(ShortLines())


def _fail(part: str, message: str) -> int:
    print(f"fatswarm {part}: {message}", file=sys.stderr)
    return ExitCode.BAD_INPUT


def _second_of_role(
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


def _add_common(p: argparse.ArgumentParser, connect_note: str = "", config_note: str = "") -> None:
    add_zenoh_arguments(p, connect_note=connect_note)
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


def _client_config(
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


# --- router ------------------------------------------------------------------------------------


def add_router_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm router`."""
    _add_common(p)


def main_router(args: argparse.Namespace) -> int:
    """Run a router until SIGTERM/SIGINT."""
    from fatswarm.deploy.net.router import run_router

    _logging(args, "info")
    stop = install_stop_signals(args.exit_with_parent)
    try:
        return run_router(args.listen, args.connect, stop, args.config, [DEFAULT_ROUTER_LISTEN])
    except ValueError as exc:
        return _fail("router", str(exc))


# --- world -------------------------------------------------------------------------------------


def add_world_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm world` (the start flags matter only for a new state file)."""
    from fatswarm.coordinator.schedule import NAMES
    from fatswarm.deploy.scenarios.starts import KINDS

    _add_common(p, GIVES_UP)
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
    from fatswarm.deploy.engine.config import input_errors, resolve_start
    from fatswarm.deploy.engine.lockstep import default_max_rounds
    from fatswarm.deploy.net.router import open_router
    from fatswarm.domain.seam import AlgorithmFailure
    from fatswarm.world.core import WorldCore, WorldSetup
    from fatswarm.world.journal import open_world
    from fatswarm.world.protocol import alive_key
    from fatswarm.world.record import RecordFormatError, read_record
    from fatswarm.world.service import serve

    _logging(args, "info")
    stop = install_stop_signals(args.exit_with_parent)

    def make_setup() -> WorldSetup:
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
        max_rounds = args.max_rounds or default_max_rounds(setting.n, args.scheduler)
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

    def open_core(setup: Callable[[], WorldSetup]) -> WorldCore:
        return open_world(
            args.state,
            setup,
            args.swarm,
            args.max_rounds,
            fsync=not args.no_fsync,
            epoch=secrets.randbelow(2**62) + 1,
        )  # this world process's, never 0

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
        conf = None if args.router else _client_config(args, shared_memory=False)
        token = alive_key(args.swarm)  # a bad --swarm is said before any wait
        fresh: WorldSetup | None = None
        if os.path.exists(args.state) and os.path.getsize(args.state) > 0:
            # resume: a bad state file is said before any wait, read only (nothing is cut yet)
            read_record(args.state, allow_torn_end=True)
        else:
            fresh = make_setup()  # a bad start is said before any wait
        if args.router:  # listening fails at once (port taken): nothing to wait for
            session = open_router(
                args.listen, args.connect, None, [DEFAULT_ROUTER_LISTEN], shared_memory=False
            )
        else:
            assert conf is not None
            session = open_client(conf, stop)
    except bad_input as exc:
        return _fail("world", str(exc))
    if session is None:
        return 0  # stopped before a router answered
    # Nothing visible before this check: no state file created or cut, no token, no state.
    refusal = _second_of_role(session, "world", args.swarm, token, stop)
    if refusal is not None or stop.is_set():
        session.close()
        return 0 if refusal is None else _fail("world", refusal)
    try:
        core: WorldCore = open_core(make_setup if fresh is None else lambda: fresh)
    except bad_input as exc:
        session.close()
        return _fail("world", str(exc))
    except AlgorithmFailure as exc:  # replaying the state file, the goal raised
        session.close()
        print(f"fatswarm world: {exc}", file=sys.stderr)
        return ExitCode.NOT_FORMED
    return serve(core, session, stop)


def _header_fields(text: str | None) -> dict[str, Any]:
    """The extra header fields the launcher passes (`--header`), as a mapping."""
    if not text:
        return {}
    fields = json.loads(text)
    if not isinstance(fields, dict):
        raise ValueError("--header must be a JSON object")
    return fields


# --- coordinator -------------------------------------------------------------------------------


def add_coordinator_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm coordinator` (n comes from the world)."""
    from fatswarm.coordinator.schedule import NAMES

    _add_common(p, GIVES_UP)
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
        "--pace",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="least time per round, to watch a run unfold (default 0: full speed)",
    )


def main_coordinator(args: argparse.Namespace) -> int:
    """Run rounds until the run ends; exit 0 formed, 1 not formed, 3 formed with collisions."""
    from fatswarm.coordinator.protocol import alive_key
    from fatswarm.coordinator.schedule import ScheduleError, Scheduler, make_scheduler
    from fatswarm.coordinator.service import Coordinator, CoordinatorConfig

    _logging(args, "info")
    stop = install_stop_signals(args.exit_with_parent)

    def scheduler_for(n: int) -> Scheduler:
        return make_scheduler(args.scheduler, n, args.seed, args.schedule, args.fairness)

    try:
        conf = _client_config(args)
        if args.move_timeout <= 0 or args.start_timeout < 0 or args.pace < 0:
            raise ValueError("--move-timeout must be > 0, --start-timeout and --pace >= 0")
        cfg = CoordinatorConfig(
            args.swarm, args.move_timeout, args.start_timeout, args.pace, scheduler=args.scheduler
        )
        token = alive_key(args.swarm)  # a bad --swarm is said before any wait
        session = open_client(conf, stop)
        if session is None:
            return 1  # stopped before a router answered: not formed
        refusal = _second_of_role(session, "coordinator", args.swarm, token, stop)
        if refusal is not None or stop.is_set():
            session.close()
            return 1 if refusal is None else _fail("coordinator", refusal)
        return Coordinator(cfg, scheduler_for, stop).run(session)
    except (ValueError, ScheduleError) as exc:
        return _fail("coordinator", str(exc))


# --- agent(s) ----------------------------------------------------------------------------------


def add_agent_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm agent`."""
    from fatswarm.agent.service import WAIT_NOTICE_S

    _add_common(p, KEEPS_WAITING.format(WAIT_NOTICE_S), PLACEHOLDER_NOTE)
    p.add_argument("--robot", type=int, required=True, metavar="I", help="robot id, 0..n-1")
    add_algorithm_arguments(p, params=False)
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        metavar="S",
        help="seed the private frame is drawn from (the run's seed)",
    )
    p.add_argument(
        "--waiting-as", default=None, metavar="WHO", help=argparse.SUPPRESS
    )  # who the waiting notice names ("": no notice)


def main_agent(args: argparse.Namespace) -> int:
    """Run one robot until SIGTERM/SIGINT."""
    from fatswarm.agent.service import AgentConfig, serve
    from fatswarm.domain.registry import load_algorithm
    from fatswarm.domain.seam import AlgorithmError

    _logging(args, "warning")
    stop = install_stop_signals(args.exit_with_parent)
    if args.robot < 0:
        return _fail("agent", f"--robot must be >= 0, got {args.robot}")
    try:
        conf = _client_config(args, lease_ms=AGENT_LEASE_MS, shared_memory=False, robot=args.robot)
    except ValueError as exc:
        return _fail("agent", str(exc))
    try:
        algorithm = load_algorithm(args.algorithm)
    except AlgorithmError as exc:
        return _fail("agent", str(exc))
    waiting = f"robot {args.robot}" if args.waiting_as is None else args.waiting_as
    return serve(
        AgentConfig(args.swarm, args.robot, args.seed, args.algorithm),
        conf,
        stop,
        waiting or None,
        algorithm,
    )


def add_agents_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm agents`."""
    from fatswarm.agent.service import WAIT_NOTICE_S

    _add_common(p, KEEPS_WAITING.format(WAIT_NOTICE_S), PLACEHOLDER_NOTE)
    p.add_argument("-n", type=int, required=True, metavar="K", help="number of agent processes")
    add_algorithm_arguments(p, params=False)
    p.add_argument(
        "--first",
        type=int,
        default=0,
        metavar="I",
        help="id of the first robot (robots I..I+K-1; default 0)",
    )
    p.add_argument("--seed", type=int, default=0, metavar="S", help="the run's seed")
    p.add_argument(
        "--spawn",
        choices=SPAWN_MODES,
        default="fork",
        help="fork: this process loads the code once and forks each agent before any "
        "Zenoh session exists (fast start, shared pages); exec: one fresh interpreter "
        "per agent (default fork)",
    )


SPAWN_MODES = ("fork", "exec")
PLACEHOLDER_NOTE = (
    f"; {ROBOT_PLACEHOLDER} in FILE is replaced by the robot id, so that each "
    "agent has its own identity (e.g. --config 'secure/agent-{robot}.json5')"
)


def agent_command(
    robot: int,
    seed: int,
    swarm: str,
    connect: Sequence[str],
    log_level: str | None = None,
    waiting_as: str | None = None,
    algorithm: str = DEFAULT_ALGORITHM,
    config: str | None = None,
) -> list[str]:
    """The argv that starts one agent process (`waiting_as`: who its waiting notice names)."""
    argv = [
        sys.executable,
        "-m",
        "fatswarm.deploy.net.parts",
        "agent",
        "--robot",
        str(robot),
        "--seed",
        str(seed),
        "--swarm",
        swarm,
        "--algorithm",
        algorithm,
    ]
    for endpoint in connect:
        argv += ["--connect", endpoint]
    if config is not None:
        argv += ["--config", config]
    if log_level:
        argv += ["--log-level", log_level]
    if waiting_as is not None:
        argv += ["--waiting-as", waiting_as]
    return argv


def agents_command(
    count: int,
    seed: int,
    swarm: str,
    connect: Sequence[str],
    log_level: str | None = None,
    spawn: str = "fork",
    first: int = 0,
    algorithm: str = DEFAULT_ALGORITHM,
    config: str | None = None,
) -> list[str]:
    """The argv of one `agents` host process starting `count` agent processes (`config`: their
    --config, ROBOT_PLACEHOLDER in it replaced by each one's robot id)."""
    argv = [
        sys.executable,
        "-m",
        "fatswarm.deploy.net.parts",
        "agents",
        "-n",
        str(count),
        "--first",
        str(first),
        "--seed",
        str(seed),
        "--swarm",
        swarm,
        "--spawn",
        spawn,
        "--algorithm",
        algorithm,
    ]
    for endpoint in connect:
        argv += ["--connect", endpoint]
    if config is not None:
        argv += ["--config", config]
    if log_level:
        argv += ["--log-level", log_level]
    return argv


def main_agents(args: argparse.Namespace) -> int:
    """Start K agent processes here (each its own OS process) and stop them on SIGTERM/SIGINT."""
    _logging(args, "warning")
    if args.n < 1 or args.first < 0:
        return _fail("agents", "-n must be >= 1 and --first >= 0")
    if not args.connect and args.config is None:
        return _fail("agents", "give the router to use with --connect ENDPOINT")
    robots = range(args.first, args.first + args.n)
    try:  # here, not in each agent process: a bad endpoint or file is one line
        check_endpoints(args.connect, "--connect")
        check_endpoints(args.listen, "--listen")
        if args.config is not None:
            for robot in robots:  # a Config only: no session in this process (fork mode)
                _client_config(args, robot=robot)
    except ValueError as exc:
        return _fail("agents", str(exc))
    from fatswarm.domain.registry import load_algorithm
    from fatswarm.domain.seam import AlgorithmError

    try:  # once here, so that a bad --algorithm is one line, not one per agent
        load_algorithm(args.algorithm)
    except AlgorithmError as exc:
        return _fail("agents", str(exc))
    if args.spawn == "exec":
        return _exec_agents(args, robots)
    return _fork_agents(args, robots)


def _exec_agents(args: argparse.Namespace, robots: range) -> int:
    from fatswarm.deploy.net.children import Children, stop_grace_s

    stop = install_stop_signals(args.exit_with_parent)
    with Children(stop_grace_s(1)) as children:
        for robot in robots:  # the first one says for all that they wait for a router
            waiting_as = _waiting_as(robots) if robot == robots[0] else ""
            children.start(
                f"agent {robot}",
                [
                    *agent_command(
                        robot,
                        args.seed,
                        args.swarm,
                        args.connect,
                        args.log_level,
                        waiting_as,
                        args.algorithm,
                        config_for(args.config, robot),
                    ),
                    "--exit-with-parent",
                    str(os.getpid()),
                ],
            )  # a killed host: none left
        while not stop.wait(0.5):
            if len(children.exited()) == len(robots):
                return 1
    return 0


def _fork_agents(args: argparse.Namespace, robots: range) -> int:
    """Load numpy, the algorithm and the zenoh module once, then fork one process per robot.

    Safe because this process never opens a Zenoh session (forking after `zenoh.open` hangs the
    child); each child opens its own session, token and frame, exactly as `fatswarm agent`.
    """
    import zenoh  # noqa: F401  (the module only: no session, no runtime thread in this process)

    from fatswarm.agent.service import AgentConfig, serve
    from fatswarm.domain.registry import load_algorithm

    algorithm = load_algorithm(args.algorithm)  # loaded once, before the forks share it
    log = logging.getLogger("fatswarm.agents")
    children: dict[int, int] = {}
    host = os.getpid()
    for robot in robots:
        pid = os.fork()
        if pid == 0:  # the agent process: never returns into the parent's code
            code = 1
            try:
                stop = install_stop_signals(host)  # a killed host leaves no agent behind
                conf = _client_config(
                    args, lease_ms=AGENT_LEASE_MS, shared_memory=False, robot=robot
                )
                # the first one says for all that they wait for a router
                waiting = _waiting_as(robots) if robot == robots[0] else None
                code = serve(
                    AgentConfig(args.swarm, robot, args.seed, args.algorithm),
                    conf,
                    stop,
                    waiting,
                    algorithm,
                )
            except BaseException:  # report, then leave without running the parent's cleanup
                log.exception("agent %d failed", robot)
            finally:
                sys.stderr.flush()
                os._exit(code)
        children[pid] = robot
    stop = install_stop_signals(args.exit_with_parent)
    while children and not stop.is_set():
        _reap(children, log)
        stop.wait(0.2)
    code = 0 if stop.is_set() else 1  # every agent gone by itself: something is wrong
    from fatswarm.deploy.net.children import stop_grace_s

    for pid in children:
        _kill(pid, signal.SIGTERM)
    deadline = time.monotonic() + stop_grace_s(len(children))
    while children and time.monotonic() < deadline:
        _reap(children, log)
        time.sleep(0.02)
    for pid in list(children):
        _kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    return code


def _waiting_as(robots: range) -> str:
    """Who the waiting notice of a host's agents names: "robot 4" or "robots 0..11"."""
    if len(robots) == 1:
        return f"robot {robots[0]}"
    return f"robots {robots[0]}..{robots[-1]}"


def _reap(children: dict[int, int], log: logging.Logger) -> None:
    while children:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            children.clear()
            return
        if pid == 0:
            return
        robot = children.pop(pid, None)
        code = os.waitstatus_to_exitcode(status)
        if code != 0:
            log.warning("agent %s exited with %d", robot, code)


def _kill(pid: int, sig: int) -> None:
    import contextlib

    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, sig)


# --- `python -m deploy.net.parts <part> ...` ------------------------------------------------------

_PARTS = {
    "router": (add_router_arguments, main_router),
    "world": (add_world_arguments, main_world),
    "coordinator": (add_coordinator_arguments, main_coordinator),
    "agent": (add_agent_arguments, main_agent),
    "agents": (add_agents_arguments, main_agents),
}


def main(argv: Sequence[str] | None = None) -> int:
    """Parse one part's flags and run it."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] not in _PARTS:
        print(f"usage: python -m deploy.net.parts {{{','.join(_PARTS)}}} ...", file=sys.stderr)
        return ExitCode.BAD_INPUT
    add, run = _PARTS[argv[0]]
    parser = argparse.ArgumentParser(prog=f"fatswarm {argv[0]}")
    add(parser)
    code = run(parser.parse_args(argv[1:]))
    return code


if __name__ == "__main__":
    sys.exit(main())
