"""The live dashboard on a pseudo-terminal: attached to a published world state, and in `run`.

The screen is read from the pty (escape codes stripped) and checked for the counters and the
outcome. Every started process is killed in `finally`; loopback only, free ports, no scouting.
"""

from __future__ import annotations

import contextlib
import fcntl
import math
import os
import pty
import re
import select
import signal
import struct
import subprocess
import sys
import termios
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fatswarm.domain.outcome import Status
from fatswarm.world.observers import AgentInfo, WorldState
from fatswarm.world.protocol import state_key

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[2]
ROWS, COLS = 40, 120
ANSI = re.compile(
    r"\x1b\[[0-?]*[ -/]*[@-~]|\x1b\][^\x07\x1b]*(\x07|\x1b\\)|\x1b[()][0-9A-Za-z]|\x1b[=>78]"
)
COMMAND_MAIN = (
    "import argparse, sys\n"
    "from fatswarm.deploy.view import {module} as m\n"
    "p = argparse.ArgumentParser()\n"
    "m.add_arguments(p)\n"
    "sys.exit(m.main(p.parse_args(sys.argv[1:])))\n"
)
DASHBOARD_MAIN = COMMAND_MAIN.replace("deploy.view", "deploy.net").format(module="watch")
REPLAY_MAIN = COMMAND_MAIN.format(module="replay")


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def screen_text(raw: bytes) -> str:
    """What was written to the terminal, without escape sequences."""
    return ANSI.sub("", raw.decode("utf-8", errors="replace"))


class PtyProcess:
    """A child process whose stdin, stdout and stderr are one pseudo-terminal of ROWS x COLS."""

    def __init__(
        self,
        argv: Sequence[str],
        env: dict[str, str] | None = None,
        size: tuple[int, int] = (ROWS, COLS),
        stdout: int | None = None,
    ) -> None:
        master, slave = pty.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", *size, 0, 0))
        full_env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES")}
        full_env.update(TERM="xterm-256color", PYTHONUNBUFFERED="1", **(env or {}))
        full_env.pop("NO_COLOR", None)
        self.proc = subprocess.Popen(
            list(argv),
            stdin=slave,
            stdout=slave if stdout is None else stdout,
            stderr=slave,
            cwd=ROOT,
            env=full_env,
            start_new_session=True,
        )
        os.close(slave)
        self.master = master
        self.output = bytearray()
        self.closed = False  # end of file on the terminal: the child and its children are gone

    def pump(self, timeout: float = 0.1) -> None:
        """Read whatever the child wrote within `timeout` (nothing once the terminal is closed)."""
        if self.closed:
            return
        ready, _, _ = select.select([self.master], [], [], timeout)
        if ready:
            try:
                chunk = os.read(self.master, 65536)
            except OSError:  # EIO: every process closed the terminal and all it wrote was read
                chunk = b""
            if not chunk:
                self.closed = True
            self.output.extend(chunk)

    def wait_for(self, predicate: Any, deadline: float) -> bool:
        """Pump until `predicate(screen_text)` holds, or the terminal is closed with all output read
        (then nothing more can come), or the deadline passes."""
        while time.monotonic() < deadline:
            self.pump()
            if predicate(self.text):
                return True
            if self.closed:
                return False
        return False

    def finish(self, deadline: float) -> int | None:
        """Pump until the child exited and all its output was read; its exit code, None if late.

        The end of output is the terminal's end of file (EIO once every writer closed it), never
        a quiet spell: on a loaded machine the last frame may take any time to come through.
        """
        while time.monotonic() < deadline and not self.closed:
            self.pump()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        return self.proc.poll()

    def kill(self) -> None:
        if self.proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.wait(timeout=10)
        os.close(self.master)

    @property
    def text(self) -> str:
        return screen_text(bytes(self.output))


@contextlib.contextmanager
def router_session() -> Iterator[tuple[Any, str]]:
    """A Zenoh router in this process on a free loopback port: (session, endpoint)."""
    import zenoh

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conf = zenoh.Config()
    conf.insert_json5("mode", '"router"')
    conf.insert_json5("listen/endpoints", f'["{endpoint}"]')
    conf.insert_json5("scouting/multicast/enabled", "false")
    session = zenoh.open(conf)
    try:
        yield session, endpoint
    finally:
        session.close()  # type: ignore[no-untyped-call]


