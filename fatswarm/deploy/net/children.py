"""Child processes in their own process groups, stopped together: SIGTERM, a grace, then SIGKILL."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Sequence
from types import TracebackType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    pass


STOP_GRACE_S = 5.0  # SIGTERM first; SIGKILL whatever is still there after this

STOP_GRACE_PER_AGENT_S = 0.1  # hundreds of agents closing sessions at once share two cores


def stop_grace_s(agents: int) -> float:
    """How long a group holding `agents` agent processes may take to stop on SIGTERM."""
    return STOP_GRACE_S + STOP_GRACE_PER_AGENT_S * agents


class Children:
    """Processes started here, each in its own process group; all stopped on exit."""

    def __init__(self, grace_s: float = STOP_GRACE_S) -> None:
        self.procs: dict[str, subprocess.Popen[bytes]] = {}
        self.grace_s = grace_s

    def __enter__(self) -> Children:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop_all()

    def start(self, name: str, argv: Sequence[str], **kwargs: Any) -> subprocess.Popen[bytes]:
        """Start `argv` as its own process group (so its own children go with it)."""
        proc = subprocess.Popen(list(argv), start_new_session=True, **kwargs)
        self.procs[name] = proc
        return proc

    def exited(self) -> dict[str, int]:
        """Children that have exited, with their exit codes."""
        return {
            name: code for name, proc in self.procs.items() if (code := proc.poll()) is not None
        }

    def stop(self, name: str, sig: int = signal.SIGTERM) -> None:
        """Signal one child's process group."""
        _signal_group(self.procs[name], sig)

    def stop_all(self, grace_s: float | None = None) -> None:
        """SIGTERM every group, wait up to `grace_s`, SIGKILL the rest, reap everything."""
        grace_s = self.grace_s if grace_s is None else grace_s
        for proc in self.procs.values():
            _signal_group(proc, signal.SIGTERM)
        deadline = time.monotonic() + grace_s
        for proc in self.procs.values():
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        stubborn = [name for name, proc in self.procs.items() if proc.poll() is None]
        if stubborn:
            print(
                f"did not stop on SIGTERM within {grace_s:g} s, killed: {', '.join(stubborn)}",
                file=sys.stderr,
            )
        for proc in self.procs.values():
            _signal_group(proc, signal.SIGKILL)  # also ends grandchildren left in the group
            proc.wait()


def _signal_group(proc: subprocess.Popen[bytes], sig: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, sig)
