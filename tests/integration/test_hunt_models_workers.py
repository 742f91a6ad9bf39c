"""`fatswarm hunt` over robot-model axes on a worker process: a saved failure says its model (the
command, summary.json, the record's header) and its command, run as it is by `fatswarm run`,
replays it exactly."""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from fatswarm.deploy import cli

pytestmark = pytest.mark.integration
ROOT = Path(__file__).resolve().parents[2]
PLANTED = f"{ROOT / 'tests' / 'data' / 'always_right.py'}:ALGORITHM"
IGNORED = ("command", "init", "schedule")  # the header's paths: the hunt's, then the replay's


def lines(path: Path) -> list[dict[str, object]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_a_failure_under_a_robot_model_replays_through_its_saved_command(tmp_path: Path) -> None:
    out = tmp_path / "found"
    argv = ["hunt", "--algorithm", PLANTED, "--scheduler", "fsync", "-n", "4"]
    argv += ["--frames", "chirality", "--sight", "8", "--record-views"]
    argv += ["--budget-runs", "4", "--max-failures", "1", "--jobs", "1", "--seed", "1"]
    assert cli.main([*argv, "--out", str(out), "-q"]) == 1
    (folder,) = out.iterdir()
    summary = json.loads((folder / "summary.json").read_text())
    model = {
        "visibility": "transparent",
        "sight": 8.0,
        "lights": "full",
        "frames": "chirality",
        "frame_change": "fixed",
    }
    assert summary["found"]["model"] == model
    command = (folder / "command").read_text().splitlines()[-1]
    assert command == summary["command"]
    words = shlex.split(command)
    assert words[words.index("--sight") : words.index("--sight") + 5] == [
        "--sight",
        "8.0",
        "--frames",
        "chirality",
        "--record-views",
    ]
    done = subprocess.run(
        [sys.executable, "-m", "fatswarm.deploy.cli", *words[1:]],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode in (1, 3), done.stderr
    saved, replayed = lines(folder / "record.jsonl"), lines(folder / "replay.jsonl")
    assert saved[0]["model"] == replayed[0]["model"] == model
    for header in (saved[0], replayed[0]):
        for key in IGNORED:
            header.pop(key, None)
    assert saved == replayed  # every round, its moves and what each looker saw
    assert any("views" in json.dumps(line) for line in saved[1:])
