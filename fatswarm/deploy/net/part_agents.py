"""`fatswarm agent` and `fatswarm agents`: one robot's process alone, or K of them on one host
(forked from one preloaded process, or one fresh interpreter each), and the argv starting them."""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
import sys
import time
from collections.abc import Sequence

from fatswarm.agent.service import WAIT_NOTICE_S, AgentConfig, serve
from fatswarm.deploy.flags import add_algorithm_arguments
from fatswarm.deploy.net.part_common import (
    KEEPS_WAITING,
    ROBOT_PLACEHOLDER,
    add_common_arguments,
    client_config,
    config_for,
    fail,
    install_stop_signals,
    part_command,
    setup_logging,
)
from fatswarm.deploy.net.zconf import AGENT_LEASE_MS, check_endpoints, settle_runtime
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import AlgorithmError


def add_ignored_seed(p: argparse.ArgumentParser) -> None:
    """`--seed`, accepted and ignored: agents once drew their private frames from the run's seed;
    the world draws them now (docs/model.md), and recipes written before still run."""
    p.add_argument("--seed", type=int, default=None, help=argparse.SUPPRESS)


def add_agent_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm agent`."""
    add_common_arguments(p, KEEPS_WAITING.format(WAIT_NOTICE_S), PLACEHOLDER_NOTE)
    p.add_argument("--robot", type=int, required=True, metavar="I", help="robot id, 0..n-1")
    add_algorithm_arguments(p, params=False)
    add_ignored_seed(p)
    p.add_argument(
        "--waiting-as", default=None, metavar="WHO", help=argparse.SUPPRESS
    )  # who the waiting notice names ("": no notice)


def main_agent(args: argparse.Namespace) -> int:
    """Run one robot until SIGTERM/SIGINT."""
    setup_logging(args, "warning")
    stop = install_stop_signals(args.exit_with_parent)
    if args.robot < 0:
        return fail("agent", f"--robot must be >= 0, got {args.robot}")
    try:
        conf = client_config(args, lease_ms=AGENT_LEASE_MS, shared_memory=False, robot=args.robot)
    except ValueError as exc:
        return fail("agent", str(exc))
    try:
        algorithm = load_algorithm(args.algorithm)
    except AlgorithmError as exc:
        return fail("agent", str(exc))
    waiting = f"robot {args.robot}" if args.waiting_as is None else args.waiting_as
    settle_runtime()
    return serve(
        AgentConfig(args.swarm, args.robot, args.algorithm),
        conf,
        stop,
        waiting or None,
        algorithm,
    )


def add_agents_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm agents`."""
    add_common_arguments(p, KEEPS_WAITING.format(WAIT_NOTICE_S), PLACEHOLDER_NOTE)
    p.add_argument("-n", type=int, required=True, metavar="K", help="number of agent processes")
    add_algorithm_arguments(p, params=False)
    p.add_argument(
        "--first",
        type=int,
        default=0,
        metavar="I",
        help="id of the first robot (robots I..I+K-1; default 0)",
    )
    add_ignored_seed(p)
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
    swarm: str,
    connect: Sequence[str],
    log_level: str | None = None,
    waiting_as: str | None = None,
    algorithm: str = DEFAULT_ALGORITHM,
    config: str | None = None,
) -> list[str]:
    """The argv that starts one agent process (`waiting_as`: who its waiting notice names)."""
    argv = part_command("agent", "--robot", str(robot), "--swarm", swarm, "--algorithm", algorithm)
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
    argv = part_command(
        *("agents", "-n", str(count), "--first", str(first), "--swarm", swarm),
        *("--spawn", spawn, "--algorithm", algorithm),
    )
    for endpoint in connect:
        argv += ["--connect", endpoint]
    if config is not None:
        argv += ["--config", config]
    if log_level:
        argv += ["--log-level", log_level]
    return argv


def main_agents(args: argparse.Namespace) -> int:
    """Start K agent processes here (each its own OS process) and stop them on SIGTERM/SIGINT."""
    setup_logging(args, "warning")
    if args.n < 1 or args.first < 0:
        return fail("agents", "-n must be >= 1 and --first >= 0")
    if not args.connect and args.config is None:
        return fail("agents", "give the router to use with --connect ENDPOINT")
    robots = range(args.first, args.first + args.n)
    try:  # here, not in each agent process: a bad endpoint or file is one line
        check_endpoints(args.connect, "--connect")
        check_endpoints(args.listen, "--listen")
        if args.config is not None:
            for robot in robots:  # a Config only: no session in this process (fork mode)
                client_config(args, robot=robot)
    except ValueError as exc:
        return fail("agents", str(exc))
    try:  # once here, so that a bad --algorithm is one line, not one per agent
        load_algorithm(args.algorithm)
    except AlgorithmError as exc:
        return fail("agents", str(exc))
    if args.spawn == "exec":
        return _exec_agents(args, robots)
    return _fork_agents(args, robots)


def _exec_agents(args: argparse.Namespace, robots: range) -> int:
    """Start one fresh interpreter per robot (`fatswarm agent`); 1 if every one has exited."""
    # here, not at the top: a lone agent process (`fatswarm agent`) never starts children
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
                        args.swarm,
                        args.connect,
                        args.log_level,
                        waiting_as,
                        args.algorithm,
                        config_for(args.config, robot),
                    ),
                    "--exit-with-parent",
                    str(os.getpid()),
                    *(["--plain-log"] if args.plain_log else []),
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
    # here, not at the top: only this host, before it forks, preloads zenoh for its agents
    import zenoh  # noqa: F401  (the module only: no session, no runtime thread in this process)

    settle_runtime()  # inherited by every fork (each opens its own session and runtime)

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
                conf = client_config(
                    args, lease_ms=AGENT_LEASE_MS, shared_memory=False, robot=robot
                )
                # the first one says for all that they wait for a router
                waiting = _waiting_as(robots) if robot == robots[0] else None
                code = serve(
                    AgentConfig(args.swarm, robot, args.algorithm),
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
    # here, after the forks: neither the forked agents nor a lone agent process need it
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
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, sig)
