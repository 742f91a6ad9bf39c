"""docs/record.schema.json against a real networked run (router, world, coordinator and agents, a
process each): its every line validates, and with the records of every other kind it shows every
key the schema names (tests/unit/test_record_schema.py checks the rest)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator
from record_kinds import SCHEMA, lines_of, problems

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def networked_record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real networked run (router, world, coordinator, 4 agent processes): about 2 s."""
    record = tmp_path_factory.mktemp("networked") / "run.jsonl"
    argv = [
        sys.executable,
        "-m",
        "fatswarm.deploy.cli",
        "run",
        "-n",
        "4",
        "--seed",
        "3",
        "--scheduler",
        "fsync",
        "--record",
        str(record),
        "-q",
        "--no-dashboard",
        "--pace",
        "0",
    ]
    proc = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    try:
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 0, out.decode(errors="replace")
    return record


def test_every_line_of_a_networked_record_validates(
    validator: Draft202012Validator, networked_record: Path
) -> None:
    header = lines_of(networked_record)[0]
    assert header["swarm"] != "lockstep" and "move_timeout" in header
    assert problems(validator, networked_record) == []


def test_the_records_use_every_key_the_schema_names(
    records: dict[str, Path], networked_record: Path
) -> None:
    """The kinds above cover the format: a key the schema names that no record shows would be
    documented but untested (and a key no schema names fails validation above)."""
    schema = json.loads(SCHEMA.read_text())
    seen: dict[str, set[str]] = {"header": set(), "round": set(), "result": set()}
    for record in [*records.values(), networked_record]:
        for line in lines_of(record):
            seen[line["type"]] |= set(line)
    for kind, keys in seen.items():
        assert set(schema["$defs"][kind]["properties"]) <= keys, kind
