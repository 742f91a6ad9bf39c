"""A test kit for an algorithm of your own: `check_algorithm(ALGORITHM)` holds it to the model's
contract, as scikit-learn's `check_estimator` does for estimators, and raises
`AlgorithmContractError` naming the property broken and the smallest view (or start) that breaks
it. docs/algorithms.md, "Testing your algorithm"; the pytest plugin is fatswarm/pytest_plugin.py.
"""

from __future__ import annotations

import itertools
import math
import sys
import time
import types
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from fatswarm.deploy.engine.config import DEFAULT_A, input_errors
from fatswarm.deploy.hunt.search import (
    Candidate,
    Case,
    Failure,
    Hunt,
    draw_candidate,
    hunt_models,
    run_candidate,
    start_families,
)
from fatswarm.deploy.hunt.shrink import shrink
from fatswarm.deploy.scenarios.adversarial import FAMILIES, adversarial_start, family_range
from fatswarm.deploy.scenarios.starts import random_start
from fatswarm.deploy.sweep.grid import params_text
from fatswarm.domain.frames import Frame
from fatswarm.domain.lights import Glance, LightsError, Lit, palette
from fatswarm.domain.path import Arc, Line, Path, Points
from fatswarm.domain.registry import check_algorithm as check_seam
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import Frames, RobotModel
from fatswarm.domain.seam import (
    MAX_TEXT,
    Algorithm,
    AlgorithmError,
    AlgorithmParamsError,
    Configured,
    ParamValue,
    assumed_frames,
    resolve_values,
)
from fatswarm.domain.wire import ProtocolError
from fatswarm.world.physics import validate_configuration
from fatswarm.world.protocol import MoveSubmitted

DEFAULT_BUDGET_S: Final = 3.0  # seconds of hunting (the checks of views take well under one more)
DEFAULT_SIZES: Final = tuple(range(2, 9))  # n the views and the hunt are drawn with
# Round schedulers only: the async models are a model an algorithm has to claim (gathering, say,
# collides under them); pass schedulers=hunt_models() for every one.
DEFAULT_SCHEDULERS: Final = ("fsync", "ssync", "centralized")
STARTS_PER_FAMILY: Final = 2  # starts each family gives the checks of views
TOLERANCE_REL: Final = 1e-9  # paths equal within this, relative to the view's extent
SWEEP_TOLERANCE: Final = 1e-9  # radians
SHRINK_RUNS: Final = 120  # lock-step runs the shrinking of a hunt's failure may take
SHRINK_CHUNK: Final = 10  # runs between two looks at the clock while shrinking
MIN_SHRINK_S: Final = 1.0  # shrinking may take as long as the hunt took, and this at least
SHOWN_ROUNDS: Final = 12  # rounds of a shrunk schedule the message shows
# decimals a shrunk view's coordinates are rounded to, the fewest first, if it still breaks then
SHRINK_DECIMALS: Final = (0, 1, 2, 3, 4, 6)
SHUFFLE_STREAM: Final = 0x7E57  # the views' shuffles, apart from every other seeded stream
ROTATIONS: Final = (math.pi / 2.0, 2.0, 4.5)  # radians: the frames a view is turned into
MIRRORED_ROTATIONS: Final = (0.0, 1.0, 3.7)