def world_state(round_no: int, n: int, status: str, swarm: str) -> WorldState:
    """A plausible published state: a regular n-gon of side 4 (robot 0 north), all agents alive."""
    r = 4.0 / (2 * math.sin(math.pi / n))
    theta = 2 * math.pi * np.arange(n) / n
    shrink = 1.0 if status == "formed" else 0.5
    positions = np.column_stack((r * shrink * np.sin(theta), r * shrink * np.cos(theta)))
    agents = tuple(
        AgentInfo(alive=True, last_active=round_no, last_path_length=0.5, timeouts=0)
        for _ in range(n)
    )
    return WorldState(
        round=round_no, n=n,
        algorithm="uniform-circle", params={"a": 4.0}, figures={"target radius": r},
        scheduler="fsync", swarm=swarm, positions=positions,
        active=tuple(range(n)), open_round=0, moved=(), stopped=(), collisions_total=0,
        status=Status(status),
        agents=agents,
    )  # fmt: skip


def test_attached_dashboard_shows_the_published_state_and_the_outcome() -> None:
    swarm = "ptytest"
    with router_session() as (session, endpoint):
        pub = session.declare_publisher(state_key(swarm))
        child = PtyProcess(
            [sys.executable, "-c", DASHBOARD_MAIN, "--connect", endpoint, "--swarm", swarm,
             "--exit-at-end"]
        )  # fmt: skip
        try:
            deadline = time.monotonic() + 30
            round_no = 0

            # keep publishing running rounds until a whole frame is on screen (it may join late)
            def shown(text: str) -> bool:
                return all(
                    re.search(p, text)
                    for p in (
                        r"swarm ptytest",
                        r"round\s+\d+",
                        r"alive\s+6 / 6",
                        r"targets\s+\d+ / 6 filled",
                    )
                )

            while time.monotonic() < deadline and not shown(child.text):
                round_no += 1
                pub.put(world_state(round_no, 6, "running", swarm).encode())
                child.pump(0.05)
            assert shown(child.text), child.text[-3000:]
            while child.proc.poll() is None and time.monotonic() < deadline:
                pub.put(world_state(round_no + 1, 6, "formed", swarm).encode())
                child.pump(0.1)
            code = child.finish(deadline)
            text = child.text
            assert code == 0, text[-3000:]
            assert (
                f"FORMED: uniform-circle goal reached by 6 robots after {round_no + 1} rounds"
                in text
            )
            assert re.search(r"targets\s+6 / 6 filled", text)
        finally:
            child.kill()
            pub.undeclare()


@pytest.mark.parametrize(("rows", "cols"), [(24, 80), (12, 50)])
def test_attached_dashboard_at_80x24_shows_agent_rows_and_below_says_it_is_too_small(
    rows: int, cols: int
) -> None:
    swarm = "ptysmall"
    with router_session() as (session, endpoint):
        pub = session.declare_publisher(state_key(swarm))
        child = PtyProcess(
            [sys.executable, "-c", DASHBOARD_MAIN, "--connect", endpoint, "--swarm", swarm,
             "--exit-at-end"],
            size=(rows, cols),
        )  # fmt: skip
        try:
            deadline = time.monotonic() + 30
            if (cols, rows) == (80, 24):
                patterns = [r"round\s+\d+", r"│\s+0\s+yes\s", r"│\s+2\s+yes\s", r"alive\s+8 / 8"]
            else:
                patterns = [
                    r"too small \(50x12\): the dashboard needs 80x24",
                    r"round \d+, 8 robots",
                ]

            def shown(text: str) -> bool:
                return all(re.search(p, text) for p in patterns)

            round_no = 0
            while time.monotonic() < deadline and not shown(child.text):
                round_no += 1
                pub.put(world_state(round_no, 8, "running", swarm).encode())
                child.pump(0.05)
            assert shown(child.text), child.text[-3000:]
            while child.proc.poll() is None and time.monotonic() < deadline:
                pub.put(world_state(round_no + 1, 8, "formed", swarm).encode())
                child.pump(0.1)
            assert child.finish(deadline) == 0, child.text[-3000:]
            verdict = f"FORMED: uniform-circle goal reached by 8 robots after {round_no + 1} rounds"
            # wrapped, perhaps, but whole: no word of it cut
            said = re.sub(r"[│\s]+", " ", child.text)
            assert verdict in said, child.text[-3000:]
        finally:
            child.kill()
            pub.undeclare()


