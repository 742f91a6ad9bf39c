"""Opening a world's durable log: resume the run record it holds (a torn last line cut first) or
start a new one. The file work the world core leaves to its shells."""

from __future__ import annotations

import logging
import os
from collections.abc import Callable

from fatswarm.world.async_core import make_world
from fatswarm.world.core import WorldCore, WorldSetup, setup_from_header
from fatswarm.world.record import RecordWriter, read_record

log = logging.getLogger("fatswarm.world")


def cut_torn_line(path: str) -> None:
    """Drop a torn last line (the world died mid-write): it was never committed nor announced."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.rfind(b"\n") + 1
    if end < len(data):
        log.warning("state file %s: dropping a torn last line of %d bytes", path, len(data) - end)
        with open(path, "r+b") as f:
            f.truncate(end)
            f.flush()
            os.fsync(f.fileno())


def open_world(
    state_path: str,
    make_setup: Callable[[], WorldSetup],
    swarm: str,
    max_rounds: int | None,
    fsync: bool = True,
    epoch: int = 0,
) -> WorldCore:
    """Resume from `state_path` if it holds a record, else start a new one from `make_setup()`.

    Raises RecordFormatError (a file that is not a run record) or what `make_setup` raises.
    """

    if os.path.exists(state_path) and os.path.getsize(state_path) > 0:
        cut_torn_line(state_path)
        record = read_record(state_path)
        setup = setup_from_header(record.header, swarm, max_rounds)
        return make_world(
            setup, RecordWriter(state_path, fsync=fsync, append=True), record, epoch=epoch
        )
    return make_world(make_setup(), RecordWriter(state_path, fsync=fsync), epoch=epoch)