# The properties, in the order they are checked: a later one compares Computes, so it means
# something only once the earlier ones hold.
RULES: Final[Mapping[str, str]] = types.MappingProxyType(
    {
        "seam": "it must be an algorithm fatswarm can load (docs/algorithms.md, 'The contract')",
        "path": "compute must return a Path the world accepts (a Lit for a luminous algorithm), "
        "without raising, for every robot of a start it accepts",
        "palette": "compute_lit must show one of the algorithm's colours",
        "oblivious": "the same view must give the same path: nothing may survive a call (no state, "
        "no randomness), and the view must be left as it was",
        "order": "the path (and colour) must not depend on the order of the view's rows",
        "mirror": "mirroring the view (x -> -x) must mirror the path (frames 'y-axis')",
        "rotation": "rotating the view must rotate the path (frames 'chirality')",
        "rotation-mirror": "rotating and mirroring the view must rotate and mirror the path "
        "(frames 'disoriented')",
        "params": "a parameter value the algorithm cannot use must be refused with "
        "AlgorithmParamsError, in one line",
        "hunt": "a seeded hunt over the start families must find no collision and no stall",
    }
)
CHECKS: Final = tuple(RULES)
_FRAME_CHECKS: Final = {
    Frames.Y_AXIS: "mirror",
    Frames.CHIRALITY: "rotation",
    Frames.DISORIENTED: "rotation-mirror",
}
_FAILURE_WORDS: Final = {
    "collision": "a collision",
    "stalled": "a stall",
    "max_rounds": "no end within the round cap",
    "invariant": "a broken invariant",
    "error": "an error in the algorithm",
}
_WRONG_TYPES: Final[Mapping[type, tuple[object, ...]]] = types.MappingProxyType(
    {
        bool: ("maybe", 1.5, None),
        int: ("many", 1.5, True, None),
        float: ("not-a-number", "nan", True, None),
        str: (1.5, True, None),
    }
)
_EDGE_VALUES: Final[Mapping[type, tuple[ParamValue, ...]]] = types.MappingProxyType(
    {
        bool: (True, False),
        int: (0, -1, 1, 2**31),
        float: (0.0, -0.0, -1.0, 1e-12, 1e12, -1e12),
        str: ("", "?", "x" * MAX_TEXT),
    }
)
_subjects = itertools.count(1)


class AlgorithmContractError(AssertionError):
    """An algorithm breaks a property of the model's contract. `property` names it (one of
    CHECKS); `view` is the smallest view found that breaks it ((k, 2), the robot at the origin,
    in its own frame; None where no view is at fault), `glance` the colours shown with it (a
    luminous algorithm); for a hunt's failure, `positions` is the smallest start, `kind` the
    failure's kind (collision, stalled, max_rounds...) and `case` the run that replays it (a
    `fatswarm.deploy.hunt.search.Case`: start, active sets by round, seed)."""

    def __init__(
        self,
        algorithm: str,
        prop: str,
        detail: str,
        *,
        view: Points | None = None,
        glance: Glance | None = None,
        positions: Points | None = None,
        kind: str | None = None,
        case: Case | None = None,
    ) -> None:
        super().__init__(f"algorithm {algorithm!r} breaks {prop!r}: {RULES[prop]}\n{detail}")
        self.algorithm = algorithm
        self.property = prop
        self.detail = detail
        self.view = view
        self.glance = glance
        self.positions = positions
        self.kind = kind
        self.case = case


@dataclass(frozen=True, slots=True)
class Checked:
    """What `check_algorithm` checked: the properties, how many views (Looks) and hunt runs, how
    many hunt starts the algorithm refused, and the seconds it took."""

    algorithm: str
    checks: tuple[str, ...]
    looks: int
    hunt_runs: int
    refused: int
    seconds: float


# -- what a robot is shown ---------------------------------------------------------------------


@dataclass(frozen=True, slots=True, eq=False)
class Look:
    """One robot's view: the others' centres relative to it, in its frame ((k, 2)), and for a
    luminous algorithm the colours it is shown (`glance.others` lined up with the rows)."""

    view: Points
    glance: Glance | None = None

    @property
    def n(self) -> int:
        return len(self.view) + 1

    def without(self, row: int) -> Look:
        """The look with robot `row` gone (its colour too)."""
        return self.permuted([i for i in range(len(self.view)) if i != row])

    def permuted(self, order: Sequence[int]) -> Look:
        """The look with its rows (and their colours) in `order`."""
        glance = self.glance
        if glance is not None and glance.others is not None:
            glance = Glance(glance.own, tuple(glance.others[i] for i in order))
        return Look(np.array(self.view[list(order)], dtype=np.float64).reshape(-1, 2), glance)

    def in_frame(self, frame: Frame) -> Look:
        """The same look in another private frame (the colours stay with their rows)."""
        return Look(frame.to_local(self.view), self.glance)

    def rounded(self, places: int) -> Look:
        return Look(np.round(self.view, places) + 0.0, self.glance)

    def configuration(self) -> Points:
        """(n, 2): the robot at the origin, then the others."""
        return np.vstack([np.zeros((1, 2)), self.view])

    def scale(self) -> float:
        return max(1.0, float(np.abs(self.view).max())) if len(self.view) else 1.0

    def describe(self) -> str:
        rows = ", ".join(f"[{_num(x)}, {_num(y)}]" for x, y in self.view)
        text = f"[{rows}]"
        if self.glance is not None:
            text += f", own colour {self.glance.own!r}, their colours {self.glance.others!r}"
        return text


