"""The `fatswarm` command: one subcommand per role; each lives in its own module.

Every subcommand module exposes `add_arguments(parser)` and `main(args) -> int` (or
`add_<name>_arguments` / `main_<name>` when one module serves several commands). Subcommand
modules import Zenoh, matplotlib and other heavy things inside their `main`, never at module level,
so `--help` stays fast and `fatswarm replay` works without a router.
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import importlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from types import FrameType
from typing import TYPE_CHECKING, Any, Final, NoReturn

from fatswarm.deploy.flags import Terminated, refuse_repeats
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.version import __version__

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
        "draw a record's trajectories to SVG or PNG, or animate them (GIF, MP4; fatswarm[plot])",
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


# name -> what its exit codes mean, for the commands whose module says none in its help
EXIT_CODES: Final = {
    "algorithms": "0 listed; 2 bad input (an algorithm that does not load: one line on stderr "
    "says why)",
    "router": "0 stopped (Ctrl-C or SIGTERM: a router routes until then); 2 bad input (an "
    "endpoint, a port in use, a --config: one line on stderr says what to fix)",
    "world": "0 stopped (Ctrl-C or SIGTERM: the world serves until then; its --state file keeps "
    "every committed round); 1 the algorithm's goal raised (the run cannot be decided); 2 bad "
    "input, or a second world of the swarm (one line on stderr says what to fix); 4 the --state "
    "file could not be written",
    "coordinator": "0 formed with no collision; 1 not formed (stalled, out of rounds, or stopped "
    "by Ctrl-C or SIGTERM before the run ended); 2 bad input, or a second coordinator of the "
    "swarm (one line on stderr says what to fix); 3 formed, but with collisions; 5 the world "
    "gave no usable answer for --give-up seconds (one line says so)",
    "agent": "0 stopped (Ctrl-C or SIGTERM: a robot runs until then); 2 bad input (one line on "
    "stderr says what to fix)",
    "agents": "0 stopped (Ctrl-C or SIGTERM: the agents run until then); 1 every agent process "
    "exited by itself; 2 bad input (one line on stderr says what to fix)",
    "dashboard": "0 the run formed with no collision; 1 not formed, or left (Ctrl-C) before it "
    "ended; 2 bad input, or a router it cannot follow (one line on stderr says why); 3 formed, "
    "but with collisions",
    "secure": "0 the folder is written; 2 bad input, or a folder that cannot be written (one "
    "line on stderr says what to fix)",
    "replay": "0 played (or printed, or saved with --svg); 2 bad input (a record that cannot be "
    "read, a --round or --robot it does not have: one line on stderr says what to fix)",
    "plot": "0 drawn; 2 bad input (a record that cannot be read, an OUT it cannot write, "
    "matplotlib missing: one line on stderr says what to fix)",
}
INTERRUPTED_CODE: Final = f"{ExitCode.INTERRUPTED:d} interrupted (Ctrl-C)"
COMMON_EXIT_CODES: Final = f"{ExitCode.BROKEN_PIPE:d} standard output closed early (e.g. | head)"
STOPPED_BY_SIGNALS: Final = ("router", "world", "coordinator", "agent", "agents", "dashboard")


def exit_codes_epilog(name: str) -> str | None:
    """The `exit codes: ...` line of a command's help that its module does not write itself."""
    codes = EXIT_CODES.get(name)
    if codes is None:
        return None
    if name not in STOPPED_BY_SIGNALS:  # the parts stop on Ctrl-C and say so above
        codes = f"{codes}; {INTERRUPTED_CODE}"
    return f"exit codes: {codes}; {COMMON_EXIT_CODES}."


_Handler = Callable[[int, FrameType | None], Any] | int | None  # what signal.signal returns


class _Formatter(argparse.HelpFormatter):
    """argparse's help, with the default of every flag that has one and whose help does not
    say it already."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            "default" in text.lower()
            or any(default is nothing for nothing in (None, False, True))  # 0 is a default
            or default == argparse.SUPPRESS
            or (isinstance(default, list) and not default)
            or action.nargs == 0
        ):
            return action.help
        shown = " ".join(default) if isinstance(default, list) else default
        return f"{text} (default {shown})"


class _Parser(argparse.ArgumentParser):
    """argparse's parser, except that a failed write of --help or --version is not swallowed
    (`main` ends a closed pipe the same way, exit 141, whatever printed into it), a usage error
    is one line, and a wrong choice suggests the closest one."""

    def _print_message(self, message: str, file: SupportsWrite[str] | None = None) -> None:
        if message:
            (file or sys.stderr).write(message)

    def error(self, message: str) -> NoReturn:
        """A usage error in one line on stderr, pointing at --help; exit 2 (bad input)."""
        self.exit(ExitCode.BAD_INPUT, f"{self.prog}: {message} (see {self.prog} --help)\n")

    def _check_value(self, action: argparse.Action, value: Any) -> None:
        """A value outside the choices, refused with the closest choice, if one is close."""
        if action.choices is None or value in action.choices:
            return
        choices = [str(c) for c in action.choices]
        close = difflib.get_close_matches(str(value), choices, n=1)
        hint = f"; did you mean {close[0]}?" if close else ""
        raise argparse.ArgumentError(
            action, f"invalid choice: {value!r} (choose from {', '.join(choices)}){hint}"
        )


def build_parser() -> argparse.ArgumentParser:
    """The full parser, with every subcommand's flags (imports each subcommand module)."""
    return _build()[0]


def _build() -> tuple[argparse.ArgumentParser, dict[str, argparse.ArgumentParser]]:
    """The full parser and each subcommand's own parser, by name."""
    parser = _Parser(
        prog="fatswarm",
        description=(
            "Swarm emulator: every robot its own process over Eclipse Zenoh. Reference algorithm: "
            "uniform circle formation by transparent fat robots (Mondal & Gan Chaudhuri)."
        ),
    )
    parser.add_argument("--version", action="version", version=f"fatswarm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    commands: dict[str, argparse.ArgumentParser] = {}
    for name, (module_name, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text, formatter_class=_Formatter)
        module = importlib.import_module(module_name)
        adder = getattr(module, f"add_{name}_arguments", None) or module.add_arguments
        adder(p)
        refuse_repeats(p)  # a flag of one value given twice, with two values: one line
        if p.epilog is None:
            p.epilog = exit_codes_epilog(name)
        p.set_defaults(_module=module_name, _name=name)
        commands[name] = p
    return parser, commands


def unrecognized(command: argparse.ArgumentParser, extras: Sequence[str]) -> str:
    """The usage error for arguments a subcommand does not take, each unknown flag with the
    closest flag it has, if one is close: "unknown flag --seeed (did you mean --seed?)"."""
    flags = [o for a in command._actions for o in a.option_strings if o.startswith("--")]
    shown = []
    for token in extras:
        flag = token.split("=", 1)[0]
        close = difflib.get_close_matches(flag, flags, n=1) if flag.startswith("--") else []
        shown.append(f"{token} (did you mean {close[0]}?)" if close else token)
    unknown = [t for t in extras if t.startswith("-") and t != "-"]
    if len(extras) == 1 or (len(unknown) == 1 and extras[0] == unknown[0]):
        # one unknown flag (what follows it is its value) or one stray argument
        return f"unknown {'flag' if unknown else 'argument'} {shown[0]}"
    return f"unrecognized arguments: {' '.join(shown)}"


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
        parser, commands = _build()
        try:
            args, extras = parser.parse_known_args(argv)
            if extras:  # blamed on the subcommand that does not take them, not on `fatswarm`
                commands[args._name].error(unrecognized(commands[args._name], extras))
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
