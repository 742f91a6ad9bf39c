"""The properties of one Look, each a function that says how a look breaks it (or None): path,
palette, obliviousness, order, and the frames (mirror, rotation, both); and their check over the
views, which shows the smallest view that breaks a property."""

from __future__ import annotations

import math
import types
from collections.abc import Callable, Mapping, Sequence
from contextlib import suppress
from typing import Any, Final

import numpy as np

from fatswarm.domain.frames import Frame
from fatswarm.domain.lights import Glance
from fatswarm.domain.path import Points
from fatswarm.domain.wire import ProtocolError
from fatswarm.testing.look import TOLERANCE_REL, Look, same_answer, show_path
from fatswarm.testing.report import AlgorithmContractError
from fatswarm.testing.shrink import shrink_look
from fatswarm.testing.starts import SHUFFLE_STREAM
from fatswarm.testing.subject import BadAnswer, Broken, Subject
from fatswarm.world.protocol import MoveSubmitted

ROTATIONS: Final = (math.pi / 2.0, 2.0, 4.5)  # radians: the frames a view is turned into
MIRRORED_ROTATIONS: Final = (0.0, 1.0, 3.7)


def _path_broken(subject: Subject, look: Look) -> str | None:
    try:
        path, _ = subject.answer(look)
        MoveSubmitted.of(0, 1, path)
    except BadAnswer as exc:
        return f"  {exc}"
    except ProtocolError as exc:
        return f"  the world refuses the path {show_path(path)}: {exc}"
    return None


def _palette_broken(subject: Subject, look: Look) -> str | None:
    try:
        _, colour = subject.answer(look)
    except BadAnswer as exc:
        return f"  {exc}"
    if isinstance(colour, str) and colour in subject.colours:
        return None
    return f"  compute_lit showed {colour!r}, not one of {', '.join(subject.colours)}"


def _oblivious_broken(subject: Subject, look: Look) -> str | None:
    """The same look three times: twice in a row, then after another view (a state that
    survives a call shows in one or the other); then whether the Compute wrote into its view."""
    try:
        first, twice = subject.answer(look), subject.answer(look)
        other = Look(look.view[::-1] * 1.5, look.permuted(range(len(look.view))[::-1]).glance)
        with suppress(BadAnswer):  # any other view: whether the algorithm takes it or not
            subject.answer(other)
        again = subject.answer(look)
        view = np.array(look.view, dtype=np.float64)
        _answer_on(subject, view, look.glance)
    except BadAnswer as exc:
        return f"  {exc}"
    if not np.array_equal(view, look.view):
        return f"  {subject.compute_name} changed the view it was given, to {Look(view).describe()}"
    for when, answer in (("called again at once", twice), ("after one other view", again)):
        if not same_answer(first, answer, look):
            return f"  first {subject.show(first)}; {when}, {subject.show(answer)}"
    return None


def _answer_on(subject: Subject, view: Points, glance: Glance | None) -> None:
    """The algorithm's Compute on `view` itself (not a copy): whether it writes into it."""
    setting = subject.setting(len(view) + 1)
    assert setting is not None
    try:
        if subject.colours:
            lit: Any = subject.algorithm
            lit.compute_lit(view, glance, setting.params)
        else:
            subject.algorithm.compute(view, setting.params)
    except Exception as exc:
        raise BadAnswer(f"{subject.compute_name} raised {type(exc).__name__}: {exc}") from exc


def _orders(k: int) -> list[list[int]]:
    """Reordered rows a view is checked with: reversed, rolled by one and shuffled (seeded by
    its size alone, so that a shrunk view is checked as it was found)."""
    if k < 2:
        return []
    shuffled = np.random.default_rng([SHUFFLE_STREAM, k]).permutation(k).tolist()
    return [list(range(k))[::-1], [*range(1, k), 0], [int(i) for i in shuffled]]


def _order_broken(subject: Subject, look: Look) -> str | None:
    try:
        base = subject.answer(look)
        for order in _orders(len(look.view)):
            other = subject.answer(look.permuted(order))
            if not same_answer(base, other, look):
                return (
                    f"  {subject.show(base)} for the view as it is; {subject.show(other)} with "
                    f"its rows in the order {order}"
                )
    except BadAnswer as exc:
        return f"  {exc}"
    return None


def _indistinguishable(look: Look, other: Look) -> bool:
    """Whether two looks show the same robots (and colours), in any order, within tolerance: a
    view that is its own mirror image, say, where the contract cannot ask the path to follow
    the frame (docs/algorithm.md, G12: the paper's robot on the axis picks a side by its +X)."""
    if look.glance != other.glance and (look.glance is None or look.glance.others is None):
        return False
    tol = TOLERANCE_REL * look.scale()
    colours = _row_colours(look)
    left = list(range(len(other.view)))
    for row, (x, y) in enumerate(look.view):
        match = next(
            (
                j
                for j in left
                if abs(other.view[j, 0] - x) <= tol
                and abs(other.view[j, 1] - y) <= tol
                and _row_colours(other)[j] == colours[row]
            ),
            None,
        )
        if match is None:
            return False
        left.remove(match)
    return look.glance is None or other.glance is None or look.glance.own == other.glance.own


def _row_colours(look: Look) -> tuple[str | None, ...]:
    others = look.glance.others if look.glance is not None else None
    return others if others is not None else (None,) * len(look.view)


def _frames_broken(frames: Sequence[Frame], what: Callable[[Frame], str]) -> Broken:
    """The property that a path computed in each of `frames` is the path in the view's frame."""

    def broken(subject: Subject, look: Look) -> str | None:
        try:
            base = subject.answer(look)
            for frame in frames:
                turned = look.in_frame(frame)
                if _indistinguishable(look, turned):
                    continue  # the robot cannot tell the frames apart: it may break the tie
                path, colour = subject.answer(turned)
                back = (frame.path_to_world(path), colour)
                if not same_answer(base, back, look):
                    return (
                        f"  {subject.show(base)} for the view; {subject.show((path, colour))} "
                        f"{what(frame)}, which is {subject.show(back)} in the view's frame"
                    )
        except BadAnswer as exc:
            return f"  {exc}"
        return None

    return broken


LOOK_PROPERTIES: Final[Mapping[str, Broken]] = types.MappingProxyType(
    {
        "path": _path_broken,
        "palette": _palette_broken,
        "oblivious": _oblivious_broken,
        "order": _order_broken,
        "mirror": _frames_broken([Frame(0.0, True)], lambda f: "for the mirrored view"),
        "rotation": _frames_broken(
            [Frame(angle, False) for angle in ROTATIONS],
            lambda f: f"for the view turned by {f.rotation!r} rad",
        ),
        "rotation-mirror": _frames_broken(
            [Frame(angle, True) for angle in MIRRORED_ROTATIONS],
            lambda f: f"for the view mirrored and turned by {f.rotation!r} rad",
        ),
    }
)


def check_looks(subject: Subject, name: str, looks: Sequence[Look]) -> None:
    """Raise AlgorithmContractError at the first look that breaks property `name`, shrunk."""
    broken = LOOK_PROPERTIES[name]
    for look in looks:
        found = broken(subject, look)
        if found is None:
            continue
        smallest = shrink_look(subject, broken, look)
        detail = broken(subject, smallest) or found
        raise AlgorithmContractError(
            subject.name,
            name,
            f"  smallest view that breaks it ({subject.describe_params(smallest.n)}; the robot "
            f"at the origin, the others relative to it): {smallest.describe()}\n{detail}",
            view=smallest.view,
            glance=smallest.glance,
        )
