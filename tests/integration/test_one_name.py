"""One name per module in every process: the CLI (lock step, and networked with all its parts)
and the API, started from the checkout's root as a developer starts them, load each of fatswarm's
files under its fatswarm.* name alone. Each process writes what it loaded when it exits (a
sitecustomize on PYTHONPATH); tests/unit/test_layout.py checks the test process itself."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from module_names import ROOT, second_names  # tests/support

pytestmark = pytest.mark.integration

# loaded first by every Python process that has its folder on PYTHONPATH (the site module)
DUMP = """\
import atexit, json, os, sys

def _dump():
    from module_names import loaded_files  # tests/support, on PYTHONPATH too

    files = loaded_files(sys.modules)
    home = files.get("fatswarm")
    with open(os.path.join(os.environ["FATSWARM_NAMES_OUT"], f"{os.getpid()}.json"), "w") as fh:
        json.dump({"argv": sys.argv, "files": files, "home": home and os.path.dirname(home)}, fh)

atexit.register(_dump)
"""


def loaded_names(tmp_path: Path, argv: list[str]) -> list[dict[str, object]]:
    """Run `argv` from the checkout's root; what each of its Python processes loaded."""
    probe, out = tmp_path / "probe", tmp_path / "names"
    probe.mkdir()
    out.mkdir()
    (probe / "sitecustomize.py").write_text(DUMP)
    support = str(ROOT / "tests" / "support")
    path = os.pathsep.join(filter(None, [str(probe), support, os.environ.get("PYTHONPATH")]))
    env = {**os.environ, "PYTHONPATH": path, "FATSWARM_NAMES_OUT": str(out)}
    done = subprocess.run(
        argv, cwd=ROOT, env=env, capture_output=True, text=True, timeout=180, check=False
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]


def problems(dumps: list[dict[str, object]]) -> list[str]:
    found = []
    for dump in dumps:
        files, home = dump["files"], dump["home"]
        assert isinstance(files, dict) and isinstance(home, str), dump
        found += [f"{dump['argv']}: {p}" for p in second_names(files, [Path(home)])]
    return found


def test_the_cli_in_lock_step_loads_every_module_under_one_name(tmp_path: Path) -> None:
    record = tmp_path / "lock.jsonl"
    argv = [sys.executable, "-m", "fatswarm", "run", "--lockstep", "-n", "4", "--seed", "1"]
    dumps = loaded_names(tmp_path, [*argv, "-q", "--record", str(record)])
    assert len(dumps) == 1
    assert "fatswarm.world.core" in str(dumps[0]["files"])
    assert not problems(dumps)


def test_a_networked_run_loads_every_module_under_one_name_in_every_part(tmp_path: Path) -> None:
    record = tmp_path / "net.jsonl"
    argv = [sys.executable, "-m", "fatswarm", "run", "-n", "3", "--seed", "1", "--pace", "0"]
    dumps = loaded_names(tmp_path, [*argv, "-q", "--no-dashboard", "--record", str(record)])
    # the launcher, the world (hosting the router), the coordinator and the agents' host
    parts = sorted(str(d["argv"]) for d in dumps)
    assert len(dumps) >= 4, parts
    assert not problems(dumps)


def test_the_api_loads_every_module_under_one_name(tmp_path: Path) -> None:
    record = tmp_path / "api.jsonl"
    code = f"import fatswarm; print(fatswarm.run(4, seed=1, record={str(record)!r}).status)"
    dumps = loaded_names(tmp_path, [sys.executable, "-c", code])
    assert len(dumps) == 1
    assert "fatswarm.deploy.engine.api" in str(dumps[0]["files"])
    assert not problems(dumps)
