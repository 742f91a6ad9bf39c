"""How a run stands and how a command ends: the statuses and exit codes, each defined once."""

from __future__ import annotations

import enum


class Status(enum.StrEnum):
    """Where a run stands. A StrEnum: records and messages carry the plain string."""

    RUNNING = "running"
    FORMED = "formed"  # the goal holds and every robot, active since the last change, stays
    STALLED = "stalled"  # every robot stays, but the goal does not hold
    MAX_ROUNDS = "max_rounds"  # the round cap came first


ENDED: tuple[Status, ...] = (Status.FORMED, Status.STALLED, Status.MAX_ROUNDS)


class ExitCode(enum.IntEnum):
    """Every exit code of the `fatswarm` command and its parts, defined once."""

    FORMED = 0  # formed, and no robot was ever stopped by contact
    OK = 0  # (the same code) a command that is not a run, such as replay or plot, did its job
    NOT_FORMED = 1  # stalled or max_rounds, collisions or not
    BAD_INPUT = 2  # one line on stderr says what to fix
    FORMED_WITH_COLLISIONS = 3  # formed, but not the collision-free formation
    RECORD_FAILED = 4  # the run record could not be written (disk full...): resume once fixed
    NO_PEER = 5  # a coordinator whose world gave no usable answer for its --give-up bound
    INTERRUPTED = 130  # 128 + SIGINT (Ctrl-C)
    BROKEN_PIPE = 141  # 128 + SIGPIPE: standard output closed early (`| head -1`)
    TERMINATED = 143  # 128 + SIGTERM


def exit_code_for(status: Status, collisions: int) -> ExitCode:
    """0 only for a collision-free formation; formed through collisions is 3, not formed is 1."""
    if status != Status.FORMED:
        return ExitCode.NOT_FORMED
    return ExitCode.FORMED if collisions == 0 else ExitCode.FORMED_WITH_COLLISIONS


__all__ = ["ENDED", "ExitCode", "Status", "exit_code_for"]
