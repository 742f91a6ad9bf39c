"""Fixtures shared by the unit and the integration tests."""

from __future__ import annotations

import os
import socket
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import settings
from jsonschema import Draft202012Validator
from record_kinds import make_records, schema_validator  # tests/support, on pytest's pythonpath

# Property tests draw the same examples on every run, so a default run (and CI) fails only where
# the code changed; FATSWARM_HYPOTHESIS=explore draws new ones each run, to hunt for what the fixed
# examples miss (then pin what it finds as a named test).
settings.register_profile("fixed", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("FATSWARM_HYPOTHESIS", "fixed"))


@pytest.fixture
def busy_port() -> Iterator[int]:
    """A loopback TCP port something listens on."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        yield s.getsockname()[1]


@pytest.fixture(scope="session")
def validator() -> Draft202012Validator:
    """docs/record.schema.json as a validator."""
    return schema_validator()


@pytest.fixture(scope="session")
def records(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One lock-step (or world core) record of each kind of record_kinds.KINDS: name -> path.
    Made once per session: the unit and the integration tests of the schema share them."""
    return make_records(tmp_path_factory)
