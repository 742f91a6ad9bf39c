"""The installed package as a fresh interpreter sees it (a `python -c` process each): only the
fatswarm name, its algorithms as entry points, the API loaded lazily."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration
GENERIC = ("agent", "world", "coordinator", "deploy")


def test_only_the_fatswarm_name_is_installed(tmp_path: Path) -> None:
    # Run away from the checkout (whose folders would be importable from its own directory).
    probe = (
        "import importlib.util, fatswarm, fatswarm.deploy.cli, fatswarm.agent.algorithm;"
        f"print([n for n in {GENERIC!r} if importlib.util.find_spec(n) is not None])"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_the_installed_package_registers_its_algorithms_as_entry_points(tmp_path: Path) -> None:
    probe = (
        "from importlib.metadata import entry_points;"
        "print(sorted((e.name, e.value) for e in entry_points(group='fatswarm.algorithms')))"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(
        [
            ("gathering", "fatswarm.agent.gathering:ALGORITHM"),
            (
                "oblot-gathering-multiplicity",
                "fatswarm.agent.oblot_gathering_multiplicity:ALGORITHM",
            ),
            ("oblot-go-to-cog", "fatswarm.agent.oblot_go_to_cog:ALGORITHM"),
            ("oblot-go-to-rightmost", "fatswarm.agent.oblot_go_to_rightmost:ALGORITHM"),
            ("oblot-move-along-sec", "fatswarm.agent.oblot_move_along_sec:ALGORITHM"),
            ("uniform-circle", "fatswarm.agent.uniform_circle:ALGORITHM"),
            ("uniform-circle-lights", "fatswarm.agent.luminous:ALGORITHM"),
            ("uniform-circle-stepped", "fatswarm.agent.stepped:ALGORITHM"),
        ]
    )


def test_the_api_is_reached_from_the_package_without_loading_it_on_import() -> None:
    probe = (
        "import sys, fatswarm; assert 'fatswarm.deploy.engine.api' not in sys.modules;"
        "assert callable(fatswarm.run) and callable(fatswarm.read_record)"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=False
    )
    assert done.returncode == 0, done.stderr
