"""The repository reads as ruff formats and checks it ([tool.ruff] in pyproject.toml). Ruff is a
program of its own (its Python package only finds the binary; there is no API to call in this
process): these two tests run it, without writing its cache, so they are integration tests."""

from __future__ import annotations

import importlib
import shutil
import subprocess
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def ruff() -> str:
    """The ruff executable: the ruff package's (the `test` extra has it), else one on PATH."""
    try:
        return str(importlib.import_module("ruff").find_ruff_bin())
    except ImportError:
        found = shutil.which("ruff")
        if found is None:
            pytest.skip("ruff is not installed: pip install -e '.[test]' brings it")
        return found


@pytest.mark.parametrize(
    "command", [["format", "--check"], ["check"]], ids=["ruff format", "ruff check"]
)
def test_ruff_finds_nothing_to_change(ruff: str, command: list[str]) -> None:
    # build/ is the copy `pip install .` leaves: git ignores it, but ruff reads .gitignore only in
    # a git checkout, and a checkout may come without .git
    done = subprocess.run(
        [ruff, *command, "--no-cache", "--extend-exclude", "build", "."],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
