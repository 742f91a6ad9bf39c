"""docs/algorithms.md as a user reads it: the whole algorithm it shows (`huddle.py`) is taken from
the page and run as written (the contract, a run that forms, its parameter refused in one line);
pytest comes with the `testing` extra, and the plugin without pytest says so in one line. The
page's `test_huddle.py` is run with the plugin in tests/integration/test_algorithms_doc_swarm.py.
"""

from __future__ import annotations

import importlib.util
import re
import sys
import tomllib
from pathlib import Path

import pytest
from algorithms_doc import DOC, page_blocks  # tests/support

import fatswarm
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import AlgorithmParamsError, Configured
from fatswarm.testing import check_algorithm

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def huddle(tmp_path_factory: pytest.TempPathFactory) -> str:
    folder = tmp_path_factory.mktemp("huddle")
    (folder / "huddle.py").write_text(page_blocks()[0], encoding="utf-8")
    return f"{folder / 'huddle.py'}:ALGORITHM"


def test_the_pages_algorithm_is_whole_and_keeps_the_contract(huddle: str) -> None:
    source = page_blocks()[0]
    assert "def make_params" in source and "def goal" in source and "ALGORITHM = " in source
    checked = check_algorithm(huddle, budget=0.5)
    assert checked.checks[0] == "seam" and "hunt" in checked.checks and checked.hunt_runs > 0


def test_the_pages_algorithm_forms_and_refuses_a_bad_tolerance_in_one_line(huddle: str) -> None:
    result = fatswarm.run(6, algorithm=huddle, scheduler="fsync", seed=2)
    assert str(result.status) == "formed" and result.collisions == 0
    with pytest.raises(AlgorithmParamsError, match=r"^tolerance must be finite and > 0, got -1"):
        Configured.of(load_algorithm(huddle), 4, {"tolerance": -1.0})


def test_the_pages_tests_use_the_fixture_and_the_kit_on_that_file() -> None:
    tests = page_blocks()[1]
    assert "def test_huddle_gathers_over_the_network(fatswarm_swarm" in tests
    assert 'check_algorithm("huddle.py:ALGORITHM"' in tests


def test_pytest_comes_with_the_testing_extra_the_page_names() -> None:
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    assert any(re.match(r"pytest\b", need) for need in extras["testing"])
    assert "pip install 'fatswarm[testing]'" in DOC.read_text(encoding="utf-8")


def test_the_plugin_without_pytest_says_what_to_install_in_one_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "pytest", None)  # import pytest raises ImportError
    path = ROOT / "fatswarm" / "pytest_plugin.py"
    spec = importlib.util.spec_from_file_location("_fatswarm_plugin_without_pytest", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)  # a copy: the session's plugin stays loaded
    with pytest.raises(ImportError) as info:
        spec.loader.exec_module(module)
    assert str(info.value) == (
        "fatswarm's pytest plugin (the fatswarm_swarm fixture) needs pytest: "
        "pip install 'fatswarm[testing]'"
    )
