"""Every figure that crosses the house, declared once: the fields of a record's round line, and the
figures of a round and of a run (name, type, unit, how a run summarises it, where it shows).

The record's reader (known keys, the result line's typed figures), the JSON Schema's round and
result lines (`record_schema`) and the sweep table's figure columns read this module instead of
listing figures again. A figure with `derive` follows from the positions after a round
(`derived`): no record carries it (old records have it too), and it reaches the world's progress
and published state, the lock step's result, the dashboard's and replay's rows, `to_dataframe`,
the summary, `--json` and `fatswarm.summary` from here alone. The figures the world counts keep
typed fields in those shapes (`Result`, `RunResult`, `Outcome`...), tied to this list by tests.
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Final, Protocol

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.path import Points, float64_array

RADIUS: Final = 1.0  # every robot is a unit disc: the rim-to-rim gap is the centres' less 2
PAIRWISE_UP_TO: Final = 80  # min_gap measures every pair up to this many robots (faster there)
FEW_UP_TO: Final = 5  # up to this many robots, every pair in Python floats (no numpy call)
KEPT_FROM: Final = 48  # a run's min_gap is kept from round to round (`_GapMemo`) from this many


class Place(enum.Flag):
    """Where a figure shows besides the record (a run figure's value, or a round figure's)."""

    NONE = 0
    RESULT_LINE = enum.auto()  # a field of the record's result line (`Result`)
    CSV = enum.auto()  # a column of the sweep table (deploy/sweep/table.py)
    SUMMARY = enum.auto()  # the end-of-run summary text, `--json` and `fatswarm.summary`
    DASHBOARD = enum.auto()  # a row of the live dashboard and of replay (each round's value)
    DATAFRAME = enum.auto()  # a column of `RunRecord.to_dataframe` (each round's value)


class Summary(enum.StrEnum):
    """How a run summarises a figure it has after each round."""

    LAST = "last"  # its value after the last round
    SUM = "sum"  # the sum over the rounds
    COUNT = "count"  # how many rounds, or entries of them
    MIN = "min"  # the smallest value of any round
    MAX = "max"  # the largest value of any round
    FIRST = "first"  # the value of the first round that has one


FigureValue = int | float | str | None
Derive = Callable[[Points], float | None]  # a round's value from the (n, 2) positions after it
# a round's value from its number and its line's other fields (`RoundEntry.extra`)
Tally = Callable[[int, Mapping[str, Any]], FigureValue]


@dataclass(frozen=True, slots=True)
class Figure:
    """A figure of a run (and, with `derive`, of each round): what every carrier of it reads.

    `schema`: its JSON Schema on the result line (RESULT_LINE); `csv`: the format of its cell
    (blank for None); `kept_on_error`: a sweep row of a run that raised still has it.
    """

    name: str
    type: type  # the Python type of a value (None, too, where `optional`)
    unit: str  # "" for a count or a word
    help: str
    summary: Summary = Summary.LAST
    places: Place = Place.NONE
    label: str = ""  # the dashboard's and summary text's words for it (default: the name)
    optional: bool = False  # None where it does not apply (no rounds, one robot, a round model)
    derive: Derive | None = None
    tally: Tally | None = None  # instead of `derive`: from the round line's other fields
    schema: Mapping[str, Any] = field(default_factory=dict)
    csv: str = ""  # a format spec: "d", ".6f"
    kept_on_error: bool = False

    @property
    def words(self) -> str:
        return self.label or self.name.replace("_", " ")


def min_gap(positions: Points) -> float | None:
    """The smallest rim-to-rim distance between two robots of the (n, 2) `positions` (their
    centres' distance less 2: unit discs), None for fewer than two robots; negative if two overlap.

    Derived by every reader, never written: the positions say it exactly, so writing it would only
    lengthen every round line and leave the records before it without it; derived, every record
    stays byte for byte and every record, old ones too, has it.

    Up to PAIRWISE_UP_TO robots, every pair at once (~20 us at n = 64); above, sort and sweep
    along the wider axis: neighbours in that order give a first bound w, then only pairs within
    w along it are measured, all at once (O(n log n) for spread swarms, O(n^2) at worst; ~60 us
    at n = 256). Both take the least of the same squares, so they give the same bits.
    """
    pts = np.asarray(positions, dtype=np.float64).reshape(-1, 2)
    if len(pts) < 2:
        return None
    return math.sqrt(_closest(pts)[0]) - 2 * RADIUS


def _closest(pts: Points) -> tuple[float, int, int]:
    """The least squared centre distance of two of the (n, 2) `pts` (n >= 2), and a pair of
    robots (i, j) at it (`min_gap`'s measure; NaN if a coordinate is: then i, j say nothing)."""
    n = len(pts)
    if n <= FEW_UP_TO:
        return _closest_few(pts)
    if n <= PAIRWISE_UP_TO:
        first, second, squares = _pair_squares(pts)
        k = int(squares.argmin())  # (the first NaN, if any: the least is NaN then, as np.min's)
        return float(squares[k]), int(first[k]), int(second[k])
    axis = 0 if np.ptp(pts[:, 0]) >= np.ptp(pts[:, 1]) else 1
    order = np.argsort(pts[:, axis], kind="stable")
    along, across = pts[order, axis], pts[order, 1 - axis]
    dx, dy = np.diff(along), np.diff(across)
    squares = dx * dx + dy * dy
    k = int(squares.argmin())
    best2, pair = float(squares[k]), (k, k + 1)
    reach = math.sqrt(best2) * (1 + 1e-9)  # a rounding margin: no closer pair is left out
    counts = np.searchsorted(along, along + reach, side="right") - np.arange(n) - 2
    np.maximum(counts, 0, out=counts)  # the pairs (i, i + 2...) within reach along the axis
    total = int(counts.sum())
    if total:
        first = np.repeat(np.arange(n), counts)
        starts = np.repeat(np.cumsum(counts) - counts, counts)
        second = first + 2 + (np.arange(total) - starts)
        dx, dy = along[second] - along[first], across[second] - across[first]
        squares = dx * dx + dy * dy
        k = int(squares.argmin())
        if squares[k] < best2:  # (the least of the two, as `min(best2, ...)`)
            best2, pair = float(squares[k]), (int(first[k]), int(second[k]))
    return best2, int(order[pair[0]]), int(order[pair[1]])


def _closest_few(pts: Points) -> tuple[float, int, int]:
    """`_closest` of a few (n, 2) `pts` (2 <= n <= FEW_UP_TO) in Python floats: the same squares
    (`dx * dx + dy * dy` of dx = x_i - x_j, dy = y_i - y_j: IEEE's operations, one at a time, as
    numpy's), the first of the least in the pairs' order (i < j, by i then j), the first NaN if
    there is one (as `argmin`: a square is never negative, so the sum is NaN just then). A NaN
    goes to numpy's own squares: the sign bit of a NaN made by Python's float operations need not
    be numpy's."""
    flat: list[float] = pts.ravel().tolist()
    if len(flat) == 4:  # two robots: one pair
        dx, dy = flat[0] - flat[2], flat[1] - flat[3]
        square = dx * dx + dy * dy
        if square == square:
            return square, 0, 1
    else:
        pairs = _few_pairs(len(pts))
        squares = [
            (dx := flat[a] - flat[b]) * dx + (dy := flat[a + 1] - flat[b + 1]) * dy
            for a, b in pairs
        ]
        best2 = min(squares)
        total = sum(squares)
        if total == total:  # no NaN (min would not say which)
            a, b = pairs[squares.index(best2)]
            return best2, a // 2, b // 2
    first, second, every = _pair_squares(pts)
    k = int(every.argmin())  # the first NaN, as `_closest`'s pairwise path
    return float(every[k]), int(first[k]), int(second[k])


@functools.lru_cache(maxsize=FEW_UP_TO + 1)
def _few_pairs(n: int) -> tuple[tuple[int, int], ...]:
    """Every pair i < j of n robots, as their x's places (2 i, 2 j) in the flat positions."""
    return tuple((2 * i, 2 * j) for i in range(n) for j in range(i + 1, n))


def _pair_squares(
    pts: Points, first: NDArray[np.intp] | None = None, second: NDArray[np.intp] | None = None
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """(i, j, the squared centre distance of i and j) of every pair i < j of the (n, 2) `pts`,
    or of the pairs (first, second) given: `dx * dx + dy * dy` of dx = x_i - x_j, dy = y_i - y_j
    ((x_j - x_i)^2 is (x_i - x_j)^2, to the bit). The points taken as complex numbers x + iy:
    one gather and one subtraction give both differences, each IEEE's as apart."""
    if first is None or second is None:
        first, second = _pairs(len(pts))
    z = np.ascontiguousarray(pts).view(np.complex128).reshape(len(pts))
    d = z[first] - z[second]
    dx, dy = d.real, d.imag
    return first, second, dx * dx + dy * dy


NEAR_MARGIN: Final = 1.0  # _GapMemo's near pairs: those within the least distance + this
NEAR_BACKOFF: Final = 8  # rounds without near pairs after a list that served no round, at
NEAR_BACKOFF_MAX: Final = 256  # first; twice as many after each such list, up to this


class _GapMemo:
    """`min_gap` round after round with the same bits (the least of the same squares), measuring
    only pairs that can be the closest:

    - the near pairs of the last whole measure (those within its least distance + NEAR_MARGIN,
      positions P0): while every robot is within D of its place in P0, a pair that is not near
      is more than that distance - 2 D apart, so if the least of the near pairs is below it (with
      a wide rounding margin), it is the least of all;
    - else, few movers, the closest pair before among the stills: the least over the stills'
      pairs is that pair's (their squares are as before), so only the pairs with a mover are
      measured;
    - else (or NaN, infinity) every pair, as `min_gap` (up to PAIRWISE_UP_TO robots, with the
      near pairs of the same squares).
    """

    def __init__(self) -> None:
        self._last: tuple[Points, float, int, int] | None = None  # positions, least, its pair
        # P0, its near pairs (i, j), their bound R (the least distance + NEAR_MARGIN), and the
        # largest coordinate of P0 (in magnitude)
        self._near: tuple[Points, NDArray[np.intp], NDArray[np.intp], float, float] | None = None
        self._served = 0  # rounds the near pairs answered
        self._backoff = 0  # rounds to go without near pairs
        self._wait = NEAR_BACKOFF // 2  # the backoff after a list that served no round

    def min_gap(self, positions: Points) -> float | None:
        shape = positions.shape  # (a reshape to (n, 2) costs more than the test of one)
        pts = positions if len(shape) == 2 and shape[1] == 2 else positions.reshape(-1, 2)
        n = len(pts)
        if n < KEPT_FROM:  # (every pair at once: cheaper than keeping any)
            if n < 2:
                return None
            return (
                math.sqrt((_closest_few(pts) if n <= FEW_UP_TO else _closest(pts))[0]) - 2 * RADIUS
            )
        found = self._near_ones(pts)  # (finite positions only: a NaN or infinity fails it)
        if found is None:
            if not np.isfinite(pts).all():
                self._last = self._near = None
                return math.sqrt(_closest(pts)[0]) - 2 * RADIUS
            few = len(pts) > PAIRWISE_UP_TO  # (up to it, every pair costs less than the movers')
            found = (few and self._few_moved(pts)) or self._whole(pts)
        if len(pts) > PAIRWISE_UP_TO:
            self._last = (pts.copy(), *found)
        return math.sqrt(found[0]) - 2 * RADIUS

    def _few_moved(self, pts: Points) -> tuple[float, int, int] | None:
        last, n = self._last, len(pts)
        if last is None or last[0].shape != pts.shape:
            return None
        before, best2, i, j = last
        movers = np.flatnonzero((before != pts).any(axis=1))  # (-0.0 for 0.0: the same squares)
        if 4 * len(movers) > n or i in movers or j in movers:
            return None
        if len(movers):
            xs, ys = pts[:, 0], pts[:, 1]
            dx = xs[movers, None] - xs[None, :]
            dy = ys[movers, None] - ys[None, :]
            squares = dx * dx + dy * dy
            squares[np.arange(len(movers)), movers] = np.inf  # (itself)
            k = int(squares.argmin())
            if squares.flat[k] < best2:
                best2, i, j = float(squares.flat[k]), int(movers[k // n]), k % n
        return best2, i, j

    def _near_ones(self, pts: Points) -> tuple[float, int, int] | None:
        near = self._near
        if near is None or near[0].shape != pts.shape:
            return None
        start, first, second, bound, scale = near
        # each robot is within hypot(dx, dy) <= sqrt(2) max(|dx|, |dy|) of its place in P0; NaN
        # (or an infinity: P0 is finite) fails the test below
        reach = 1.5 * float(np.abs(pts - start).max())
        if not reach < bound:
            return None
        _, _, squares = _pair_squares(pts, first, second)
        k = int(squares.argmin())
        best2 = float(squares[k])
        scale += reach  # |p| <= |p0| + reach, for every coordinate p of a robot (p0 of P0)
        if math.sqrt(best2) + 2 * reach * (1 + 1e-6) + 1e-6 + 1e-9 * scale >= bound:
            return None  # a pair that is not near might be closer
        self._served += 1
        return best2, int(first[k]), int(second[k])

    def _whole(self, pts: Points) -> tuple[float, int, int]:
        if len(pts) <= PAIRWISE_UP_TO:  # every pair: its squares give the near pairs too
            first, second, squares = _pair_squares(pts)
            k = int(squares.argmin())
            best2, i, j = float(squares[k]), int(first[k]), int(second[k])
        else:
            best2, i, j = _closest(pts)
        if self._near is not None and self._served:
            self._wait = NEAR_BACKOFF // 2
        elif self._near is not None:  # robots that moved too far for near pairs to pay: wait
            self._wait = min(2 * self._wait, NEAR_BACKOFF_MAX)
            self._backoff = self._wait
        self._near, self._served = None, 0
        if self._backoff:
            self._backoff -= 1
        else:
            bound = math.sqrt(best2) + NEAR_MARGIN
            scale = float(np.abs(pts).max())
            reach = bound * (1 + 1e-6) + 1e-9 * scale
            if len(pts) <= PAIRWISE_UP_TO:
                keep = squares <= reach * reach
                near_first, near_second = first[keep], second[keep]
            else:
                near_first, near_second = _within(pts, reach)
            self._near = (pts.copy(), near_first, near_second, bound, scale)
        return best2, i, j


def _within(pts: Points, reach: float) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """The pairs (i, j) of the (n, 2) `pts` whose centres may be `reach` apart or closer (every
    such pair, and maybe others), above PAIRWISE_UP_TO robots."""
    n = len(pts)
    order = np.argsort(pts[:, 0], kind="stable")
    along = pts[order, 0]
    counts = np.searchsorted(along, along + reach, side="right") - np.arange(n) - 1
    np.maximum(counts, 0, out=counts)  # the pairs (i, i + 1...) within reach along x
    total = int(counts.sum())
    first = np.repeat(np.arange(n), counts)
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    second = first + 1 + (np.arange(total) - starts)
    return order[first], order[second]


@functools.lru_cache(maxsize=16)
def _pairs(n: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """(i, j) of every pair i < j of n robots (read-only)."""
    first, second = np.triu_indices(n, 1)
    first.setflags(write=False)
    second.setflags(write=False)
    return first, second


def failures(round_no: int, line: Mapping[str, Any]) -> int:
    """How many computes of a round failed: the entries of its line's `failed`."""
    del round_no
    failed = line.get("failed")
    return 0 if failed is None or not isinstance(failed, Mapping) else len(failed)


def first_failure(round_no: int, line: Mapping[str, Any]) -> str | None:
    """The round's first failed compute (the least robot's), as the verdict names it: `robot 2
    in round 3: ViewError: ...` (`cycle` for an async run's line: it has a `look`); None if none
    failed."""
    failed = line.get("failed")
    if failed is None or not isinstance(failed, Mapping) or not failed:
        return None
    robot = min(failed, key=lambda r: int(r) if str(r).isdigit() else -1)
    word = "cycle" if "look" in line else "round"
    return f"robot {robot} in {word} {round_no}: {failed[robot]}"


_NUMBER: Final = {"$ref": "#/$defs/number", "minimum": 0}
_COUNT: Final = {"type": "integer", "minimum": 0}

# The figures of a run, in the sweep table's order of columns. A new one goes at the end.
FIGURES: tuple[Figure, ...] = (
    Figure(
        "status",
        str,
        "",
        "How the run ended: formed, stalled or max_rounds (a sweep row: error if it raised).",
        places=Place.RESULT_LINE | Place.CSV,
        kept_on_error=True,
        schema={"enum": ["formed", "stalled", "max_rounds"]},
    ),
    Figure(
        "rounds",
        int,
        "",
        "Rounds committed (async models: ended Look-Compute-Move cycles).",
        Summary.COUNT,
        Place.RESULT_LINE | Place.CSV,
        schema=_COUNT,
        csv="d",
    ),
    Figure(
        "time",
        float,
        "virtual time",
        "Async models: the virtual time the run ended at.",
        places=Place.RESULT_LINE | Place.CSV,
        optional=True,
        schema=_NUMBER,
        csv=".6f",
    ),
    Figure(
        "epochs",
        int,
        "",
        "Completed epochs (an epoch ends once every robot has been active since the last one "
        "ended; a crashed robot counts as active).",
        Summary.COUNT,
        Place.RESULT_LINE | Place.CSV,
        optional=True,  # records of early versions do not say
        schema=_COUNT,
        csv="d",
    ),
    Figure(
        "looks",
        int,
        "",
        "Looks over the run (robots activated, counted once a round each).",
        Summary.SUM,
        Place.CSV,
        csv="d",
    ),
    Figure(
        "moves",
        int,
        "",
        "Moves applied over the run (the number of round lines' move entries).",
        Summary.SUM,
        Place.RESULT_LINE | Place.CSV,
        schema=_COUNT,
        csv="d",
    ),
    Figure(
        "collisions",
        int,
        "",
        "Collision entries over the run.",
        Summary.SUM,
        Place.RESULT_LINE | Place.CSV,
        schema=_COUNT,
        csv="d",
    ),
    Figure(
        "total_distance",
        float,
        "robot radii",
        "The sum of every move's traveled (robot radii).",
        Summary.SUM,
        Place.RESULT_LINE | Place.CSV,
        schema=_NUMBER,
        csv=".6f",
    ),
    Figure(
        "bound",
        float,
        "robot radii",
        "Sweeps: the least total distance of any run from the start to the final spots "
        "(optimal assignment; blank without scipy).",
        places=Place.CSV,
        optional=True,
        csv=".6f",
        kept_on_error=True,
    ),
    Figure(
        "ratio",
        float,
        "",
        "Sweeps: total_distance / bound (blank when the bound is ~0 or unknown).",
        places=Place.CSV,
        optional=True,
        csv=".6f",
        kept_on_error=True,
    ),
    Figure(
        "wall_s",
        float,
        "s",
        "Sweeps: the run's wall-clock seconds.",
        places=Place.CSV,
        csv=".3f",
        kept_on_error=True,
    ),
    Figure(
        "min_gap",
        float,
        "robot radii",
        "The smallest rim-to-rim distance between two robots after a round (centres' distance "
        "less 2; negative: an overlap); over a run, its minimum over the rounds (how close the "
        "swarm came to a collision). Derived from the positions, never written: every record, "
        "old ones too, has it. None with one robot, or no round.",
        Summary.MIN,
        Place.CSV | Place.SUMMARY | Place.DASHBOARD | Place.DATAFRAME,
        optional=True,
        derive=min_gap,
        csv=".6f",
    ),
    Figure(
        "failures",
        int,
        "",
        "Computes that failed (the algorithm raised; the robot stayed): the entries of the round "
        "lines' `failed`, over the run. Derived from the round lines, never written on the "
        "result line: every record has it (0 before the field existed, as none was counted).",
        Summary.SUM,
        Place.CSV | Place.SUMMARY | Place.DATAFRAME,
        tally=failures,
        csv="d",
    ),
    Figure(
        "first_failure",
        str,
        "",
        "The run's first failed compute, as the verdict names it (`robot 2 in round 3: "
        "ViewError: ...`); None if no compute failed.",
        Summary.FIRST,
        Place.CSV | Place.SUMMARY,
        label="first failure",
        optional=True,
        tally=first_failure,
    ),
)


def place(where: Place, figures: Iterable[Figure] | None = None) -> tuple[Figure, ...]:
    """The figures (of FIGURES, read now: a test may add one) that show `where`, in order."""
    return tuple(f for f in (FIGURES if figures is None else figures) if where in f.places)


def derived_figures() -> tuple[Figure, ...]:
    """The figures that follow from each round: the positions after it (`derive`), or its line's
    other fields (`tally`)."""
    global _derived_cache  # made again when FIGURES is another tuple
    of, derived = _derived_cache
    if of is not FIGURES:  # FIGURES read now: a test may add one
        derived = tuple(f for f in FIGURES if f.derive is not None or f.tally is not None)
        _derived_cache = (FIGURES, derived)
    return derived


_derived_cache: tuple[tuple[Figure, ...] | None, tuple[Figure, ...]] = (None, ())


def derived(
    positions: Points, round_no: int = 0, line: Mapping[str, Any] | None = None
) -> dict[str, FigureValue]:
    """Every derived figure of a round, by name: of the (n, 2) positions after it, and of its
    number and line's other fields (`line`: `RoundEntry.extra`; None: a line with none)."""
    return {f.name: round_value(f, positions, round_no, line) for f in derived_figures()}


def round_value(
    figure: Figure, positions: Points, round_no: int = 0, line: Mapping[str, Any] | None = None
) -> FigureValue:
    """One derived figure's value for a round (see `derived`)."""
    if figure.derive is not None:
        return figure.derive(positions)
    assert figure.tally is not None, f"{figure.name} is not derived"
    return figure.tally(round_no, line or {})


def summarise(how: Summary, so_far: FigureValue, value: FigureValue) -> FigureValue:
    """`so_far` (the run's value before this round; None: no round yet) with one more round's
    `value` (None: the figure does not apply to it, and the run's value stays)."""
    if value is None:
        return so_far
    if so_far is None or how is _LAST:
        return value
    if how is _ADDED[0] or how is _ADDED[1]:  # (the members themselves: no text compared)
        return so_far + value  # type: ignore[operator]
    if how == _LAST:
        return value
    if how == _FIRST:
        return so_far
    if how == _MIN:  # (`min(so_far, value)`: the first of the least)
        return value if value < so_far else so_far  # type: ignore[operator]
    if how == _MAX:  # (`max(so_far, value)`: the first of the largest)
        return value if value > so_far else so_far  # type: ignore[operator]
    return so_far + value  # type: ignore[operator]


# (the members read once: an enum's member read from its class costs more than the test, and the
# folder summarises every derived figure every round)
_LAST, _FIRST, _MIN, _MAX = Summary.LAST, Summary.FIRST, Summary.MIN, Summary.MAX
_ADDED = (Summary.SUM, Summary.COUNT)


class RunFolder:
    """The run's values of the derived figures so far, fed the positions after each round and
    its line's other fields (a round that left every robot where it was, to the bit, reuses the
    last round's values of the positions: the world core feeds every committed round, and many
    change nothing)."""

    def __init__(self, values: Mapping[str, FigureValue] | None = None) -> None:
        self.values: dict[str, FigureValue] = dict(values or {})
        # the last positions' shape and bytes, and their values of the figures
        self._last: tuple[tuple[tuple[int, ...], bytes], dict[str, FigureValue]] | None = None
        self._gap = _GapMemo()  # min_gap kept from round to round

    def add(
        self, positions: Points, round_no: int = 0, line: Mapping[str, Any] | None = None
    ) -> None:
        pts = float64_array(positions)
        figures = derived_figures()
        seen = (pts.shape, pts.tobytes())  # the positions to the bit
        last = self._last
        if last is not None and last[0] == seen:
            rounds = last[1]  # (the same bits: the same values)
        else:
            rounds = {}
            for f in figures:
                derive = f.derive
                if derive is not None:
                    rounds[f.name] = self._gap.min_gap(pts) if derive is min_gap else derive(pts)
            self._last = (seen, rounds)
        values, of_line = self.values, line or {}
        for f in figures:
            name, tally = f.name, f.tally
            value = rounds.get(name) if tally is None else tally(round_no, of_line)
            if value is not None:
                values[name] = summarise(f.summary, values.get(name), value)
            elif name not in values:  # (a value None leaves the run's as it was)
                values[name] = None

    def snapshot(self) -> dict[str, FigureValue]:
        global _names_cache  # made again when the derived figures are another tuple
        figures = derived_figures()
        of, names = _names_cache
        if of is not figures:
            names = tuple(f.name for f in figures)
            _names_cache = (figures, names)
        values = self.values
        if len(values) == len(names) and tuple(values) == names:  # (every one, in order)
            return dict(values)
        return {name: values.get(name) for name in names}


_names_cache: tuple[tuple[Figure, ...] | None, tuple[str, ...]] = (None, ())


class RoundLine(Protocol):
    """A round of a record as the derived figures read it (`RoundEntry`)."""

    @property
    def round(self) -> int: ...

    @property
    def positions(self) -> Points: ...

    @property
    def extra(self) -> Mapping[str, Any]: ...


def run_derived(rounds: Iterable[Points | RoundLine]) -> dict[str, FigureValue]:
    """The run's values of the derived figures from each of its rounds: its line (a record's
    `RoundEntry`), or the positions after it alone (a line without other fields)."""
    folder = RunFolder()
    for entry in rounds:
        if isinstance(entry, np.ndarray) or not hasattr(entry, "extra"):
            folder.add(np.asarray(entry, dtype=np.float64))
        else:
            folder.add(entry.positions, entry.round, entry.extra)
    return folder.snapshot()


def summary_values(values: Mapping[str, FigureValue]) -> dict[str, FigureValue]:
    """The run's derived figures the summary, `--json` and `fatswarm.summary` show, by name
    (None: it does not apply, e.g. no round)."""
    return {f.name: values.get(f.name) for f in derived_figures() if Place.SUMMARY in f.places}


def known_numbers(values: Mapping[str, FigureValue]) -> dict[str, float]:
    """The numbers among `values` (those known: no None, no text), as floats."""
    return {k: float(v) for k, v in values.items() if isinstance(v, int | float) and v is not True}


def cell(figure: Figure, value: FigureValue) -> str:
    """A sweep table's cell of `figure`: blank for None, else formatted as `figure.csv` says."""
    if value is None:
        return ""
    return format(value, figure.csv) if figure.csv else str(value)


def shown(value: FigureValue) -> str:
    """A figure in the summary text and the dashboard: three decimals, `-` for None."""
    if value is None:
        return "-"
    return f"{value:.3f}" if isinstance(value, float) else str(value)


def names(figures: Sequence[Figure]) -> tuple[str, ...]:
    return tuple(f.name for f in figures)


__all__ = [
    "FIGURES",
    "PAIRWISE_UP_TO",
    "RADIUS",
    "Derive",
    "Figure",
    "FigureValue",
    "Place",
    "RoundLine",
    "RunFolder",
    "Summary",
    "Tally",
    "cell",
    "derived",
    "derived_figures",
    "failures",
    "first_failure",
    "known_numbers",
    "min_gap",
    "names",
    "place",
    "round_value",
    "run_derived",
    "shown",
    "summarise",
    "summary_values",
]
