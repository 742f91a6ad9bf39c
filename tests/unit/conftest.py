"""Fixtures shared by the unit tests of the `fatswarm run` command line."""

from __future__ import annotations

from typing import Any

import pytest

from fatswarm.deploy.net import launcher


@pytest.fixture
def no_launch(monkeypatch: pytest.MonkeyPatch) -> None:
    """A networked run in these tests must be refused (or stubbed) before it starts anything."""

    def launch(*args: Any) -> int:
        raise AssertionError("the networked run started processes for refused input")

    monkeypatch.setattr(launcher, "_launch", launch)
