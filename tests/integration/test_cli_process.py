"""`fatswarm` as a process: SIGTERM exits 143 and Ctrl-C 130 (lockstep and networked), a closed
standard output ends quietly with 141, and a networked --json run keeps stdout to one object."""

from __future__ import annotations

import contextlib
import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

import pytest
from netharness import descendants_of, running

from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[2]
FATSWARM = [sys.executable, "-m", "fatswarm.deploy.cli"]
DEADLINE_S = 120.0  # a deadline, not a duration: the machine is shared


def _default_sigint() -> None:
    # a child of a shell that ignores SIGINT (a background job) would inherit the ignoring, and
    # Python only turns SIGINT into KeyboardInterrupt where it is not ignored
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class Lines:
    """The lines of a stream, read by a thread, so a test can wait for one with a deadline."""

    def __init__(self, stream: IO[bytes]) -> None:
        self.lines: list[str] = []
        self._new: queue.Queue[None] = queue.Queue()
        self._thread = threading.Thread(target=self._read, args=(stream,), daemon=True)
        self._thread.start()

    def _read(self, stream: IO[bytes]) -> None:
        for raw in stream:
            self.lines.append(raw.decode(errors="replace"))
            self._new.put(None)

    def wait_for(self, predicate: Callable[[str], bool], deadline_s: float = DEADLINE_S) -> bool:
        end = time.monotonic() + deadline_s
        while not any(predicate(line) for line in list(self.lines)):
            remaining = end - time.monotonic()
            if remaining <= 0 or (not self._thread.is_alive() and self._new.empty()):
                return False
            with contextlib.suppress(queue.Empty):
                self._new.get(timeout=min(remaining, 0.5))
        return True

    def text(self) -> str:
        self._thread.join(timeout=30)
        return "".join(self.lines)


