"""Ctrl-C or SIGTERM on a networked `fatswarm run --record X`: exit 130 or 143, every process
stopped, and a last line saying after which round its record stopped and how to go on (below the
live dashboard's final frame when it showed one); `--resume` then ends it as the lock step does."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from netharness import DEADLINE_S, assert_same_run, lockstep_record
from test_dashboard_pty import PtyProcess, screen_text

from fatswarm.deploy.net.launcher import stopped_line
from fatswarm.world.record import RecordFormatError
from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration

N, SEED = 4, 3  # forms under ssync in about a dozen rounds (as the lock step says)


def _rounds(record: Path) -> int:
    """Committed rounds in the record so far (0 while it is not there or has no header yet)."""
    try:
        return len(read_record(record, allow_torn_end=True).rounds)
    except (RecordFormatError, OSError):
        return 0


def _wait_for_rounds(record: Path, rounds: int, proc: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while _rounds(record) < rounds:
        assert proc.poll() is None, "the run ended before the signal"
        assert time.monotonic() < deadline, f"no round {rounds} in {DEADLINE_S} s"
        time.sleep(0.05)


def _said(word: str, record: Path) -> str:
    return stopped_line(word, _rounds(record), record=str(record), scheduler="ssync", seed=SEED)


def _run(record: Path, *flags: str) -> list[str]:
    return [
        *(sys.executable, "-m", "fatswarm.deploy.cli", "run", "-n", str(N), "--seed", str(SEED)),
        *("--pace", "0.3", "--record", str(record), *flags),
    ]


@pytest.mark.parametrize(
    ("sig", "code", "word"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")],
)
def test_a_signalled_networked_run_says_after_which_round_and_how_to_go_on(
    tmp_path: Path, sig: int, code: int, word: str
) -> None:
    record = tmp_path / "run.jsonl"
    proc = subprocess.Popen(
        _run(record, "--no-dashboard"),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        _wait_for_rounds(record, 2, proc)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=DEADLINE_S)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == code, err
    said = _said(word, record)
    assert err.splitlines()[-1] == said, err
    go_on = f"go on with `fatswarm run --record {record} --resume`"
    assert said == f"{word} after round {_rounds(record)}; {go_on}"
    assert out == ""  # standard output carries only a summary, and there is none
    if sig == signal.SIGINT:
        return  # either signal closes the record alike: the SIGTERM case goes on with --resume
    # and going on as it says ends the run as the lock step does
    done = subprocess.run(
        [sys.executable, "-m", "fatswarm.deploy.cli", "run", "--record", str(record), "--resume"],
        capture_output=True,
        text=True,
        timeout=DEADLINE_S,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert_same_run(read_record(record), lockstep_record(tmp_path / "lock.jsonl", N, SEED))


def test_ctrl_c_under_the_live_dashboard_says_it_below_the_final_frame(tmp_path: Path) -> None:
    record = tmp_path / "run.jsonl"
    child = PtyProcess(_run(record))
    try:
        deadline = time.monotonic() + DEADLINE_S
        assert child.wait_for(lambda text: "fatswarm · live" in text, deadline), child.text[-3000:]
        while _rounds(record) < 2:
            assert child.proc.poll() is None and time.monotonic() < deadline, child.text[-3000:]
            child.pump(0.05)  # (the terminal must be read, or the view blocks writing to it)
        child.proc.send_signal(signal.SIGINT)
        assert child.finish(deadline) == 130, child.text[-3000:]
        raw = bytes(child.output)
        left = raw.rfind(b"\x1b[?1049l")  # the live view left the alternate screen...
        assert left > raw.find(b"\x1b[?1049h") >= 0
        after = screen_text(raw[left:])
        frame = after.index("fatswarm · live")  # ...printed its final frame on the main one...
        said = _said("interrupted", record)
        assert after.index(said) > frame, after  # ...and the line comes below it, last
        assert after.rstrip().endswith(said), after[-500:]
    finally:
        child.kill()