Answer = tuple[Path, object]  # a Compute's path, and the colour of a luminous one (else None)


class _BadAnswer(Exception):
    """The algorithm raised, or answered something that is not a Path (a Lit)."""


# -- the algorithm under test ------------------------------------------------------------------


class _Subject:
    """The algorithm checked, its parameters, and its configuration for each n (cached)."""

    def __init__(self, algorithm: Algorithm[Any], ref: str | None, given: Mapping[str, object]):
        self.algorithm = algorithm
        self.ref = ref  # how to load it, when it was given that way
        self.given = dict(given)
        self.name = str(algorithm.name)
        self.colours = palette(algorithm)
        self.frames = assumed_frames(algorithm)
        self._settings: dict[int, Configured | None] = {}
        self.refusals: dict[int, str] = {}  # n -> why the algorithm refuses it

    @staticmethod
    def of(algorithm: object, params: Mapping[str, object] | None) -> _Subject:
        """The subject; raises AlgorithmError for a reference that cannot be loaded and
        AlgorithmContractError ('seam') for an object that is not an algorithm."""
        ref = algorithm if isinstance(algorithm, str) else None
        loaded = load_algorithm(algorithm) if isinstance(algorithm, str) else algorithm
        label = str(getattr(loaded, "name", type(loaded).__name__))
        try:
            checked = check_seam(loaded, ref or label)
            subject = _Subject(checked, ref, params or {})
        except (AlgorithmError, LightsError) as exc:
            raise AlgorithmContractError(label, "seam", f"  {exc}") from None
        resolve_values(checked, subject.given)  # an unknown parameter, a bad value: ValueError
        return subject

    def setting(self, n: int) -> Configured | None:
        """The algorithm configured for n robots; None if it refuses n (AlgorithmParamsError)."""
        if n not in self._settings:
            try:
                self._settings[n] = Configured.of(self.algorithm, n, self.given)
            except AlgorithmParamsError as exc:
                self._settings[n] = None
                self.refusals[n] = str(exc)
        return self._settings[n]

    def accepts(self, look: Look) -> bool:
        """Whether the look is a robot's of a start the algorithm accepts (valid, not refused)."""
        setting = self.setting(look.n)
        if setting is None:
            return False
        try:
            setting.check_start(validate_configuration(look.configuration()))
        except input_errors():
            return False
        return True

    def answer(self, look: Look) -> Answer:
        """The Compute of the robot shown `look` (on a copy of its view); raises _BadAnswer."""
        setting = self.setting(look.n)
        assert setting is not None  # looks come from starts configured for their n
        view = np.array(look.view, dtype=np.float64).reshape(-1, 2)
        try:
            if self.colours:
                lit: Any = self.algorithm
                given = lit.compute_lit(view, look.glance, setting.params)
                if not isinstance(given, Lit):
                    raise _BadAnswer(f"compute_lit returned {type(given).__name__}, not a Lit")
                path, colour = given.path, given.colour
            else:
                path, colour = self.algorithm.compute(view, setting.params), None
        except _BadAnswer:
            raise
        except Exception as exc:
            raise _BadAnswer(f"{self.compute_name} raised {type(exc).__name__}: {exc}") from exc
        if not isinstance(path, Path):
            raise _BadAnswer(f"{self.compute_name} returned {type(path).__name__}, not a Path")
        return path, colour

    @property
    def compute_name(self) -> str:
        return "compute_lit" if self.colours else "compute"

    def show(self, answer: Answer) -> str:
        path, colour = answer
        return _show_path(path) + (f", colour {colour!r}" if self.colours else "")

    def describe_params(self, n: int) -> str:
        setting = self.setting(n)
        shown = setting.describe().partition(" ")[2] if setting is not None else ""
        return f"n = {n}" + (f", {shown}" if shown else "")

    @contextmanager
    def reference(self) -> Iterator[str]:
        """How the hunt loads the algorithm: its reference, or (an object given as is) a module
        made for it in this process for the time of the hunt."""
        if self.ref is not None:
            yield self.ref
            return
        module_name = f"_fatswarm_testing_subject_{next(_subjects)}"
        module = types.ModuleType(module_name)
        module.ALGORITHM = self.algorithm  # type: ignore[attr-defined]
        sys.modules[module_name] = module
        try:
            yield f"{module_name}:ALGORITHM"
        finally:
            sys.modules.pop(module_name, None)