def _stop(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    for stream in (proc.stdout, proc.stderr):
        if stream is not None:
            stream.close()


@pytest.fixture
def started() -> Iterator[list[subprocess.Popen[bytes]]]:
    procs: list[subprocess.Popen[bytes]] = []
    try:
        yield procs
    finally:
        for proc in procs:
            _stop(proc)


def _start(procs: list[subprocess.Popen[bytes]], argv: list[str]) -> subprocess.Popen[bytes]:
    proc = subprocess.Popen(
        [*FATSWARM, *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=ROOT,
        start_new_session=True,
        preexec_fn=_default_sigint,
    )
    procs.append(proc)
    return proc


# --- signals ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("sig", "code", "said"),
    [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")],
    ids=["SIGTERM", "SIGINT"],
)
def test_a_signalled_lockstep_run_exits_128_plus_the_signal_with_its_record_closed(
    sig: int, code: int, said: str, tmp_path: Path, started: list[subprocess.Popen[bytes]]
) -> None:
    target = tmp_path / "run.jsonl"
    # centralized, n = 200: about a minute, long enough to be signalled mid-run
    proc = _start(
        started,
        [
            "run",
            "--lockstep",
            "-n",
            "200",
            "--seed",
            "1",
            "--scheduler",
            "centralized",
            "--record",
            str(target),
        ],
    )
    assert proc.stderr is not None and proc.stdout is not None
    err = Lines(proc.stderr)
    assert err.wait_for(lambda line: line.startswith("round ")), err.text()  # a progress line
    proc.send_signal(sig)
    assert proc.wait(timeout=DEADLINE_S) == code, err.text()
    text = err.text()
    record = read_record(target, allow_torn_end=True)
    assert record.header.n == 200 and record.result is None
    k = len(record.rounds)  # the line says after which round the record ends, and how to go on
    assert text.splitlines()[-1] == (
        f"{said} after round {k}; go on with `fatswarm run --lockstep --record {target} --resume`"
    ), text
    assert "Traceback" not in text, text
    assert proc.stdout.read() == b""  # no summary for a run that did not end


def _all_started(proc: subprocess.Popen[bytes], n: int, err: Lines) -> list[int]:
    """The pids under a networked run once all are up: world, coordinator, agents host, n agents."""
    children: list[int] = []
    end = time.monotonic() + DEADLINE_S
    while len(children) < n + 3:
        assert time.monotonic() < end and proc.poll() is None, err.text()
        children = descendants_of(proc.pid)
        time.sleep(0.05)
    return children


def test_ctrl_c_to_a_networked_run_exits_130_and_stops_every_process(
    started: list[subprocess.Popen[bytes]],
) -> None:
    n = 3
    proc = _start(started, ["run", "-n", str(n), "--seed", "1", "--pace", "0.5", "-q"])
    assert proc.stderr is not None
    err = Lines(proc.stderr)
    children = _all_started(proc, n, err)
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=DEADLINE_S) == 130, err.text()
    text = err.text()
    assert "interrupted: stopping every process started" in text and "Traceback" not in text
    assert not [pid for pid in children if running(pid)]


@pytest.mark.parametrize(
    ("part", "said"),
    [("agents", "the agents' process"), ("coordinator", "the coordinator process")],
)
def test_a_networked_run_whose_part_dies_ends_with_1_and_says_which(
    started: list[subprocess.Popen[bytes]],
    tmp_path: Path,
    part: str,
    said: str,
) -> None:
    n = 3
    record = tmp_path / "run.jsonl"
    proc = _start(
        started,
        ["run", "-n", str(n), "--seed", "1", "--pace", "0.5", "-q", "--record", str(record)],
    )
    assert proc.stderr is not None
    err = Lines(proc.stderr)
    children = _all_started(proc, n, err)
    victim = next(
        p
        for p in children  # the launcher's own child (agents are forked copies)
        if part.encode() in Path(f"/proc/{p}/cmdline").read_bytes().split(b"\0")
        and Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[1] == str(proc.pid)
    )
    os.kill(victim, signal.SIGKILL)
    assert proc.wait(timeout=DEADLINE_S) == 1, err.text()
    text = err.text()
    assert f"{said} exited with code -9" in text and "Traceback" not in text
    assert not [pid for pid in children if running(pid)]
    assert read_record(record).header.n == n


# --- a closed standard output ----------------------------------------------------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["run", "--lockstep", "-n", "8", "--seed", "1", "-q"],
        ["run", "--lockstep", "-n", "8", "--seed", "1", "-q", "--json"],
    ],
    ids=["help", "run", "run-json"],
)
def test_a_closed_stdout_ends_quietly_with_141(argv: list[str]) -> None:
    read_end, write_end = os.pipe()
    os.close(read_end)  # as `| head -1` once it has its line: every write fails with EPIPE
    try:
        done = subprocess.run(
            [*FATSWARM, *argv],
            stdout=write_end,
            stderr=subprocess.PIPE,
            cwd=ROOT,
            timeout=DEADLINE_S,
        )
    finally:
        os.close(write_end)
    assert done.returncode == 141, done.stderr
    assert done.stderr == b""


def test_a_run_piped_into_head_prints_its_verdict_and_no_traceback() -> None:
    command = " ".join([*FATSWARM, "run", "--lockstep", "-n", "8", "--seed", "1", "-q"])
    done = subprocess.run(
        ["sh", "-c", f"{command} | head -1"], capture_output=True, cwd=ROOT, timeout=DEADLINE_S
    )
    assert re.fullmatch(rb"formed in \d+ rounds, collision-free\n", done.stdout), done.stdout
    assert done.stderr == b""


# --- a networked --json run ------------------------------------------------------------------


def test_a_networked_json_run_prints_one_object_on_stdout_and_progress_on_stderr(
    tmp_path: Path, started: list[subprocess.Popen[bytes]]
) -> None:
    target = tmp_path / "net.jsonl"
    proc = _start(
        started,
        [
            "run",
            "-n",
            "4",
            "--seed",
            "2",
            "--scheduler",
            "fsync",
            "--record",
            str(target),
            "--json",
        ],
    )
    out, err = proc.communicate(timeout=240)
    assert proc.returncode == 0, err.decode(errors="replace")[-3000:]
    (line,) = out.decode().splitlines()
    summary = json.loads(line)
    assert summary["status"] == "formed" and summary["exit_code"] == 0
    assert (summary["n"], summary["seed"], summary["scheduler"]) == (4, 2, "fsync")
    assert summary["record"] == str(target)
    result = read_record(target).result
    assert result is not None and summary["rounds"] == result.rounds
    assert re.search(rb"^round \d+ \w+: targets \d+/4", err, re.MULTILINE), err[-3000:]
