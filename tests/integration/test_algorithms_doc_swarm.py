"""docs/algorithms.md's `huddle.py` and `test_huddle.py`, taken from the page, run by pytest in a
session of their own, as a user runs them: the contract in one call and a networked swarm through
the `fatswarm_swarm` fixture (the plugin found by its entry point)."""

from __future__ import annotations

from importlib.metadata import entry_points

import pytest
from algorithms_doc import page_blocks  # tests/support

pytest_plugins = ["pytester"]
pytestmark = pytest.mark.integration


def test_the_pages_tests_pass_as_written(pytester: pytest.Pytester) -> None:
    algorithm, tests = page_blocks()
    pytester.makepyfile(huddle=algorithm, test_huddle=tests)
    installed = any(ep.value == "fatswarm.pytest_plugin" for ep in entry_points(group="pytest11"))
    plugin = [] if installed else ["-p", "fatswarm.pytest_plugin"]
    result = pytester.runpytest_subprocess(*plugin, "-p", "no:cacheprovider", timeout=240)
    result.assert_outcomes(passed=2)
