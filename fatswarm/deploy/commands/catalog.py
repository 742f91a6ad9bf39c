"""`fatswarm algorithms`: the registered algorithms, or one, with parameters and assumptions."""

from __future__ import annotations

import argparse
import sys

from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.registry import available, load_algorithm
from fatswarm.domain.seam import AlgorithmError, assumptions_of


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm algorithms`."""
    p.add_argument(
        "algorithm",
        nargs="?",
        default=None,
        metavar="NAME",
        help="show this one (a registered name, module:attribute or "
        "path/to/file.py:attribute) with its parameters; default: list them all",
    )


def describe(ref: str) -> str:
    """An algorithm's name, summary, parameters (name, default, help) and what it assumes
    (`Assumptions`), one per line."""
    algorithm = load_algorithm(ref)
    lines = [f"{algorithm.name}: {algorithm.summary}"]
    flags = [f"--param {spec.name}={spec.default!r}" for spec in algorithm.parameters]
    width = max((len(flag) for flag in flags), default=0)
    for flag, spec in zip(flags, algorithm.parameters, strict=True):
        lines.append(f"  {flag:<{width}}  {spec.help}")
    if not algorithm.parameters:
        lines.append("  (no parameters)")
    lines.append("  assumes (a run outside goes ahead and says so):")
    lines += [f"    {line}" for line in assumptions_of(algorithm).lines()]
    return "\n".join(lines)


def main(args: argparse.Namespace) -> int:
    """Print the catalogue (or one entry); an algorithm that does not load is one line, exit 2."""
    refs = [args.algorithm] if args.algorithm else list(available())
    shown = 0
    for ref in refs:
        try:
            text = describe(ref)
        except AlgorithmError as exc:
            print(f"fatswarm algorithms: {exc}", file=sys.stderr)
            if args.algorithm:
                return ExitCode.BAD_INPUT
            continue  # a broken plug-in among the registered ones: said, the rest still listed
        print(("\n" if shown else "") + text)
        shown += 1
    return ExitCode.OK


__all__ = ["add_arguments", "describe", "main"]
