"""The world part, a process of its own, refuses a start outside the supported range
(fatswarm/domain/tolerance.py) with one line, like `fatswarm run` (tests/unit/test_cli_run.py)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration
ROOT = Path(__file__).resolve().parents[2]


def test_world_part_refuses_a_start_outside_the_supported_range(tmp_path: Path) -> None:
    # a process of its own: the part installs signal handlers and logging for its whole process
    proc = subprocess.run(
        [sys.executable, "-m", "fatswarm.deploy.net.parts", "world",
         "--state", str(tmp_path / "w.jsonl"), "--connect", "tcp/127.0.0.1:9",
         "-n", "2", "-a", "1e10"],
        capture_output=True, text=True, cwd=ROOT, timeout=60,
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("fatswarm world: a must be at most 20000 for n = 2")
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
