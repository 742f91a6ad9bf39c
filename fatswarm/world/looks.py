"""What each robot is shown, and the lights it shows: the world's side of the robot model.

The world alone decides what a robot sees (sight, obstruction: `world.sight`), in which frame
(`fatswarm.domain.frames`), how far off (`--noise`), and which colours it reads (`--lights`); it
keeps every robot's colour and the views it served when `--record-views` asks. Pure: the world
core holds one of these.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.draws import look_noise, view_order, view_orders
from fatswarm.domain.frames import Frame, FrameRows, draw_frame
from fatswarm.domain.path import Path, Points
from fatswarm.domain.robot_model import Bodies, FrameChange, Lights, RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.world.sight import seen

Seen = tuple[Points, tuple[int, ...] | None, int | None]
"""What one Look shows: the view in the looker's frame, the colours it reads of those it sees
(lined up with the view; None if it reads none) and its own (None if it cannot read it)."""

AHEAD_LIMIT = 1 << 20
"""`Looks.prepare` builds a round's views at once up to this many points (16 MB); past it, each
view alone."""
ORDERS_AHEAD = 1 << 15
"""`Looks.views_at_once` draws every robot's view orders of rounds ahead, up to this many indices
(256 kB), once rounds follow one another and two rounds or more fit: one call of each numpy
operation for all of them (small swarms); 2 rounds the first time, then twice as many as the
time before, up to ROUNDS_AHEAD."""
ROUNDS_AHEAD = 64
"""At most this many rounds' view orders drawn at once (`ORDERS_AHEAD`)."""


Column = NDArray[np.float64]  # (t, 1)


@dataclass(frozen=True, slots=True, eq=False)  # holds arrays
class _Lookers:
    """The robots of a round's views at once (`Looks.views_at_once`) and their frames: `rows`
    their ids (None: every robot, in order), `sign` (m, 1) -1.0 where a frame is a mirror alone,
    else 1.0 (None: no mirror alone), `turned` the rows whose frame turns, with each one's
    mirror factor, cosine and sine as columns (None: no frame turns)."""

    robots: tuple[int, ...]
    rows: NDArray[np.intp] | None
    sign: Column | None
    turned: tuple[NDArray[np.intp], Column, Column, Column] | None


def _turned_rows(
    frames: Sequence[Frame], turned: list[int]
) -> tuple[NDArray[np.intp], Column, Column, Column]:
    """The rows `turned` of `frames` (those whose frame turns), each one's mirror factor (-1.0
    where mirrored), cosine and sine of its rotation, as `Frame.to_local` takes them."""
    return (
        np.asarray(turned, dtype=np.intp),
        np.array([-1.0 if frames[i].mirror else 1.0 for i in turned])[:, None],
        np.array([math.cos(frames[i].rotation) for i in turned])[:, None],
        np.array([math.sin(frames[i].rotation) for i in turned])[:, None],
    )


