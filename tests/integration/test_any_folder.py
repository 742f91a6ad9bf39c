"""A networked run works from any folder: the processes it starts import fatswarm as installed,
even where the current directory holds a folder named fatswarm (issue 28: the parent of a clone;
`python -m` alone puts the current directory first on sys.path)."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration


def fatswarm_command() -> list[str]:
    """The `fatswarm` script beside this interpreter, as a user types it; else its equivalent
    (`python -P`: neither puts the current directory on sys.path)."""
    script = shutil.which("fatswarm", path=str(Path(sys.executable).parent))
    return [script] if script else [sys.executable, "-P", "-m", "fatswarm"]


# what a process importing the folder's fatswarm, not the installed one, trips on
TRIP = "raise ImportError('the fatswarm folder of the current directory was imported')\n"


@pytest.mark.parametrize(
    "inside",
    [
        # a clone: no __init__.py, so a namespace package that only an editable install lets
        # win over the installed one; its world/ would then be imported as fatswarm.world
        pytest.param({"pyproject.toml": "", "world/__init__.py": TRIP}, id="the parent of a clone"),
        pytest.param({"__init__.py": TRIP}, id="a package named fatswarm"),
    ],
)
def test_a_networked_run_forms_from_a_folder_holding_a_fatswarm_folder(
    tmp_path: Path, inside: dict[str, str]
) -> None:
    work = tmp_path / "work"
    for name, text in inside.items():
        (work / "fatswarm" / name).parent.mkdir(parents=True, exist_ok=True)
        (work / "fatswarm" / name).write_text(text)
    record = tmp_path / "net.jsonl"
    argv = [*fatswarm_command(), "run", "-n", "3", "--seed", "1", "--pace", "0", "-q"]
    argv += ["--no-dashboard", "--record", str(record)]
    proc = subprocess.Popen(
        argv, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    try:
        out = proc.communicate(timeout=180)[0].decode(errors="replace")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 0, out
    result = read_record(record).result
    assert result is not None and result.status == "formed", out
