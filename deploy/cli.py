"""The `fatswarm` command: one subcommand per role; each lives in its own module.

Every subcommand module exposes `add_arguments(parser)` and `main(args) -> int` (or
`add_<name>_arguments` / `main_<name>` when one module serves several commands). Subcommand
modules import Zenoh, matplotlib and other heavy things inside their `main`, never at module level,
so `--help` stays fast and `fatswarm replay` works without a router.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

# name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "run": ("fatswarm.deploy.run", "run a swarm (networked by default, --lockstep: one process)"),
    "router": ("fatswarm.deploy.parts", "run a Zenoh router alone (for several hosts)"),
    "world": ("fatswarm.deploy.parts", "run the world process alone"),
    "coordinator": ("fatswarm.deploy.parts", "run the coordinator process alone"),
    "agent": ("fatswarm.deploy.parts", "run one agent (robot) process alone"),
    "agents": ("fatswarm.deploy.parts", "run K agent processes on this host"),
    "dashboard": ("fatswarm.deploy.dashboard", "attach a read-only dashboard to a running swarm"),
    "replay": ("fatswarm.deploy.replay", "play a run record in the dashboard"),
    "plot": ("fatswarm.deploy.plot", "draw a record's trajectories to SVG or PNG (fatswarm[plot])"),
}

EXIT_BAD_INPUT = 2


def build_parser() -> argparse.ArgumentParser:
    """The full parser, with every subcommand's flags (imports each subcommand module)."""
    parser = argparse.ArgumentParser(
        prog="fatswarm",
        description=(
            "Swarm emulator: every robot its own process over Eclipse Zenoh. Reference algorithm: "
            "uniform circle formation by transparent fat robots (Mondal & Gan Chaudhuri)."
        ),
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (module_name, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        module = importlib.import_module(module_name)
        adder = getattr(module, f"add_{name}_arguments", None) or module.add_arguments
        adder(p)
        p.set_defaults(_module=module_name, _name=name)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    module = importlib.import_module(args._module)
    run = getattr(module, f"main_{args._name}", None) or module.main
    try:
        code: int = run(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
