"""The unit tests' rule holds by a guard (tests/unit/conftest.py): every way in to a Zenoh session
or a process raises, naming the rule, while a unit test runs."""

from __future__ import annotations

import asyncio
import multiprocessing
import os
import subprocess
import sys
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor

import pytest
import zenoh

REFUSED = r" in a unit test: a unit test opens no Zenoh session and starts no process: move it to "


def _reaped(pid: int) -> None:
    """The child of a fork (had the guard let it through) leaves at once; the parent reaps it."""
    if pid == 0:
        os._exit(0)
    os.waitpid(pid, 0)


def _nowhere() -> zenoh.Config:
    """A client that, were it let through, would fail on its own: no router listens on port 1."""
    return zenoh.Config.from_json5(
        '{mode: "client", connect: {endpoints: ["tcp/127.0.0.1:1"]}, '
        "scouting: {multicast: {enabled: false}}}"
    )


async def _shell() -> None:
    child = await asyncio.create_subprocess_exec(sys.executable, "-c", "pass")
    await child.wait()


def _pooled() -> None:
    with ProcessPoolExecutor(1) as pool:
        pool.submit(int).result(timeout=60)


PY = [sys.executable, "-c", "pass"]
WAYS_IN: dict[str, Callable[[], object]] = {
    "zenoh.open": lambda: zenoh.open(_nowhere()),
    "subprocess.run": lambda: subprocess.run(PY, check=True, timeout=60),
    "asyncio subprocess": lambda: asyncio.run(_shell()),
    "os.system": lambda: os.system("true"),
    "os.fork": lambda: _reaped(os.fork()),
    "os.forkpty": lambda: _reaped(os.forkpty()[0]),
    "os.posix_spawn": lambda: _reaped(os.posix_spawn(sys.executable, PY, os.environ)),
    "multiprocessing": lambda: multiprocessing.get_context("spawn").Process(target=int).start(),
    "process pool": lambda: _pooled(),
}


@pytest.mark.parametrize("way_in", WAYS_IN.values(), ids=WAYS_IN.keys())
def test_a_unit_test_that_opens_a_session_or_starts_a_process_fails_naming_the_rule(
    way_in: Callable[[], object],
) -> None:
    with pytest.raises(AssertionError, match=REFUSED + "tests/integration/$"):
        way_in()
