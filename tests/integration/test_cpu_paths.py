"""Records are the same on every CPU: numpy's optional kernels (AVX-512, AVX2) give other last
bits of arctan2 and arccos than its baseline ones, and no record may hang on them (issue 30,
item 3). bench/cpu_paths.py runs the same lock-step runs with numpy's optional paths on and off,
each in a fresh process, and compares the records' hashes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

SCRIPT = Path(__file__).resolve().parents[2] / "bench" / "cpu_paths.py"


def compare(count: int) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(SCRIPT), "--count", str(count)],
        capture_output=True,
        text=True,
        timeout=3600,
        check=False,
    )


def check(done: subprocess.CompletedProcess[str]) -> None:
    if done.returncode == 2:
        pytest.skip(done.stdout.strip())  # this CPU runs numpy's baseline paths only
    assert done.returncode == 0, done.stdout + done.stderr
    assert "records identical" in done.stdout


def test_records_do_not_depend_on_numpys_optional_cpu_paths() -> None:
    check(compare(20))


@pytest.mark.slow
def test_records_do_not_depend_on_numpys_optional_cpu_paths_wide() -> None:
    check(compare(1200))
