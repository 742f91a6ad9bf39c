"""Fixtures shared by the unit tests, and their rule: a unit test opens no Zenoh session and starts
no process (STYLE.md, "Tests"; such a test lives in tests/integration/). The guard below makes
every way in raise UnitTestIsolationError while a unit test runs, its fixtures included."""

from __future__ import annotations

import multiprocessing.process
import os
import subprocess
from collections.abc import Generator, Iterator
from contextlib import contextmanager
from typing import Any

import pytest
import zenoh

from fatswarm.deploy.net import launcher

RULE = "a unit test opens no Zenoh session and starts no process: move it to tests/integration/"


class UnitTestIsolationError(AssertionError):
    """A unit test tried to open a Zenoh session or start a process."""


def _refuse(what: str) -> Any:
    def refused(*args: object, **kwargs: object) -> Any:
        raise UnitTestIsolationError(f"{what} in a unit test: {RULE}")

    return refused


# Where a session or a process begins: every Popen (subprocess.run, asyncio's subprocesses,
# os.popen) goes through _execute_child, every multiprocessing Process (pools included) through
# start, and os.spawn*, pty.fork and multiprocessing's fork through os.fork or os.forkpty.
_WAYS_IN: tuple[tuple[object, str, str], ...] = (
    (zenoh, "open", "zenoh.open"),
    (zenoh, "scout", "zenoh.scout"),
    (subprocess.Popen, "_execute_child", "a subprocess"),
    (multiprocessing.process.BaseProcess, "start", "a multiprocessing Process"),
    (os, "fork", "os.fork"),
    (os, "forkpty", "os.forkpty"),
    (os, "posix_spawn", "os.posix_spawn"),
    (os, "posix_spawnp", "os.posix_spawnp"),
    (os, "system", "os.system"),
)


@contextmanager
def no_sessions_or_processes() -> Iterator[None]:
    """While inside, each way in to a Zenoh session or a process raises UnitTestIsolationError."""
    with pytest.MonkeyPatch.context() as patch:
        for owner, name, what in _WAYS_IN:
            patch.setattr(owner, name, _refuse(what))
        yield


# A conftest's runtest hooks run for the tests of its own folder only: the guard covers each unit
# test's setup (its fixtures of any scope that it is the first to ask for), call and teardown.
@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item: pytest.Item) -> Generator[None, None, None]:
    with no_sessions_or_processes():
        return (yield)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Generator[None, None, None]:
    with no_sessions_or_processes():
        return (yield)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item: pytest.Item) -> Generator[None, None, None]:
    with no_sessions_or_processes():
        return (yield)


@pytest.fixture
def no_launch(monkeypatch: pytest.MonkeyPatch) -> None:
    """A networked run in these tests must be refused (or stubbed) before it starts anything."""

    def launch(*args: Any) -> int:
        raise AssertionError("the networked run started processes for refused input")

    monkeypatch.setattr(launcher, "_launch", launch)
