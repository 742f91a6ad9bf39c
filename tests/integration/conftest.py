"""Fixtures of the networked integration tests (the harness lives in netharness.py)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from netharness import Swarm


@pytest.fixture
def make_swarm(tmp_path: Path) -> Iterator[Callable[..., Swarm]]:
    made: list[Swarm] = []

    def make(n: int, seed: int, scheduler: str = "ssync", endpoint: str | None = None) -> Swarm:
        tmp = tmp_path / f"swarm-{len(made)}" if made else tmp_path  # each its own state and logs
        tmp.mkdir(exist_ok=True)
        swarm = Swarm(tmp, n, seed, scheduler, endpoint)
        made.append(swarm)
        return swarm

    try:
        yield make
    finally:
        for swarm in made:
            swarm.close()
