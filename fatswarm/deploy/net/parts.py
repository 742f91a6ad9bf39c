"""Each networked part alone (`fatswarm router|world|coordinator|agent|agents`), for several hosts.

Also the entry point the launcher spawns (`python -m deploy.net.parts <part> ...`): it parses only
the part's own flags, so starting 128 agents does not import every subcommand of the CLI. Each
part is its own module (deploy/net/part_*.py), and this one imports only the part it runs.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from fatswarm.domain.outcome import ExitCode

# part -> the module holding its `add_<part>_arguments(parser)` and `main_<part>(args)`
PARTS = {
    "router": "fatswarm.deploy.net.part_router",
    "world": "fatswarm.deploy.net.part_world",
    "coordinator": "fatswarm.deploy.net.part_coordinator",
    "agent": "fatswarm.deploy.net.part_agents",
    "agents": "fatswarm.deploy.net.part_agents",
}


# --- `python -m deploy.net.parts <part> ...` ------------------------------------------------------


def main(argv: Sequence[str] | None = None) -> int:
    """Parse one part's flags and run it."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] not in PARTS:
        print(f"usage: python -m deploy.net.parts {{{','.join(PARTS)}}} ...", file=sys.stderr)
        return ExitCode.BAD_INPUT
    module = importlib.import_module(PARTS[argv[0]])
    parser = argparse.ArgumentParser(prog=f"fatswarm {argv[0]}")
    getattr(module, f"add_{argv[0]}_arguments")(parser)
    code: int = getattr(module, f"main_{argv[0]}")(parser.parse_args(argv[1:]))
    return code


if __name__ == "__main__":
    sys.exit(main())
