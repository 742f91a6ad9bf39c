"""`quick_init` (fatswarm/domain/quick.py): a frozen dataclass whose __init__ sets its slots
directly makes the very objects the dataclass's own __init__ makes, and stays frozen."""

from __future__ import annotations

import copy
import dataclasses
import inspect
from collections.abc import Callable

import pytest

from fatswarm.domain.quick import quick_init, quick_new
from fatswarm.world.protocol import Commit, ControlReply


def _message(quick: bool) -> type:
    @dataclasses.dataclass(frozen=True, slots=True)
    class Message:
        round: int
        robots: tuple[int, ...]
        epoch: int = 0
        why: str = ""
        extra: tuple[int, ...] = dataclasses.field(default=(), kw_only=True)

    return quick_init(Message) if quick else Message


def test_a_quick_init_makes_what_the_dataclass_init_makes() -> None:
    plain, quick = _message(False), _message(True)
    assert str(inspect.signature(quick)) == str(inspect.signature(plain))
    for args, kwargs in [((1, (2, 3)), {}), ((4, (), 5), {"why": "w", "extra": (6,)})]:
        a, b = plain(*args, **kwargs), quick(*args, **kwargs)
        assert dataclasses.astuple(a) == dataclasses.astuple(b)
        assert repr(a) == repr(b)
        assert dataclasses.replace(b, epoch=9).epoch == 9
        assert copy.deepcopy(b) == b
        assert hash(b) == hash(quick(*args, **kwargs))
    with pytest.raises(TypeError):
        quick(1, (), 0, "", (7,))  # `extra` is keyword-only, as in the dataclass's own
    with pytest.raises(TypeError):
        quick(1)  # `robots` has no default
    with pytest.raises(dataclasses.FrozenInstanceError):
        quick(1, ()).round = 2


@pytest.mark.parametrize("maker", [quick_init, quick_new])
def test_quick_init_and_quick_new_refuse_what_they_cannot_keep(
    maker: Callable[[type], object],
) -> None:
    @dataclasses.dataclass(frozen=True, slots=True)
    class Factory:
        items: list[int] = dataclasses.field(default_factory=list)

    @dataclasses.dataclass(frozen=True)
    class NoSlots:
        x: int

    @dataclasses.dataclass(slots=True)
    class NotFrozen:
        x: int

    @dataclasses.dataclass(frozen=True, slots=True)
    class Checked:
        x: int

        def __post_init__(self) -> None:
            raise AssertionError

    # a default factory is quick_new's caller's to fill in, not quick_init's to keep
    for cls in (Factory, NoSlots, NotFrozen, Checked)[maker is quick_new :]:
        with pytest.raises(TypeError):
            maker(cls)


def test_the_round_messages_are_built_by_quick_init() -> None:
    assert ControlReply.__init__.__code__.co_filename.startswith("<quick_init")
    commit = Commit(3, then_active=(0, 1))
    assert (commit.round, commit.timed_out, commit.then_active, commit.delays) == (
        3,
        (),
        (0, 1),
        (),
    )
