"""Records are the same on every CPU: numpy's optional kernels (AVX-512, AVX2) give other last
bits of arctan2 and arccos than its baseline ones, OpenBLAS's kernels with fused multiply-add
(Haswell, SkylakeX, Zen) give other last bits of dot products than those without (Nehalem,
Sandybridge), and no record may hang on them (issue 30, item 3). bench/cpu_paths.py runs the same
lock-step runs as the CPU allows and then with each variant forced, each in a fresh process, and
compares the records' hashes (and, with --plans, the paper's plan on plan_digest's --quick
collection)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

SCRIPT = Path(__file__).resolve().parents[2] / "bench" / "cpu_paths.py"


def compare(*args: str) -> subprocess.CompletedProcess[str]:
    # Unmeasured by coverage (a measured run would trace every child's lock-step runs, about
    # twice their time): they run the lock step the other tests measure, only on other kernels.
    env = {k: v for k, v in os.environ.items() if not k.startswith("COVERAGE_PROCESS_")}
    return subprocess.run(
        [sys.executable, str(SCRIPT), *args],
        capture_output=True,
        text=True,
        timeout=3600,
        check=False,
        env=env,
    )


def check(done: subprocess.CompletedProcess[str]) -> None:
    if done.returncode == 2:
        pytest.skip(done.stdout.strip())  # this CPU has no kernel whose bits a variant changes
    assert done.returncode == 0, done.stdout + done.stderr
    assert "differ" not in done.stdout, done.stdout


def test_records_do_not_depend_on_numpys_optional_cpu_paths() -> None:
    check(compare("--count", "20", "--variants", "numpy-off"))


def test_records_do_not_depend_on_openblas_kernels() -> None:
    # The model cases with OpenBLAS's no-FMA kernel against this CPU's own: while the plan's dot
    # products went through BLAS, uc-dense's and stepped-async's records differed here.
    check(compare("--count", "0", "--variants", "Nehalem"))


@pytest.mark.slow
def test_records_and_plans_do_not_depend_on_any_cpu_variant_wide() -> None:
    check(compare("--count", "1200", "--plans"))