# -- comparing and showing paths ---------------------------------------------------------------


def _num(value: float) -> str:
    return repr(float(value) + 0.0)


def _show_path(path: Path) -> str:
    if not path:
        return "stay"
    parts = []
    for seg in path.segments:
        if isinstance(seg, Line):
            parts.append(f"line to ({_num(seg.end[0])}, {_num(seg.end[1])})")
        else:
            parts.append(
                f"arc about ({_num(seg.center[0])}, {_num(seg.center[1])}) by {seg.sweep!r}"
            )
    return " then ".join(parts)


def _same_path(p: Path, q: Path, tol: float) -> bool:
    if len(p) != len(q):
        return False
    for s, t in zip(p.segments, q.segments, strict=True):
        if isinstance(s, Line) and isinstance(t, Line):
            a, b = s.end, t.end
        elif isinstance(s, Arc) and isinstance(t, Arc):
            if abs(s.sweep - t.sweep) > SWEEP_TOLERANCE:
                return False
            a, b = s.center, t.center
        else:
            return False
        if abs(a[0] - b[0]) > tol or abs(a[1] - b[1]) > tol:
            return False
    return True


def _same(p: Answer, q: Answer, look: Look) -> bool:
    return p[1] == q[1] and _same_path(p[0], q[0], TOLERANCE_REL * look.scale())


# -- the properties of one Look ----------------------------------------------------------------

Broken = Callable[[_Subject, Look], str | None]  # how a look breaks a property, or None


def _path_broken(subject: _Subject, look: Look) -> str | None:
    try:
        path, _ = subject.answer(look)
        MoveSubmitted.of(0, 1, path)
    except _BadAnswer as exc:
        return f"  {exc}"
    except ProtocolError as exc:
        return f"  the world refuses the path {_show_path(path)}: {exc}"
    return None


def _palette_broken(subject: _Subject, look: Look) -> str | None:
    try:
        _, colour = subject.answer(look)
    except _BadAnswer as exc:
        return f"  {exc}"
    if isinstance(colour, str) and colour in subject.colours:
        return None
    return f"  compute_lit showed {colour!r}, not one of {', '.join(subject.colours)}"


def _oblivious_broken(subject: _Subject, look: Look) -> str | None:
    """The same look three times: twice in a row, then after another view (a state that
    survives a call shows in one or the other); then whether the Compute wrote into its view."""
    try:
        first, twice = subject.answer(look), subject.answer(look)
        other = Look(look.view[::-1] * 1.5, look.permuted(range(len(look.view))[::-1]).glance)
        with suppress(_BadAnswer):  # any other view: whether the algorithm takes it or not
            subject.answer(other)
        again = subject.answer(look)
        view = np.array(look.view, dtype=np.float64)
        _answer_on(subject, view, look.glance)
    except _BadAnswer as exc:
        return f"  {exc}"
    if not np.array_equal(view, look.view):
        return f"  {subject.compute_name} changed the view it was given, to {Look(view).describe()}"
    for when, answer in (("called again at once", twice), ("after one other view", again)):
        if not _same(first, answer, look):
            return f"  first {subject.show(first)}; {when}, {subject.show(answer)}"
    return None


