"""The world's durable log and the shells' side of its effects: open a run record (resume the run it
holds, a torn last line cut first, or start a new one), and perform what the core asks (append a
line, log a note). The file work and the logging the world core leaves to its shells.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterable
from typing import Protocol

from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Configured
from fatswarm.world.core import WorldCore
from fatswarm.world.effects import Committed, Effect, Note, Rejected
from fatswarm.world.record import Header, RecordWriter, Result, RoundEntry
from fatswarm.world.record_read import read_record
from fatswarm.world.setup import WorldSetup, setup_from_header

log = logging.getLogger("fatswarm.world")


class Journal(Protocol):
    """Where record lines go: `world.record.RecordWriter` (or a test's list)."""

    def append(self, line: Header | RoundEntry | Result) -> None: ...

    def close(self) -> None: ...


def perform(
    effects: Iterable[Effect],
    journal: Journal | None,
    refused: Callable[[Rejected], None] | None = None,
) -> list[Committed]:
    """Do what the core asked, in order: record lines to `journal` (none kept if None), notes to
    the log, refused inputs to `refused` (each logged if None). Returns the rounds committed, for
    a caller's callbacks. Raises RecordWriteError."""
    committed = []
    for effect in effects:
        if isinstance(effect, Note):
            log.log(effect.level, "%s", effect.text)
            continue
        if isinstance(effect, Rejected):
            if refused is None:
                log.warning("%s", effect.text)
            else:
                refused(effect)
            continue
        if isinstance(effect, Committed):
            committed.append(effect)
            line: Header | RoundEntry | Result = effect.entry
        else:
            line = effect
        if journal is not None:
            journal.append(line)
    return committed


def load_configured(setup: WorldSetup) -> Configured:
    """The run's algorithm, loaded by its reference and configured for `setup` (every process
    of a run loads it the same way). Raises AlgorithmError or AlgorithmParamsError."""
    return Configured.of(load_algorithm(setup.algorithm), setup.n, setup.params)


def cut_torn_line(path: str) -> None:
    """Drop a torn last line (the world died mid-write): it was never committed nor announced."""
    dropped = drop_torn_line(path)
    if dropped:
        log.warning("state file %s: dropping a torn last line of %d bytes", path, dropped)


def drop_torn_line(path: str) -> int:
    """Cut what follows the last newline of the file at `path` (a torn last line), durably; the
    number of bytes cut (0: none)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.rfind(b"\n") + 1
    if end < len(data):
        with open(path, "r+b") as f:
            f.truncate(end)
            f.flush()
            os.fsync(f.fileno())
    return len(data) - end


def open_world(
    state_path: str,
    make_setup: Callable[[], WorldSetup],
    swarm: str,
    max_rounds: int | None,
    fsync: bool = True,
    epoch: int = 0,
) -> tuple[WorldCore, RecordWriter]:
    """Resume from `state_path` if it holds a record, else start a new one from `make_setup()`:
    the world core and the record it appends to (its header written, for a new run).

    Raises RecordFormatError (a file that is not a run record), AlgorithmError or
    AlgorithmParamsError (an algorithm it cannot load), or what `make_setup` raises.
    """
    if os.path.exists(state_path) and os.path.getsize(state_path) > 0:
        cut_torn_line(state_path)
        record = read_record(state_path)
        setup = setup_from_header(record.header, swarm, max_rounds)
        journal = RecordWriter(state_path, fsync=fsync, append=True)
        core = WorldCore(setup, load_configured(setup), record, epoch=epoch)
        perform(core.take_effects(), journal)
        readout = core.readout
        log.info("resumed %s after round %d (%s)", state_path, readout.committed, readout.status)
        return core, journal
    setup = make_setup()
    journal = RecordWriter(state_path, fsync=fsync)
    core = WorldCore(setup, load_configured(setup), epoch=epoch)
    perform(core.take_effects(), journal)
    return core, journal
