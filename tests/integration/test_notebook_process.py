"""`python -m fatswarm` is the fatswarm command (a process of its own; the rest of the notebook
API is tested in tests/unit/test_notebook.py)."""

from __future__ import annotations

import subprocess
import sys

import pytest

pytestmark = pytest.mark.integration


def test_python_dash_m_fatswarm_is_the_fatswarm_command() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "fatswarm", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage: fatswarm ") and " run " in done.stdout