def _answer_on(subject: _Subject, view: Points, glance: Glance | None) -> None:
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
        raise _BadAnswer(f"{subject.compute_name} raised {type(exc).__name__}: {exc}") from exc


def _orders(k: int) -> list[list[int]]:
    """Reordered rows a view is checked with: reversed, rolled by one and shuffled (seeded by
    its size alone, so that a shrunk view is checked as it was found)."""
    if k < 2:
        return []
    shuffled = np.random.default_rng([SHUFFLE_STREAM, k]).permutation(k).tolist()
    return [list(range(k))[::-1], [*range(1, k), 0], [int(i) for i in shuffled]]


def _order_broken(subject: _Subject, look: Look) -> str | None:
    try:
        base = subject.answer(look)
        for order in _orders(len(look.view)):
            other = subject.answer(look.permuted(order))
            if not _same(base, other, look):
                return (
                    f"  {subject.show(base)} for the view as it is; {subject.show(other)} with "
                    f"its rows in the order {order}"
                )
    except _BadAnswer as exc:
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

    def broken(subject: _Subject, look: Look) -> str | None:
        try:
            base = subject.answer(look)
            for frame in frames:
                turned = look.in_frame(frame)
                if _indistinguishable(look, turned):
                    continue  # the robot cannot tell the frames apart: it may break the tie
                path, colour = subject.answer(turned)
                back = (frame.path_to_world(path), colour)
                if not _same(base, back, look):
                    return (
                        f"  {subject.show(base)} for the view; {subject.show((path, colour))} "
                        f"{what(frame)}, which is {subject.show(back)} in the view's frame"
                    )
        except _BadAnswer as exc:
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


# -- the views checked -------------------------------------------------------------------------


def _start(setting: Configured, family: str, n: int, seed: int) -> Points:
    """A start of the family (`fatswarm hunt`'s), random kinds at the algorithm's scale `a`."""
    if family in FAMILIES:
        return adversarial_start(family, n, seed)
    scale = setting.values.get("a", DEFAULT_A)
    assert isinstance(scale, (int, float))
    return random_start(n, seed, family, float(scale))


def _family_sizes(family: str, sizes: Sequence[int]) -> list[int]:
    lo, hi = family_range(family) if family in FAMILIES else (2, max(sizes))
    return [n for n in sizes if max(lo, 2) <= n <= hi]


def _starts(subject: _Subject, seed: int, sizes: Sequence[int]) -> list[Points]:
    """STARTS_PER_FAMILY starts of every start family, n drawn from `sizes`, that the algorithm
    accepts; raises ValueError if it accepts none."""
    rng = np.random.default_rng([SHUFFLE_STREAM, seed & 0xFFFFFFFF])
    starts: list[Points] = []
    refusals: list[str] = []
    for family in start_families():
        usable = _family_sizes(family, sizes)
        for _ in range(STARTS_PER_FAMILY if usable else 0):
            n = usable[int(rng.integers(len(usable)))]
            start_seed = int(rng.integers(2**31))
            setting = subject.setting(n)
            if setting is None:
                refusals.append(f"n = {n}: {subject.refusals[n]}")
                continue
            try:
                positions = validate_configuration(_start(setting, family, n, start_seed))
                setting.check_start(positions)
            except input_errors() as exc:
                refusals.append(f"n = {n}, {family}: {exc}")
                continue
            starts.append(positions)
    if not starts:
        raise ValueError(
            f"algorithm {subject.name} refuses every start drawn with n in {list(sizes)} "
            f"({refusals[0] if refusals else 'none'}); pass sizes= with the n it supports"
        )
    return starts


