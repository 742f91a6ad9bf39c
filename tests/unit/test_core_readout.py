"""The world core's readout: what the shells read of it, live and read only, and nothing else."""

from __future__ import annotations

import ast
from pathlib import Path as FsPath

import numpy as np
import pytest

from fatswarm.domain.path import Line, Path
from fatswarm.world.core import WorldCore
from fatswarm.world.journal import load_configured
from fatswarm.world.protocol import Begin, Commit
from fatswarm.world.setup import WorldSetup

ROOT = FsPath(__file__).resolve().parents[2]
SHELLS = ("deploy/engine/lockstep.py", "world/service.py", "world/journal.py")
CORE_NAMES = {"world", "core"}  # what the shells call the world core they drive


def _core() -> WorldCore:
    start = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    setup = WorldSetup("t", 3, 1, "ssync", start, 50, params={"a": 4.0})
    core = WorldCore(setup, load_configured(setup))
    for robot in range(3):
        core.set_alive(robot, True)
    return core


def test_the_readout_follows_the_core_round_by_round() -> None:
    core = _core()
    readout = core.readout
    assert (readout.committed, readout.open_round, readout.status) == (0, 0, "running")
    assert core.control(Begin(1, (0, 2)))[0].ok
    assert (readout.open_round, readout.active, set(readout.held)) == (1, (0, 2), set())
    assert core.admit_look(0)
    mirrored = readout.frame(0, 1).mirror
    assert core.hold(0, 1, Path((Line((-1.0 if mirrored else 1.0, 0.0)),)), None)
    assert set(readout.held) == {0}
    assert core.control(Commit(1))[0].ok
    assert (readout.committed, readout.open_round, set(readout.held)) == (1, 0, set())
    assert readout.positions[0].tolist() == [1.0, 0.0]
    assert readout.progress().rounds == 1 and readout.progress().moves == 1
    assert (readout.time(), readout.lights(), readout.setup.n) == (None, (), 3)


def test_the_readout_cannot_change_the_core() -> None:
    readout = _core().readout
    with pytest.raises(AttributeError):
        readout.open_round = 3  # type: ignore[misc]
    with pytest.raises(AttributeError):
        readout.extra = 1  # type: ignore[attr-defined]
    assert not hasattr(readout.held, "pop")  # a view of the held moves' robots, not the dict


def _is_core(expr: ast.expr) -> bool:
    """Whether `expr` names the world core a shell drives: `world`, `core`, `self.world`."""
    if isinstance(expr, ast.Name):
        return expr.id in CORE_NAMES
    return (
        isinstance(expr, ast.Attribute)
        and expr.attr in CORE_NAMES
        and isinstance(expr.value, ast.Name)
        and expr.value.id == "self"
    )


def _reads_of_the_core(source: str) -> set[str]:
    """The attributes a module names on the world core it drives (`world.x`, `self.core.x`)."""
    return {
        node.attr
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.Attribute) and _is_core(node.value)
    }


@pytest.mark.parametrize("shell", SHELLS)
def test_the_shells_send_the_core_commands_and_read_it_through_its_readout(shell: str) -> None:
    commands = {
        name for name, value in vars(WorldCore).items() if callable(value) and name[0] != "_"
    }
    named = _reads_of_the_core((ROOT / shell).read_text(encoding="utf-8"))
    assert named - commands - {"readout"} == set()


def test_the_check_of_the_shells_sees_a_read_of_the_core_books() -> None:
    reads = _reads_of_the_core("def f(world):\n    return world.positions, self.core.tracker\n")
    assert reads == {"positions", "tracker"}
