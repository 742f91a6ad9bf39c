"""`fatswarm run`: run a swarm, networked (default, deploy.net.launcher) or in one process
(--lockstep): its flags and its entry. The run the flags ask for is `run_input.resolve_run`; the
lock step's command `run_lockstep.run_lockstep_command`.

Exit codes (`ExitCode`): 0 formed with no collision, 1 not formed (stalled or max_rounds, with or
without collisions), 2 bad input (one line on stderr), 3 formed but with collisions, 4 the record
could not be written, 130 interrupted (SIGINT), 141 standard output closed early (a broken pipe),
143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
from typing import Final

from fatswarm.coordinator.schedule import NAMES
from fatswarm.deploy.commands.run_input import check_outputs, check_svg, resolve_run
from fatswarm.deploy.commands.run_lockstep import run_lockstep_command
from fatswarm.deploy.engine.config import (
    DEFAULT_A,
    DEFAULT_N,
    DEFAULT_SCHEDULER,
    DEFAULT_START,
)
from fatswarm.deploy.flags import (
    StoreGiven,
    add_algorithm_arguments,
    add_robot_model_arguments,
)
from fatswarm.deploy.net.run_flags import add_network_arguments
from fatswarm.deploy.scenarios.starts import KINDS
from fatswarm.deploy.view import dashboard
from fatswarm.domain.outcome import ExitCode

EXIT_CODES_HELP: Final = (
    f"exit codes: {ExitCode.FORMED:d} formed with no collision; {ExitCode.NOT_FORMED:d} not formed "
    f"(stalled or out of rounds; networked: or a part's process died, one line says which); "
    f"{ExitCode.BAD_INPUT:d} bad input (one line on stderr says what to "
    f"fix); {ExitCode.FORMED_WITH_COLLISIONS:d} formed, but with collisions (robots stopped at "
    f"contact: not the collision-free formation the paper guarantees); "
    f"{ExitCode.RECORD_FAILED:d} the run record could not be written (disk full, permissions: "
    f"the run stopped; --resume goes on once fixed); {ExitCode.INTERRUPTED:d} "
    f"interrupted (Ctrl-C); {ExitCode.BROKEN_PIPE:d} standard output closed early (e.g. | head); "
    f"{ExitCode.TERMINATED:d} terminated (SIGTERM). A run stopped by a signal or a record it "
    "cannot write says in one line after which round, and how to go on (--resume)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm run`, the launcher's (networked) and the dashboard's among them."""
    p.epilog = EXIT_CODES_HELP
    _add_start_arguments(p)
    _add_model_arguments(p)
    add_robot_model_arguments(p)
    _add_output_arguments(p)
    add_network_arguments(p)
    # The dashboard's run flags (--no-dashboard, --svg): `add_run_arguments`, because the CLI
    # would hand an `add_dashboard_arguments` to `fatswarm dashboard` itself. Called through its
    # module: the CLI would take an `add_run_arguments` of this module for all of run's flags.
    dashboard.add_run_arguments(p)


def _add_start_arguments(p: argparse.ArgumentParser) -> None:
    """How the run is made (in lock step or not), its robots, algorithm, seed and start."""
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="run every robot in this one process, in lock step (no Zenoh; refuses the "
        "networked-run flags)",
    )
    p.add_argument(
        "-n",
        type=int,
        default=None,
        metavar="N",
        help=f"number of robots (default {DEFAULT_N}; with --init, taken from the file)",
    )
    p.add_argument(
        "-a",
        type=float,
        default=None,
        metavar="A",
        help=f"the paper's least side of the polygon, > 3: --param a=A (default "
        f"{DEFAULT_A:g}, or the --init file's 'a'); random starts are drawn at this "
        "scale",
    )
    add_algorithm_arguments(p)
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        metavar="S",
        help="seed of the start, frames and scheduler (default: random, printed)",
    )
    p.add_argument(
        "--init",
        metavar="PATH",
        help='start from a JSON file {"positions": [[x, y], ...], "a": 4.0}',
    )
    p.add_argument(
        "--start",
        choices=KINDS,
        default=DEFAULT_START,
        action=StoreGiven,
        help=f"kind of random start without --init (default {DEFAULT_START}: needs SEC expansion)",
    )


def _add_model_arguments(p: argparse.ArgumentParser) -> None:
    """The scheduler and the adversary: who is active, fairness, round cap, non-rigid, crashes."""
    p.add_argument(
        "--scheduler",
        choices=NAMES,
        default=DEFAULT_SCHEDULER,
        action=StoreGiven,
        help=f"who is active each round (default {DEFAULT_SCHEDULER}); async, "
        "async-slowest: no rounds, robots on their own clocks in virtual time, the "
        "adversary's delays random or slowest robot last",
    )
    p.add_argument(
        "--schedule",
        metavar="PATH",
        help='scripted scheduler: JSON {"rounds": [[0, 2], [1], ...]} or a run record',
    )
    p.add_argument(
        "--fairness",
        type=int,
        default=None,
        metavar="K",
        help="ssync/centralized: every robot active at least once in every K rounds (default 2n)",
    )
    p.add_argument(
        "--max-rounds",
        type=int,
        default=None,
        metavar="R",
        help="stop after R rounds (default: 10 (n + 10) for fsync, 40 (n + 10) for "
        "ssync, 10 n (n + 10) otherwise; for the async models 40 n (n + 10) ended cycles, "
        "times ceil(reach / 40) when the radius of the start's or target circle, the reach, "
        "exceeds 40, and times ceil(0.5 / DELTA) under --non-rigid DELTA below 0.5)",
    )
    p.add_argument(
        "--non-rigid",
        type=float,
        default=None,
        metavar="DELTA",
        help="non-rigid moves: the adversary may stop a move anywhere after the robot "
        "has travelled DELTA (> 0, robot radii; e.g. 1) or at its end, drawn from the "
        "seed (default: rigid moves)",
    )
    p.add_argument(
        "--crash",
        type=int,
        default=None,
        metavar="F",
        help="F robots (0 < F < n) crash at rounds the adversary draws from the seed "
        "and stay for good as still obstacles; the goal is then judged on the live "
        "robots (default: none)",
    )


def _add_output_arguments(p: argparse.ArgumentParser) -> None:
    """The run record (new, overwritten or resumed) and what is printed."""
    p.add_argument(
        "--record",
        metavar="PATH",
        help="write the run record (JSON Lines) to PATH (a new file, unless --force)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="let --record overwrite an existing file; networked: also start a run larger "
        "than this machine seems to hold (see the estimate it prints)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the unfinished run of the --record file after its last round, "
        "appending to it: n, a, seed, scheduler, start and round cap are the record's "
        "(a flag that contradicts them is refused)",
    )
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no progress lines while running (the summary is still printed)",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="print the summary as one JSON object on stdout (progress stays on "
        "stderr; no live dashboard)",
    )


def main(args: argparse.Namespace) -> int:
    """Run the swarm as asked; returns the exit code."""
    if not args.lockstep:
        return _networked(args)
    return run_lockstep_command(args)


def _networked(args: argparse.Namespace) -> int:
    # the launcher (subprocess, the parts' supervision) loads only for a networked run: the CLI
    # imports this module to build its parser
    from fatswarm.deploy.net.launcher import run_networked

    return run_networked(args, resolve_run)


__all__ = [
    "EXIT_CODES_HELP",
    "add_arguments",
    "check_outputs",
    "check_svg",
    "main",
    "resolve_run",
    "run_lockstep_command",
]