def _looks(subject: _Subject, seed: int, sizes: Sequence[int]) -> list[Look]:
    """Every robot's look at each start, in the paper's frame; a luminous robot's twice: at the
    start (every colour the first) and with colours drawn from the seed."""
    rng = np.random.default_rng([SHUFFLE_STREAM, seed & 0xFFFFFFFF, 1])
    looks: list[Look] = []
    for positions in _starts(subject, seed, sizes):
        for robot in range(len(positions)):
            view = np.delete(positions, robot, axis=0) - positions[robot]
            if not subject.colours:
                looks.append(Look(view))
                continue
            first, k = subject.colours[0], len(view)
            drawn = [
                subject.colours[int(i)] for i in rng.integers(len(subject.colours), size=k + 1)
            ]
            looks.append(Look(view, Glance(first, (first,) * k)))
            looks.append(Look(view, Glance(drawn[0], tuple(drawn[1:]))))
    return looks


def _shrink(subject: _Subject, broken: Broken, look: Look) -> Look:
    """The smallest look found that still breaks the property: robots dropped one at a time while
    it still breaks (down to one robot seen), then the coordinates rounded to the fewest decimals
    that still break it. Every look tried is of a start the algorithm accepts."""
    best = look
    dropped = True
    while dropped and len(best.view) > 1:
        dropped = False
        for row in range(len(best.view)):
            smaller = best.without(row)
            if subject.accepts(smaller) and broken(subject, smaller) is not None:
                best, dropped = smaller, True
                break
    for places in SHRINK_DECIMALS:
        simpler = best.rounded(places)
        if subject.accepts(simpler) and broken(subject, simpler) is not None:
            return simpler
    return best


def _check_looks(subject: _Subject, name: str, looks: Sequence[Look]) -> None:
    """Raise AlgorithmContractError at the first look that breaks property `name`, shrunk."""
    broken = LOOK_PROPERTIES[name]
    for look in looks:
        found = broken(subject, look)
        if found is None:
            continue
        smallest = _shrink(subject, broken, look)
        detail = broken(subject, smallest) or found
        raise AlgorithmContractError(
            subject.name,
            name,
            f"  smallest view that breaks it ({subject.describe_params(smallest.n)}; the robot "
            f"at the origin, the others relative to it): {smallest.describe()}\n{detail}",
            view=smallest.view,
            glance=smallest.glance,
        )


# -- parameters --------------------------------------------------------------------------------


def _refusal_problem(subject: _Subject, n: int, values: Mapping[str, object], wrong: bool) -> str:
    """What is wrong with how the algorithm takes `values` for n robots ('' if nothing): it must
    refuse with AlgorithmParamsError in one line (and must refuse a value of the wrong type)."""
    what = ", ".join(f"{k}={v!r}" for k, v in values.items()) or "its defaults"
    try:
        Configured.of(subject.algorithm, n, {**subject.given, **values})
    except AlgorithmParamsError as exc:
        text = str(exc).strip()
        if not text or "\n" in text:
            return f"{what} (n = {n}) was refused with {text.count(chr(10)) + 1} lines: {text!r}"
        return ""
    except Exception as exc:
        return (
            f"make_params raised {type(exc).__name__}: {exc} for {what} (n = {n}); raise "
            "AlgorithmParamsError with one line saying what to fix"
        )
    return f"{what} (n = {n}) was accepted, a value of the wrong type" if wrong else ""


def _check_params(subject: _Subject, sizes: Sequence[int]) -> None:
    """Every n (refused or not, by AlgorithmParamsError only); then, for n the algorithm takes,
    each parameter with values of the wrong type (through the seam, as `--param` gives them) and
    values at the edges of its type (taken, or refused in one line)."""
    problems = (_refusal_problem(subject, n, {}, False) for n in sorted({1, 2, *sizes}))
    problem = next((p for p in problems if p), "")
    n = next((n for n in sizes if subject.setting(n) is not None), None)
    if not problem and n is not None:
        tries = (
            (spec.name, value, wrong)
            for spec in subject.algorithm.parameters
            for wrong, values in ((True, _WRONG_TYPES[spec.kind]), (False, _EDGE_VALUES[spec.kind]))
            for value in values
        )
        problems = (_refusal_problem(subject, n, {name: v}, wrong) for name, v, wrong in tries)
        problem = next((p for p in problems if p), "")
    if problem:
        raise AlgorithmContractError(subject.name, "params", f"  {problem}")