class Looks:
    """Builds each Look's view in the looker's frame; keeps the colours and the views served."""

    def __init__(
        self, model: RobotModel, setting: Configured, n: int, seed: int, record_views: bool
    ) -> None:
        self.model, self.n, self.seed = model, n, seed
        self.palette = setting.colours
        self.record_views = record_views
        # point bodies: robots may share a point; an algorithm without multiplicity detection
        # sees each occupied point once (and not its own: docs/model.md, "Bodies")
        self.points = model.bodies is Bodies.POINTS
        self.once = self.points and not setting.assumptions.multiplicity
        self._fixed: list[Frame] | None = (
            [draw_frame(model, seed, r, 0) for r in range(n)]
            if model.frame_change is FrameChange.FIXED
            else None
        )
        self._fixed_sign = None if self._fixed is None else _mirror_signs(self._fixed)
        self._fixed_turns = self._fixed is not None and any(f.rotation for f in self._fixed)
        self._fixed_rows = None if self._fixed is None else FrameRows.of(self._fixed)
        self._everyone = list(range(n))
        self._everyone_ids = tuple(self._everyone)
        # the frames of the robots that looked last (`views_at_once`), while frames are fixed
        self._lookers: _Lookers | None = None
        # every robot's view orders of the rounds from the first, drawn at once (`_orders`),
        # and the round whose views were built last
        self._orders_ahead: tuple[int, list[np.ndarray]] | None = None
        self._last_round = -1
        # every robot's colour (palette index; the first at the start); none without lights
        self.colours: list[int] | None = [0] * n if self.palette else None
        # whether a view is every other robot, exact, with no colours and nothing recorded
        self.plain = (
            model.sees_all
            and not model.noise
            and self.colours is None
            and not record_views
            and not self.once
        )
        self.views: dict[int, list[int]] = {}  # robot -> the ids it saw, of Looks not recorded yet
        # views built ahead for one round and one configuration (`prepare`): robot -> its view
        self._ahead: tuple[int, Points, dict[int, Points]] | None = None

    def frame(self, robot: int, look_round: int) -> Frame:
        """Robot `robot`'s frame for its Look of round `look_round`."""
        if self._fixed is not None:
            return self._fixed[robot]
        return draw_frame(self.model, self.seed, robot, look_round)

    def view(self, positions: Points, robot: int, look_round: int) -> Seen:
        """What robot `robot`'s Look shows at `positions` in round `look_round`."""
        if self.plain:
            # the paper's model: every other robot (the fast path of every Look of every run)
            ahead = self._ahead
            if ahead is not None and ahead[0] == look_round and ahead[1] is positions:
                view = ahead[2].pop(robot, None)
                if view is not None:
                    return view, None, None
            others = np.concatenate((positions[:robot], positions[robot + 1 :]))
            others -= positions[robot]
            order = view_order(self.seed, look_round, robot, len(others))
            return self.frame(robot, look_round).to_local(others[order]), None, None
        ids = self.shown(positions, robot, look_round)
        if self.record_views:
            self.views[robot] = sorted(int(i) for i in ids)
        view = self.frame(robot, look_round).to_local(positions[ids] - positions[robot])
        if self.model.noise:  # inaccurate sensors: each position seen off by its own error
            view += self.model.noise * look_noise(self.seed, robot, look_round, len(view))
        if self.colours is None:
            return view, None, None
        lights = self.model.lights
        shown = None if lights is Lights.INTERNAL else tuple(self.colours[i] for i in ids)
        own = None if lights is Lights.EXTERNAL else self.colours[robot]
        return view, shown, own

    def prepare(self, positions: Points, look_round: int, robots: Sequence[int]) -> None:
        """Build the views of `robots` for their Looks of round `look_round` at `positions` in one
        pass (`views`), for `view` to hand out."""
        self._ahead = None
        views = self.views_at_once(positions, look_round, robots)
        if views is not None:
            self._ahead = (look_round, positions, dict(zip(robots, views, strict=True)))

    def views_at_once(
        self, positions: Points, look_round: int, robots: Sequence[int]
    ) -> Points | None:
        """(k, n-1, 2): the views of `robots`' Looks of round `look_round` at `positions`, row i
        robot robots[i]'s, each the very array `view` would build alone (the same differences,
        `view_orders` gives each row `view_order`'s order, the same frame, the same operations);
        None unless the model's views are all alike (`plain`) and fit AHEAD_LIMIT."""
        k = self.n - 1
        if not self.plain or not robots or len(robots) * k > AHEAD_LIMIT:
            return None
        lookers = self._lookers_of(tuple(robots), look_round)
        order = self._orders(look_round, lookers)  # indices among all robots
        # each point as one complex number (a column: what each row's differences are of): one
        # gather, and a complex difference is the two coordinates' differences, the very
        # operations (faster than (m, k, 2) broadcast)
        table = np.ascontiguousarray(positions, dtype=np.float64).view(np.complex128)
        pairs = table.take(order)  # (the column taken as flat)
        pairs -= table if lookers.rows is None else table[lookers.rows]
        rel: Points = pairs.view(np.float64).reshape(len(order), k, 2)
        if lookers.sign is not None:  # x * 1.0 is x, bit for bit: the mirror of to_local alone
            rel[:, :, 0] *= lookers.sign
        if lookers.turned is not None:  # Frame.to_local's operations, on every turned row at once
            at, mirror, c, s = lookers.turned
            x = rel[at, :, 0] * mirror  # -x where mirrored, as to_local's `*= -1.0`
            y = rel[at, :, 1]
            rel[at, :, 0] = c * x - s * y
            rel[at, :, 1] = s * x + c * y
        return rel

    def _orders(self, look_round: int, lookers: _Lookers) -> np.ndarray:
        """(m, n-1): `view_orders` of `lookers` in round `look_round` (among all robots): rows of
        the rounds drawn ahead (`ORDERS_AHEAD`) where round after round asks, else drawn now."""
        k = self.n - 1
        follows, self._last_round = look_round == self._last_round + 1, look_round
        ahead = self._orders_ahead
        if ahead is not None and 0 <= look_round - ahead[0] < len(ahead[1]):
            orders: np.ndarray = ahead[1][look_round - ahead[0]]
            return orders if lookers.rows is None else orders[lookers.rows]
        if not follows or not 0 < 2 * self.n * k <= ORDERS_AHEAD:
            return view_orders(self.seed, look_round, lookers.robots, k, True)
        # twice as many rounds as the last time: no more drawn in vain than were used
        rounds = min(ROUNDS_AHEAD, ORDERS_AHEAD // (self.n * k), 2 * len(ahead[1]) if ahead else 2)
        orders = view_orders(self.seed, look_round, self._everyone_ids, k, True, rounds)
        self._orders_ahead = (look_round, list(orders.reshape(rounds, self.n, k)))
        return orders[: self.n] if lookers.rows is None else orders[lookers.rows]

    def _lookers_of(self, robots: tuple[int, ...], look_round: int) -> _Lookers:
        """What `views_at_once` needs of `robots`' frames for round `look_round`: kept while the
        same robots look in frames drawn once (every fsync round)."""
        kept = self._lookers
        if kept is not None and kept.robots == robots:
            return kept
        everyone = len(robots) == self.n and robots == self._everyone_ids
        rows = None if everyone else np.asarray(robots, dtype=np.intp)
        frames: Sequence[Frame]
        if self._fixed is not None and self._fixed_sign is not None:  # drawn once
            sign = self._fixed_sign if rows is None else self._fixed_sign[rows]
            frames = [self._fixed[robot] for robot in robots] if self._fixed_turns else ()
        else:
            frames = [self.frame(robot, look_round) for robot in robots]
            sign = _mirror_signs(frames)
        turned = [i for i, frame in enumerate(frames) if frame.rotation]
        lookers = _Lookers(
            robots,
            rows,
            sign[:, None] if bool((sign < 0.0).any()) else None,
            _turned_rows(frames, turned) if turned else None,
        )
        if self._fixed is not None:
            self._lookers = lookers
        return lookers

    def shown(self, positions: Points, robot: int, look_round: int) -> np.ndarray:
        """The ids of the robots robot `robot`'s Look of round `look_round` shows at `positions`,
        in the order of its view's rows (`view`; the fast path's too: every other robot)."""
        ids = self.seen_by(positions, robot)
        ids = ids[view_order(self.seed, look_round, robot, len(ids))]
        if self.once:
            ids = _each_point_once(positions, robot, ids)
        return ids

    def seen_by(self, positions: Points, robot: int) -> np.ndarray:
        """The ids of the robots `robot` sees now, ascending."""
        if self.model.sees_all:
            return np.delete(np.arange(self.n), robot)
        return seen(positions, robot, self.model.visibility, self.model.sight, points=self.points)

    def to_world(self, robot: int, look_round: int, path: Path) -> Path:
        """A path robot `robot` computed in the frame of its Look, in world axes."""
        return self.frame(robot, look_round).path_to_world(path)

    def lines_to_world(self, robots: Sequence[int], look_round: int, ends: Points) -> Points:
        """(m, 2): row i the end of a straight line robot robots[i] computed in the frame of its
        Look of round `look_round` (relative to it), in world axes: `to_world` of each one's
        `Path((Line(ends[i]),))`, the same bits, at once (`FrameRows.lines_to_world`)."""
        if self._fixed_rows is not None:  # every robot's frame drawn once: its row
            whole = len(robots) == self.n and robots == self._everyone
            rows = self._fixed_rows
            if not whole:
                rows = rows.take(np.asarray(robots, dtype=np.intp))
        else:  # a frame per Look: drawn per robot, then turned as arrays
            rows = FrameRows.of([self.frame(robot, look_round) for robot in robots])
        return rows.lines_to_world(ends)

    def show(self, colours: Mapping[int, int], skip: Collection[int] = ()) -> bool:
        """The robots of `colours` show their new colour now (a move starts), but those of
        `skip` (crashed: they act no more); True if any colour changed (the configuration did)."""
        changed = False
        if self.colours is not None:
            for robot, colour in colours.items():
                if robot not in skip and self.colours[robot] != colour:
                    self.colours[robot], changed = colour, True
        return changed

    def colour(self, robot: int) -> int | None:
        """Robot `robot`'s colour now (None without lights)."""
        return None if self.colours is None else self.colours[robot]

    def names(self) -> tuple[str, ...]:
        """Every robot's colour name now (() without lights)."""
        return () if self.colours is None else tuple(self.palette[c] for c in self.colours)

    def restore(self, names: object) -> bool:
        """Every robot's colour as a resumed record's line gives it (`lights`), if it does; True
        if any changed."""
        if self.colours is None or not isinstance(names, list) or len(names) != self.n:
            return False
        colours = [self.palette.index(c) if c in self.palette else 0 for c in names]
        changed, self.colours = colours != self.colours, colours
        return changed

    def round_fields(self, lookers: Iterable[int]) -> dict[str, Any]:
        """A record line's model fields: every robot's colour now (`lights`), and the views the
        robots of `lookers` were served (`views`, with --record-views), which are then dropped."""
        extra: dict[str, Any] = {}
        if self.colours is not None:
            extra["lights"] = list(self.names())
        if self.record_views:
            extra["views"] = {str(r): self.views.pop(r, []) for r in sorted(lookers)}
        return extra


def _each_point_once(positions: Points, robot: int, ids: np.ndarray) -> np.ndarray:
    """`ids` (in view order) less every robot at a point already shown, or at `robot`'s own
    point: what a robot without multiplicity detection sees of point robots. Positions are on the
    grid, so robots at one point have the very same coordinates."""
    own = (float(positions[robot, 0]), float(positions[robot, 1]))
    shown: set[tuple[float, float]] = {own}
    keep = []
    for i in ids.tolist():
        point = (float(positions[i, 0]), float(positions[i, 1]))
        if point not in shown:
            shown.add(point)
            keep.append(i)
    return np.asarray(keep, dtype=ids.dtype)


def _mirror_signs(frames: Sequence[Frame]) -> np.ndarray:
    """-1.0 for each frame that is a mirror alone, else 1.0: what `Looks.prepare` multiplies a
    view's x by before a rotation, if any, turns it."""
    return np.array([-1.0 if f.mirror and not f.rotation else 1.0 for f in frames])


__all__ = ["Looks", "Seen"]
