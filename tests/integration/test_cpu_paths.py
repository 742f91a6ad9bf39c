"""Records are the same on every CPU: numpy's optional kernels (AVX-512, AVX2) give other last
bits of arctan2 and arccos than its baseline ones, OpenBLAS's kernels with fused multiply-add
(Haswell, SkylakeX, Zen) give other last bits of dot products than those without (Nehalem,
Sandybridge), and no record may hang on them (issue 30, item 3). bench/cpu_paths.py runs the same
lock-step runs as the CPU allows and then with each variant forced, each in a fresh process, and
compares the records' hashes (and, with --plans, the paper's plan on plan_digest's --quick
collection)."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

SCRIPT = Path(__file__).resolve().parents[2] / "bench" / "cpu_paths.py"
# The default run's comparisons: numpy's optional paths off on the model cases and 20 adversarial
# cases; the model cases with OpenBLAS's no-FMA kernel against this CPU's own (while the plan's
# dot products went through BLAS, uc-dense's and stepped-async's records differed here).
DEFAULT_RUN = {
    "numpy-off": ("--count", "20", "--variants", "numpy-off"),
    "Nehalem": ("--count", "0", "--variants", "Nehalem"),
}


def start(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, str(SCRIPT), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def compare(*args: str) -> subprocess.CompletedProcess[str]:
    return finish(start(*args))


def finish(proc: subprocess.Popen[str]) -> subprocess.CompletedProcess[str]:
    try:
        out, err = proc.communicate(timeout=3600)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


@pytest.fixture(scope="module")
def started() -> Iterator[dict[str, subprocess.Popen[str]]]:
    """The default run's comparisons, started at once (each runs its children one after the
    other; the two side by side): each test collects its own."""
    procs = {variant: start(*args) for variant, args in DEFAULT_RUN.items()}
    try:
        yield procs
    finally:
        for proc in procs.values():
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def check(done: subprocess.CompletedProcess[str]) -> None:
    if done.returncode == 2:
        pytest.skip(done.stdout.strip())  # this CPU has no kernel whose bits a variant changes
    assert done.returncode == 0, done.stdout + done.stderr
    assert "differ" not in done.stdout, done.stdout


def test_records_do_not_depend_on_numpys_optional_cpu_paths(
    started: dict[str, subprocess.Popen[str]],
) -> None:
    check(finish(started["numpy-off"]))


def test_records_do_not_depend_on_openblas_kernels(
    started: dict[str, subprocess.Popen[str]],
) -> None:
    check(finish(started["Nehalem"]))


@pytest.mark.slow
def test_records_and_plans_do_not_depend_on_any_cpu_variant_wide() -> None:
    check(compare("--count", "1200", "--plans"))