# -- the hunt ----------------------------------------------------------------------------------


def _hunt(
    subject: _Subject, seed: int, budget_s: float, sizes: Sequence[int], schedulers: Sequence[str]
) -> tuple[int, int]:
    """Lock-step runs drawn as `fatswarm hunt` draws them (every start family, `sizes`,
    `schedulers`; the paper's model under each of the frames the algorithm declares), from
    `seed`, until `budget_s` has passed (one run at least): (runs, starts the algorithm refused).
    Raises AlgorithmContractError at the first failure, shrunk."""
    runs = refused = 0
    refusal = ""
    with subject.reference() as ref:
        texts = [f"{k}={_text(v)}" for k, v in subject.given.items()]
        hunt = Hunt(
            algorithm=ref,
            params=params_text(subject.algorithm, texts),
            families=start_families(),
            sizes=tuple(sizes),
            models=tuple(schedulers),
            robot_models=tuple(RobotModel(frames=frames) for frames in subject.frames),
        )
        started = time.monotonic()
        deadline = started + budget_s
        for index in itertools.count():
            if index and time.monotonic() >= deadline:
                break
            candidate = draw_candidate(hunt, seed, index)
            outcome, case = run_candidate(hunt, candidate)
            if outcome.refused:
                refused += 1
                refusal = refusal or f"n = {candidate.n}, {candidate.family}: {outcome.refused}"
                continue
            runs += 1
            if outcome.failure is not None and case is not None:
                _hunt_failed(subject, hunt, candidate, outcome.failure, case, started)
    if not runs:
        raise ValueError(
            f"algorithm {subject.name} refused every one of the {refused} starts the hunt drew "
            f"({refusal}); pass sizes= with the n it supports"
        )
    return runs, refused


def _text(value: object) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def _hunt_failed(
    subject: _Subject,
    hunt: Hunt,
    candidate: Candidate,
    failure: Failure,
    case: Case,
    hunt_started: float,
) -> None:
    """Shrink the failure of a hunt's run (`fatswarm hunt`'s shrinker, for about as long as the
    hunt took) and raise it."""
    deadline = time.monotonic() + max(MIN_SHRINK_S, time.monotonic() - hunt_started)
    small, found, runs = _shrunk(hunt, case, failure, deadline)
    positions = small.points()
    script = ""
    if small.rounds is not None:
        shown = [list(r) for r in small.rounds[:SHOWN_ROUNDS]]
        more = f" ... ({len(small.rounds)} rounds)" if len(small.rounds) > SHOWN_ROUNDS else ""
        script = f"; active robots by round {shown}{more}, then {small.after}"
    model = "scripted" if small.rounds is not None else small.model
    detail = (
        f"  {_FAILURE_WORDS.get(found.kind, found.kind)}: {found.detail}\n"
        f"  smallest start that breaks it (n = {small.n}, {model}, run seed {small.seed}"
        f"{script}): {Look(positions).describe()}\n"
        f"  found by hunt run {candidate.index} (start family {candidate.family}, n = "
        f"{candidate.n}, {candidate.model}, run seed {candidate.seed}), shrunk in "
        f"{runs} runs"
    )
    raise AlgorithmContractError(
        subject.name, "hunt", detail, positions=positions, kind=found.kind, case=small
    )


def _shrunk(hunt: Hunt, case: Case, failure: Failure, deadline: float) -> tuple[Case, Failure, int]:
    """`fatswarm hunt`'s shrinking of a failure, SHRINK_CHUNK runs at a time until it finds
    nothing smaller, SHRINK_RUNS are spent or `deadline` (time.monotonic) passes: the smallest
    case, its failure and the runs taken."""
    runs = 0
    while runs < SHRINK_RUNS:
        shrunk = shrink(hunt, case, failure.kind, budget=SHRINK_CHUNK)
        runs += shrunk.runs
        if not shrunk.reproduced:
            break
        case, failure = shrunk.case, shrunk.failure
        if not shrunk.steps or time.monotonic() >= deadline:
            break
    return case, failure, runs


# -- the entry point ---------------------------------------------------------------------------


