"""fatswarm's pytest plugin in a pytest session of its own (pytester): its `fatswarm_swarm` fixture
runs a networked swarm of 3 robots (and one from a start of its own), gives its record, says
why a run refuses its input, and leaves no process behind."""

from __future__ import annotations

import contextlib
import os
import secrets
import subprocess
import sys
from importlib.metadata import entry_points
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]
pytestmark = pytest.mark.integration

OUTER_ENV = "FATSWARM_PLUGIN_TEST"  # set here: every process of the inner session inherits it

INNER_TEST = """
import pytest

from fatswarm.pytest_plugin import SwarmRunError, marked


def test_a_swarm_of_three_gathers(fatswarm_swarm):
    record = fatswarm_swarm("gathering", n=3, seed=1, scheduler="fsync")
    assert record.header.n == 3 and record.header.algorithm == "gathering"
    assert record.header.scheduler == "fsync" and record.header.seed == 1
    assert record.result is not None and record.result.status == "formed"
    assert len(record.rounds) == record.result.rounds > 0
    assert all(not entry.collisions for entry in record.rounds)
    assert marked(fatswarm_swarm.marks[-1]) == []  # its processes are gone when it returns
    print("networked record:", len(record.rounds), "rounds")


def test_a_start_of_its_own_and_a_refused_parameter(fatswarm_swarm):
    record = fatswarm_swarm(
        "gathering", init=[[0.0, 0.0], [6.0, 0.5]], scheduler="ssync", params={"tolerance": 0.01}
    )
    assert record.header.n == 2 and record.header.params == {"tolerance": 0.01}
    assert record.header.initial.tolist() == [[0.0, 0.0], [6.0, 0.5]]
    with pytest.raises(SwarmRunError, match="exited with 2: .*tolerance must be finite and > 0"):
        fatswarm_swarm("gathering", params={"tolerance": -1.0})
"""


def carrying(value: str) -> list[int]:
    """Processes whose environment holds OUTER_ENV=`value` (read from /proc)."""
    wanted = f"{OUTER_ENV}={value}".encode()
    found = []
    for environ in Path("/proc").glob("[0-9]*/environ"):
        with contextlib.suppress(OSError):
            if wanted in environ.read_bytes().split(b"\0"):
                found.append(int(environ.parent.name))
    return found


def installed() -> bool:
    """Whether this environment's fatswarm declares the plugin (an install since it has one)."""
    return any(ep.value == "fatswarm.pytest_plugin" for ep in entry_points(group="pytest11"))


def test_the_fixture_runs_a_networked_swarm_and_leaves_no_process(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    token = secrets.token_hex(8)
    monkeypatch.setenv(OUTER_ENV, token)
    probe = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:  # the scan sees a process that carries the token
        assert probe.pid in carrying(token)
    finally:
        probe.kill()
        probe.wait()
    pytester.makepyfile(test_swarm=INNER_TEST)
    # installed with its entry point, pytest loads the plugin by itself; a checkout installed
    # before the plugin existed names it
    plugin = [] if installed() else ["-p", "fatswarm.pytest_plugin"]
    result = pytester.runpytest_subprocess(*plugin, "-p", "no:cacheprovider", "-s", timeout=240)
    result.assert_outcomes(passed=2)
    result.stdout.fnmatch_lines(["*networked record: * rounds*"])
    assert carrying(token) == [], "processes of the run are left"
    assert os.environ[OUTER_ENV] == token
