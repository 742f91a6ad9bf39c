"""The `fatswarm` command: one subcommand per role; each lives in its own module.

Every subcommand module exposes `add_arguments(parser)` and `main(args) -> int` (or
`add_<name>_arguments` / `main_<name>` when one module serves several commands). Subcommand
modules import Zenoh, matplotlib and other heavy things inside their `main`, never at module level,
so `--help` stays fast and `fatswarm replay` works without a router.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from types import FrameType
from typing import TYPE_CHECKING, Any, NoReturn

from fatswarm import __version__
from fatswarm.domain.outcome import ExitCode

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

# name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "run": (
        "fatswarm.deploy.commands.run",
        "run a swarm (networked by default, --lockstep: one process)",
    ),
    "algorithms": (
        "fatswarm.deploy.commands.catalog",
        "list the algorithms a run can use, or one's parameters",
    ),
    "router": ("fatswarm.deploy.net.part_router", "run a Zenoh router alone (for several hosts)"),
    "world": ("fatswarm.deploy.net.part_world", "run the world process alone"),
    "coordinator": ("fatswarm.deploy.net.part_coordinator", "run the coordinator process alone"),
    "agent": ("fatswarm.deploy.net.part_agents", "run one agent (robot) process alone"),
    "agents": ("fatswarm.deploy.net.part_agents", "run K agent processes on this host"),
    "dashboard": (
        "fatswarm.deploy.net.watch",
        "attach a read-only dashboard to a running swarm",
    ),
    "secure": (
        "fatswarm.deploy.secure.pki",
        "make a swarm's certificates and Zenoh configurations for "
        "several hosts: mutual TLS, access control (needs fatswarm[secure])",
    ),
    "replay": ("fatswarm.deploy.view.replay", "play a run record in the dashboard"),
    "plot": (
        "fatswarm.deploy.view.plot",
        "draw a record's trajectories to SVG or PNG (fatswarm[plot])",
    ),
    "sweep": (
        "fatswarm.deploy.sweep.command",
        "run a grid of lock-step runs on every core into a CSV (resumable)",
    ),
    "hunt": (
        "fatswarm.deploy.hunt.command",
        "search for counterexamples on every core, shrink them "
        "and save each as a replayable start and schedule",
    ),
}


_Handler = Callable[[int, FrameType | None], Any] | int | None  # what signal.signal returns


class Terminated(BaseException):
    """SIGTERM arrived: unwind like Ctrl-C (closing files, stopping children), then exit 143.

    A BaseException, as KeyboardInterrupt is, so that no `except Exception` swallows it.
    """


class _Parser(argparse.ArgumentParser):
    """argparse's parser, except that a failed write of --help or --version is not swallowed
    (`main` ends a closed pipe the same way, exit 141, whatever printed into it), and a usage
    error is one line."""

    def _print_message(self, message: str, file: SupportsWrite[str] | None = None) -> None:
        if message:
            (file or sys.stderr).write(message)

    def error(self, message: str) -> NoReturn:
        """A usage error in one line on stderr, pointing at --help; exit 2 (bad input)."""
        self.exit(ExitCode.BAD_INPUT, f"{self.prog}: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The full parser, with every subcommand's flags (imports each subcommand module)."""
    parser = _Parser(
        prog="fatswarm",
        description=(
            "Swarm emulator: every robot its own process over Eclipse Zenoh. Reference algorithm: "
            "uniform circle formation by transparent fat robots (Mondal & Gan Chaudhuri)."
        ),
    )
    parser.add_argument("--version", action="version", version=f"fatswarm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (module_name, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        module = importlib.import_module(module_name)
        adder = getattr(module, f"add_{name}_arguments", None) or module.add_arguments
        adder(p)
        p.set_defaults(_module=module_name, _name=name)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the process exit code.

    Standard output closed early (`fatswarm run ... | head -1`) ends quietly with 141, as a
    process killed by SIGPIPE would: no traceback, whatever was left to print is dropped.
    """
    try:
        try:
            return _main(argv)
        finally:
            sys.stdout.flush()  # here, so that a closed pipe is caught below, not at exit
    except BrokenPipeError:
        _drop_stdout()
        return ExitCode.BROKEN_PIPE


def _main(argv: Sequence[str] | None) -> int:
    """Parse, then run the subcommand; Ctrl-C exits 130 and SIGTERM 143, after unwinding."""
    previous = _raise_on_sigterm()
    try:
        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # --help, --version or a usage error: argparse printed it
            return exc.code if isinstance(exc.code, int) else int(exc.code is not None)
        args._argv = ["fatswarm", *(sys.argv[1:] if argv is None else argv)]  # for records
        module = importlib.import_module(args._module)
        run = getattr(module, f"main_{args._name}", None) or module.main
        code: int = run(args)
        return code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return ExitCode.INTERRUPTED
    except Terminated:
        print("terminated", file=sys.stderr)
        return ExitCode.TERMINATED
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _raise_on_sigterm() -> _Handler:
    """Make SIGTERM raise `Terminated` (main thread only); the handler it replaces, or None."""
    if threading.current_thread() is not threading.main_thread():
        return None

    def terminated(signum: int, frame: FrameType | None) -> None:
        raise Terminated

    return signal.signal(signal.SIGTERM, terminated)


def _drop_stdout() -> None:
    """Point standard output at /dev/null, so the flush at exit cannot fail again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        with contextlib.suppress(OSError, ValueError):  # no descriptor: an in-process capture
            os.dup2(devnull, sys.stdout.fileno())
    finally:
        os.close(devnull)


if __name__ == "__main__":
    sys.exit(main())