def test_replay_with_standard_output_not_a_terminal_prints_one_frame_at_once(
    tmp_path: Path,
) -> None:
    record = ROOT / "tests" / "data" / "lockstep-n6-seed1.jsonl"
    out = tmp_path / "out.txt"
    with out.open("wb") as sink:  # standard input a terminal, standard output a file
        child = PtyProcess([sys.executable, "-c", REPLAY_MAIN, str(record)], stdout=sink.fileno())
        try:
            assert child.finish(time.monotonic() + 60) == 0, child.text[-2000:]
        finally:
            child.kill()
    text = out.read_text()
    assert "FORMED: uniform-circle goal reached by 6 robots after 17 rounds" in text
    assert "\x1b[?1049h" not in text  # never went to the alternate screen to play


def test_attached_dashboard_without_a_router_says_so_and_exits_2() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"  # nothing listens there
    child = PtyProcess([sys.executable, "-c", DASHBOARD_MAIN, "--connect", endpoint])
    try:
        code = child.finish(time.monotonic() + 30)
        assert code == 2, child.text[-2000:]
        assert f"cannot follow {endpoint}" in child.text
        assert "Traceback" not in child.text
    finally:
        child.kill()


def test_replay_on_a_terminal_steps_with_keys_and_quits() -> None:
    record = ROOT / "tests" / "data" / "lockstep-n6-seed1.jsonl"
    child = PtyProcess([sys.executable, "-c", REPLAY_MAIN, str(record), "--round", "5"])
    try:
        deadline = time.monotonic() + 30
        # --round K starts paused at K
        assert child.wait_for(
            lambda t: re.search(r"round\s+5 / 17", t) and "[paused" in t, deadline
        ), child.text
        keys = "space play/pause  ←/→ step  +/- speed  g/G first/last  q quit"
        assert keys in child.text  # at 120 columns the key help is whole
        os.write(child.master, b"..")  # two steps forward
        assert child.wait_for(lambda t: re.search(r"round\s+7 / 17", t), deadline), child.text
        os.write(child.master, b"G")  # to the end: the outcome shows
        assert child.wait_for(
            lambda t: "FORMED: uniform-circle goal reached by 6" in t, deadline
        ), child.text
        os.write(child.master, b"q")
        assert child.finish(deadline) == 0, child.text[-2000:]
    finally:
        child.kill()


def test_fatswarm_run_shows_the_live_dashboard_and_leaves_the_final_frame_on_screen(
    tmp_path: Path,
) -> None:
    svg = tmp_path / "final.svg"
    # Paced rounds: unpaced, the whole run can end between two looks of the live view (5 per
    # second), which then never sees two states and cannot measure a rate.
    child = PtyProcess(
        [sys.executable, "-m", "fatswarm.deploy.cli", "run", "-n", "5", "--seed", "3",
         "--scheduler", "fsync", "--max-rounds", "400", "--pace", "0.3", "--svg", str(svg)]
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 300  # a deadline, not a duration: a loaded CI host

        def live_with_rate(text: str) -> bool:
            return "fatswarm · live" in text and bool(re.search(r"rounds/s\s+[\d,.]+", text))

        assert child.wait_for(live_with_rate, deadline), child.text[-3000:]
        code = child.finish(deadline)
        text = child.text
        assert code == 0, text[-3000:]
        assert "fatswarm · live" in text
        assert re.search(r"rounds/s\s+[\d,.]+", text)
        assert re.search(r"targets\s+5 / 5 filled", text)
        assert "FORMED: uniform-circle goal reached by 5 robots" in text
        assert svg.read_text().startswith("<svg")
        # the live view ran on the alternate screen, which the terminal drops on leaving it: the
        # final frame is printed after that, whole, with the summary still below it on screen
        raw = bytes(child.output)
        left = raw.rfind(b"\x1b[?1049l")
        assert left > raw.find(b"\x1b[?1049h") >= 0
        after = screen_text(raw[left:])
        final = after[after.index("fatswarm · live") :].rstrip("\n").splitlines()
        assert len(final) <= ROWS - 1, "\n".join(final)  # the prompt fits below it too
        assert any("FORMED: uniform-circle goal reached by 5 robots" in line for line in final)
        assert any(line.startswith("formed in ") for line in final)  # the summary
    finally:
        child.kill()


def test_fatswarm_run_prints_progress_lines_when_not_a_terminal() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "fatswarm.deploy.cli", "run", "-n", "4", "--seed", "2",
         "--scheduler", "fsync", "--max-rounds", "400"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=ROOT, text=True,
        start_new_session=True,
    )  # fmt: skip
    try:
        out, _ = proc.communicate(timeout=150)
        assert proc.returncode == 0, out[-3000:]
        assert re.search(r"^round \d+ \w+: targets \d+/4", out, re.MULTILINE), out[-3000:]
        assert not ANSI.search(out)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)
