"""The run `fatswarm run`'s flags ask for, checked before anything runs (shared by the lock step and
the networked launcher, so both refuse the same input with the same message): the outputs, the
flags of the other mode, and the run itself (`resolve_run`)."""

from __future__ import annotations

import argparse
import os

from fatswarm.deploy.commands.resume import resolve_resume
from fatswarm.deploy.engine.config import RunConfig, RunInputError, RunSetup
from fatswarm.deploy.flags import check_start_flags, check_writable


def networked_flags_given(args: argparse.Namespace) -> list[str]:
    """The networked-only flags (the launcher's) that differ from their defaults in `args`."""
    flags: tuple[tuple[str, str, object], ...] = getattr(args, "_networked_flags", ())
    return [flag for flag, dest, default in flags if getattr(args, dest, default) != default]


def check_lockstep_flags(args: argparse.Namespace) -> None:
    """Refuse networked-only flags in a lockstep run rather than ignore them (RunInputError)."""
    given = networked_flags_given(args)
    if given:
        only = "is" if len(given) == 1 else "are"
        raise RunInputError(
            f"{', '.join(given)} {only} for networked runs only: drop "
            f"{'it' if len(given) == 1 else 'them'} or --lockstep"
        )


def check_outputs(args: argparse.Namespace) -> None:
    """Refuse a --record or --svg that cannot be written, before anything runs (RunInputError).

    An existing record is overwritten only with --force (--resume continues it).
    """
    record: str | None = args.record
    resume = bool(getattr(args, "resume", False))
    if resume and not record:
        raise RunInputError("--resume continues a run record: name it with --record PATH")
    if getattr(args, "force", False) and not record and getattr(args, "lockstep", True):
        raise RunInputError("--force lets --record overwrite its file: name it with --record PATH")
    if record:
        check_writable("--record", record)
        if resume and args.force:
            raise RunInputError(
                "--resume continues the --record file, --force overwrites it: pass one of them"
            )
        if os.path.exists(record) and not os.path.isfile(record):
            raise RunInputError(
                f"--record {record} exists and is not a regular file (a device, "
                "a pipe...); name a file"
            )
        if os.path.exists(record) and not (args.force or resume):
            raise RunInputError(f"--record {record} exists; pass --force to overwrite it")
    svg: str | None = getattr(args, "svg", None)  # the dashboard's flag
    if svg:
        check_svg(svg)


def check_svg(svg: str) -> None:
    """Refuse an --svg that cannot be written or does not end in .svg: the final frame is SVG,
    and SVG in a .png file opens nowhere (`fatswarm plot RECORD OUT.png` draws a PNG)."""
    check_writable("--svg", svg)
    if os.path.splitext(svg)[1].lower() != ".svg":
        raise RunInputError(
            f"--svg writes the final frame as SVG: name a .svg file, got {svg!r} (for a PNG: "
            "--record R, then fatswarm plot R OUT.png)"
        )


def resolve_run(args: argparse.Namespace, seed: int) -> RunSetup:
    """Build the run the flags describe (shared by lockstep and networked runs, so both refuse
    the same input with the same message); raises one of `input_errors()`."""
    check_outputs(args)
    check_start_flags(args)
    if getattr(args, "resume", False):
        return resolve_resume(args)
    return RunConfig.from_args(args, seed).resolve(networked=not getattr(args, "lockstep", True))


__all__ = [
    "check_lockstep_flags",
    "check_outputs",
    "check_svg",
    "networked_flags_given",
    "resolve_run",
]