def _chosen(subject: _Subject, checks: Iterable[str] | None) -> tuple[str, ...]:
    """The properties to check, in CHECKS order: those asked for (ValueError for an unknown
    name), else every one that applies (the frames the algorithm declares; the palette of a
    luminous one). `seam` is always checked, first."""
    if checks is not None:
        asked = set(checks) if not isinstance(checks, str) else {checks}
        unknown = sorted(asked - set(CHECKS))
        if unknown:
            raise ValueError(f"unknown checks {unknown}; choose from {', '.join(CHECKS)}")
    else:
        asked = {"path", "palette", "oblivious", "order", "params", "hunt"}
        asked |= {_FRAME_CHECKS[frames] for frames in subject.frames}
    if not subject.colours:
        asked.discard("palette")
    return tuple(name for name in CHECKS if name in asked and name != "seam")


def _check_arguments(
    seed: object, budget: object, sizes: Sequence[int], schedulers: Sequence[str]
) -> None:
    """Refuse arguments check_algorithm cannot use (ValueError, one line)."""
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ValueError(f"seed must be an int, got {seed!r}")
    if isinstance(budget, bool) or not isinstance(budget, (int, float)) or not budget >= 0:
        raise ValueError(f"budget must be a number of seconds >= 0, got {budget!r}")
    if not sizes or any(isinstance(n, bool) or not isinstance(n, int) or n < 2 for n in sizes):
        raise ValueError(f"sizes must be whole numbers of robots >= 2, got {list(sizes)!r}")
    known = hunt_models()
    if not schedulers or any(s not in known for s in schedulers):
        raise ValueError(f"schedulers must be some of {', '.join(known)}, got {list(schedulers)!r}")


def check_algorithm(
    algorithm: object,
    *,
    params: Mapping[str, object] | None = None,
    seed: int = 0,
    budget: float = DEFAULT_BUDGET_S,
    sizes: Sequence[int] = DEFAULT_SIZES,
    schedulers: Sequence[str] = DEFAULT_SCHEDULERS,
    checks: Iterable[str] | None = None,
) -> Checked:
    """Hold `algorithm` (the object, or a reference as `--algorithm` takes it) to the model's
    contract; raise AlgorithmContractError at the first property it breaks.

    In order (RULES says each): `seam` (it is an algorithm), `path`, `palette` (luminous only),
    `oblivious`, `order`, the frames it declares (`mirror` for y-axis, `rotation` for chirality,
    `rotation-mirror` for disoriented), `params` and `hunt`. The views are every robot's of two
    starts of each of `fatswarm hunt`'s start families (n from `sizes`, drawn from `seed`), with
    `params` (defaults for the rest); a broken property is shown on the smallest view found (robots
    dropped while it still breaks, then coordinates rounded). The hunt runs lock-step runs drawn
    from `seed` over the start families, `sizes` and `schedulers` for `budget` seconds, and shrinks
    a failure as `fatswarm hunt` does. `checks`: only these (names of CHECKS).

    Raises ValueError for arguments it cannot use, or when the algorithm refuses every start drawn.
    """
    started = time.monotonic()
    sizes, schedulers = tuple(sizes), tuple(schedulers)
    _check_arguments(seed, budget, sizes, schedulers)
    subject = _Subject.of(algorithm, params)
    names = _chosen(subject, checks)
    looks = _looks(subject, seed, sizes) if set(names) & set(LOOK_PROPERTIES) else []
    runs = refused = 0
    for name in names:
        if name in LOOK_PROPERTIES:
            _check_looks(subject, name, looks)
        elif name == "params":
            _check_params(subject, sizes)
        else:
            runs, refused = _hunt(subject, seed, float(budget), sizes, schedulers)
    return Checked(subject.name, names, len(looks), runs, refused, time.monotonic() - started)


__all__ = [
    "CHECKS",
    "DEFAULT_BUDGET_S",
    "DEFAULT_SCHEDULERS",
    "DEFAULT_SIZES",
    "RULES",
    "AlgorithmContractError",
    "Checked",
    "Look",
    "check_algorithm",
]
