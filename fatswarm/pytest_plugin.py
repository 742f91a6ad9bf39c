"""fatswarm's pytest plugin (entry point group `pytest11`): the `fatswarm_swarm` fixture runs a
networked swarm of your algorithm on loopback, one process per robot, and gives its record
(docs/algorithms.md, "Testing your algorithm"). Light to import: pytest loads it in every session.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import signal
import subprocess
import sys
import time
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Final

try:
    import pytest
except ImportError:  # the plugin is for pytest; fatswarm does not install it
    raise ImportError(
        "fatswarm's pytest plugin (the fatswarm_swarm fixture) needs pytest: "
        "pip install 'fatswarm[testing]'"
    ) from None

if TYPE_CHECKING:
    from fatswarm.world.record import RunRecord

MARK_ENV: Final = "FATSWARM_PYTEST_SWARM"  # every process of a run inherits it: found by it
DEFAULT_TIMEOUT_S: Final = 120.0  # a run still going then is stopped and its test fails
STOP_GRACE_S: Final = 15.0  # `fatswarm run` stops its parts on SIGTERM within this
KILL_WAIT_S: Final = 5.0
RUN_ENDED: Final = (0, 1, 3)  # formed; not formed (stalled, round cap, a part died); collisions
# flags the fixture gives itself: a record under tmp_path, no dashboard, quiet, networked
OWN_FLAGS: Final = frozenset(
    {"record", "force", "resume", "lockstep", "quiet", "q", "json", "no_dashboard"}
)
SHOWN_OUTPUT: Final = 2000  # characters of a failed run's output an error shows (the last)


class SwarmRunError(RuntimeError):
    """`fatswarm run` refused its input, did not end in time, or left no record (the message has
    its exit code and the end of its output)."""


class SwarmRunner:
    """The `fatswarm_swarm` fixture: call it to run a networked swarm and get its record; every
    process a run starts is stopped before the call returns, and again at teardown."""

    def __init__(self, tmp_path: Path) -> None:
        self.tmp_path = tmp_path
        self.marks: list[str] = []  # one per run: MARK_ENV's value in its processes

    def __call__(
        self,
        algorithm: str,
        n: int | None = 5,
        seed: int = 1,
        scheduler: str = "fsync",
        *,
        params: Mapping[str, object] | None = None,
        init: Sequence[Sequence[float]] | None = None,
        timeout: float = DEFAULT_TIMEOUT_S,
        **flags: object,
    ) -> RunRecord:
        """Run `fatswarm run --algorithm ALGORITHM -n N --seed SEED --scheduler SCHEDULER` (a
        registered name, `pkg.mod:OBJ`, or `path/file.py:OBJ` from the current directory), with
        `params` as `--param NAME=VALUE`, `init` (positions [[x, y], ...]: the start, n taken
        from it) and any other flag of `fatswarm run` as a keyword (`sight=6`, `non_rigid=1.0`,
        `record_views=True`, `visibility="opaque"`...); return its record
        (`fatswarm.world.record_read.read_record`), whatever the run's end: check
        `record.result`. Raises SwarmRunError if it refuses its input, outlasts `timeout`
        seconds, or leaves no record."""
        index = len(self.marks) + 1
        record = self.tmp_path / f"fatswarm-swarm-{index}.jsonl"
        log = self.tmp_path / f"fatswarm-swarm-{index}.log"
        argv = [sys.executable, "-m", "fatswarm.deploy.cli", "run", "--algorithm", algorithm]
        if init is not None:
            start = self.tmp_path / f"fatswarm-swarm-{index}-start.json"
            start.write_text(json.dumps({"positions": [list(map(float, p)) for p in init]}))
            argv += ["--init", str(start)]
        elif n is not None:
            argv += ["-n", str(n)]
        argv += ["--seed", str(seed), "--scheduler", scheduler]
        argv += [*run_flags(params or {}, flags), "--no-dashboard", "-q", "--record", str(record)]
        mark = f"{os.getpid()}-{index}-{secrets.token_hex(6)}"
        self.marks.append(mark)
        code = _run(argv, log, mark, timeout)
        output = log.read_text(errors="replace")
        if code is None:
            raise SwarmRunError(
                f"fatswarm run did not end within {timeout:g} s; stopped: "
                f"{output[-SHOWN_OUTPUT:].strip()}"
            )
        if code not in RUN_ENDED or not record.exists():
            raise SwarmRunError(
                f"fatswarm run exited with {code}: {output[-SHOWN_OUTPUT:].strip()}"
            )
        # the record reader (numpy, the record's types) only once a run asks: pytest loads this
        # module in every session of an environment where fatswarm is installed
        from fatswarm.world.record_read import read_record

        return read_record(record)

    def close(self) -> None:
        """Stop whatever any run of this fixture left behind (nothing, normally)."""
        for mark in self.marks:
            stop_marked(mark)


def run_flags(params: Mapping[str, object], flags: Mapping[str, object]) -> list[str]:
    """`--param NAME=VALUE` for each parameter, then `--flag-name VALUE` for each keyword (True:
    the flag alone; False or None: left out; a list or tuple: the flag repeated). Raises
    ValueError for a flag the fixture sets itself."""
    out: list[str] = []
    for name, value in params.items():
        out += ["--param", f"{name}={_text(value)}"]
    for key, value in flags.items():
        if key in OWN_FLAGS:
            raise ValueError(f"fatswarm_swarm sets --{key.replace('_', '-')} itself")
        flag = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            out.append(flag)
            continue
        values = value if isinstance(value, (list, tuple)) else [value]
        for item in values:
            out += [flag, _text(item)]
    return out


def _text(value: object) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def _run(argv: list[str], log: Path, mark: str, timeout: float) -> int | None:
    """Run `argv` in its own process group, its output to `log`, marked with `mark`; its exit
    code (None if it outlasted `timeout`). Every process it started is stopped on return."""
    env = {**os.environ, MARK_ENV: mark, "PYTHONPATH": python_path()}
    with log.open("wb") as out:
        proc = subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            env=env,
        )
    try:
        return proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    finally:
        _stop_group(proc)
        stop_marked(mark)


def python_path() -> str:
    """PYTHONPATH for the run: the current directory and the test session's own entries of
    sys.path (where pytest put the tests' folders), so the run imports the algorithm as the test
    does; then PYTHONPATH as it was."""
    prefixes = {os.path.realpath(p) for p in (sys.prefix, sys.base_prefix, sys.exec_prefix)}
    entries = [os.getcwd()]
    for entry in sys.path:
        full = os.path.realpath(entry or os.getcwd())
        inside = any(full == p or full.startswith(p + os.sep) for p in prefixes)
        if os.path.isdir(full) and not inside and full not in entries:
            entries.append(full)
    given = os.environ.get("PYTHONPATH")
    return os.pathsep.join([*entries, *([given] if given else [])])


def _stop_group(proc: subprocess.Popen[bytes]) -> None:
    """SIGTERM `fatswarm run`'s process group if it still runs (it stops every part it started),
    SIGKILL after STOP_GRACE_S; reaped."""
    if proc.poll() is not None:
        return  # reaped: its pid (and group id) may be another's now; the mark finds the rest
    _signal_group(proc.pid, signal.SIGTERM)
    try:
        proc.wait(timeout=STOP_GRACE_S)
    except subprocess.TimeoutExpired:
        _signal_group(proc.pid, signal.SIGKILL)
        proc.wait()


def _signal_group(pgid: int, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, sig)


def marked(mark: str) -> list[int]:
    """The processes whose environment carries MARK_ENV=`mark` (Linux: read from /proc; none
    elsewhere): those a run started, its parts in their own sessions included."""
    wanted = f"{MARK_ENV}={mark}".encode()
    found = []
    for environ in Path("/proc").glob("[0-9]*/environ"):
        with contextlib.suppress(OSError):
            if wanted in environ.read_bytes().split(b"\0"):
                found.append(int(environ.parent.name))
    return [pid for pid in found if pid != os.getpid()]


def stop_marked(mark: str) -> None:
    """SIGTERM every process of the run marked `mark`, SIGKILL those left after KILL_WAIT_S."""
    pids = marked(mark)
    for sig in (signal.SIGTERM, signal.SIGKILL):
        for pid in pids:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, sig)
        deadline = time.monotonic() + KILL_WAIT_S
        while pids and time.monotonic() < deadline:
            pids = [pid for pid in pids if _alive(pid)]
            if pids:
                time.sleep(0.05)
        if not pids:
            return


def _alive(pid: int) -> bool:
    """Whether `pid` runs (not a zombie; Linux /proc)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


@pytest.fixture
def fatswarm_swarm(tmp_path: Path) -> Iterator[SwarmRunner]:
    """Run networked swarms of your algorithm on loopback: `fatswarm_swarm("pkg.mod:OBJ", n=5,
    seed=1, scheduler="fsync", **flags)` returns the run's record (see `SwarmRunner`). Each run
    is `fatswarm run` in its own process group (world hosting the Zenoh router on a free loopback
    port, multicast scouting off, coordinator, one process per robot), its record and output
    under tmp_path; every process it started is stopped when it returns and at teardown."""
    runner = SwarmRunner(tmp_path)
    try:
        yield runner
    finally:
        runner.close()


__all__ = ["MARK_ENV", "SwarmRunError", "SwarmRunner", "fatswarm_swarm", "run_flags"]
