"""Frozen dataclasses built faster: the messages a round builds every time (a lock step's round
builds each a few times) set their fields through their slots, not `object.__setattr__` by name.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, TypeVar

C = TypeVar("C", bound=type)
T = TypeVar("T")


def _check_slotted(cls: type, maker: str) -> None:
    """Raise TypeError unless `cls` is a frozen dataclass with slots and no `__post_init__`."""
    params = getattr(cls, "__dataclass_params__", None)
    if params is None or not params.frozen or "__slots__" not in cls.__dict__:
        raise TypeError(f"{maker} takes a frozen dataclass with slots, not {cls.__name__}")
    if hasattr(cls, "__post_init__"):
        raise TypeError(f"{maker} cannot keep {cls.__name__}.__post_init__")


def quick_init(cls: C) -> C:
    """`cls`, a frozen dataclass with slots, with an `__init__` that sets each field straight
    through its slot (the slot's own descriptor) instead of `object.__setattr__(self, name, ...)`
    as the dataclass's does: the same parameters (order, defaults, keyword-only ones), the same
    object made, at about half the cost. Raises TypeError for a class it cannot do that for (no
    slots, a field with a default factory or left out of `__init__`, a `__post_init__`)."""
    _check_slotted(cls, "quick_init")
    names: dict[str, Any] = {}
    positional: list[str] = []
    keywords: list[str] = []
    body: list[str] = []
    for f in dataclasses.fields(cls):
        if not f.init or f.default_factory is not dataclasses.MISSING:
            raise TypeError(f"quick_init cannot make {cls.__name__}.{f.name} (init or factory)")
        names[f"_set_{f.name}"] = cls.__dict__[f.name].__set__
        param = f.name
        if f.default is not dataclasses.MISSING:
            names[f"_default_{f.name}"] = f.default
            param += f"=_default_{f.name}"
        (keywords if f.kw_only else positional).append(param)
        body.append(f"    _set_{f.name}(self, {f.name})\n")
    signature = ", ".join(["self", *positional, *(["*", *keywords] if keywords else [])])
    source = f"def __init__({signature}):\n" + ("".join(body) or "    pass\n")
    where = f"<quick_init {cls.__module__}.{cls.__qualname__}>"  # (for tracebacks, profiles)
    exec(compile(source, where, "exec"), names)  # made of the class's own field names alone
    init = names["__init__"]
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__module__ = cls.__module__
    made = cls.__dict__["__init__"]  # the dataclass's own
    init.__doc__, init.__annotations__ = made.__doc__, dict(made.__annotations__)
    cls.__init__ = init  # type: ignore[misc]
    return cls


def quick_new(cls: type[T]) -> Callable[..., T]:
    """A maker of `cls` (a frozen dataclass with slots) from every field's value by name, none left
    out (defaults and factories are the caller's): each set straight through its slot, as
    `quick_init`'s, for a class whose `__init__` it cannot replace (a field with a default
    factory) built every round. The same object as `cls(**values)`."""
    _check_slotted(cls, "quick_new")
    names: dict[str, Any] = {"_new": object.__new__, "_cls": cls}
    fields = [f.name for f in dataclasses.fields(cls)]  # type: ignore[arg-type]
    for name in fields:
        names[f"_set_{name}"] = cls.__dict__[name].__set__
    body = "".join(f"    _set_{name}(self, {name})\n" for name in fields)
    source = f"def new(*, {', '.join(fields)}):\n    self = _new(_cls)\n{body}    return self\n"
    exec(compile(source, f"<quick_new {cls.__module__}.{cls.__qualname__}>", "exec"), names)
    made: Callable[..., T] = names["new"]
    made.__qualname__ = f"quick_new({cls.__qualname__})"
    return made


__all__ = ["quick_init", "quick_new"]
