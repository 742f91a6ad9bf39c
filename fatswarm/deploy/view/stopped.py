"""The one line a run that stopped before its end prints last (a signal, or a record it could not
write): after which round, and how to go on. One definition for the lock step
(`deploy.commands.run_lockstep`) and the networked launcher (`deploy.net.launcher`)."""

from __future__ import annotations

import shlex

from fatswarm.deploy.view.summary import unit


def stopped_line(
    word: str,
    done: int,
    *,
    record: str | None,
    scheduler: str,
    lockstep: bool = False,
    seed: int | None = None,
    fix: bool = False,
) -> str:
    """The line a run stopped by a signal (`word`: "interrupted", "terminated") or a failed write
    ("stopped", with `fix`) prints: after which round, and how to go on (`fatswarm run --record R
    --resume`, with `--lockstep` for a `lockstep` run), or why it cannot be. `done`: the rounds
    (ended cycles, under an async model) its record holds. `fix`: something must be fixed first
    (a full disk)."""
    after = f"{word} after {unit(scheduler)} {done}"
    del seed  # (every run resumes, async ones too: by a replay, `lockstep.ReplayedRecord`)
    if not record:
        return f"{after} (no --record: nothing to resume)"
    mode = " --lockstep" if lockstep else ""
    then = "once that is fixed, go on" if fix else "go on"
    return f"{after}; {then} with `fatswarm run{mode} --record {shlex.quote(record)} --resume`"


__all__ = ["stopped_line"]
