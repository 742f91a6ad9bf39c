"""The wheel holds every module of the tree, each once, under the fatswarm name alone: built by pip
from a copy of the checkout (pyproject.toml finds the packages; nothing lists them by hand)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from module_names import FOLDERS, ROOT  # tests/support

pytestmark = pytest.mark.integration


def modules_of_the_tree(root: Path) -> set[str]:
    """fatswarm/... for every module under root/fatswarm, through its links to the folders."""
    found = set()
    for folder, dirs, files in os.walk(root / "fatswarm", followlinks=True):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        found |= {
            (Path(folder) / f).relative_to(root).as_posix() for f in files if f.endswith(".py")
        }
    return found


def test_the_wheel_holds_every_module_of_the_tree_once(tmp_path: Path) -> None:
    source = tmp_path / "source"  # pip builds in the source folder: a copy, not the checkout
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, source / name)
    for folder in FOLDERS:
        shutil.copytree(
            ROOT / folder,
            source / folder,
            symlinks=True,
            ignore=shutil.ignore_patterns("__pycache__"),
        )
    # pip and the build it starts, unmeasured by coverage (they run no fatswarm code: tracing
    # them only slows a measured run down)
    env = {k: v for k, v in os.environ.items() if not k.startswith("COVERAGE_PROCESS_")}
    done = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp_path), str(source)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        env=env,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    (wheel,) = tmp_path.glob("fatswarm-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert len(names) == len(set(names))
    assert {n.split("/")[0] for n in names} == {
        "fatswarm",
        wheel.name.split("-py3")[0] + ".dist-info",
    }
    expected = modules_of_the_tree(ROOT)
    assert len(expected) > 100
    assert {n for n in names if n.endswith(".py")} == expected
