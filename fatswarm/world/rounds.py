"""The world's model for the round schedulers: a round opens for an active set, its held moves are
applied at once through physics when it commits, and the round becomes one record line.

The non-rigid adversary cuts moves and the crash adversary stops robots here (`world.faults`);
a robot whose agent stays gone counts as crashed by the rule of the record's `crashed` field.
"""

from __future__ import annotations

from collections.abc import ItemsView, Iterator, KeysView, Mapping, ValuesView
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.draws import cut_fraction
from fatswarm.domain.path import Line, Path, Points, transform
from fatswarm.world.effects import Committed
from fatswarm.world.faults import crash_after, cut_path, stuck_in
from fatswarm.world.model import Books, RoundBooking
from fatswarm.world.physics import RoundOutcome, apply_round
from fatswarm.world.protocol import Begin, Commit, ControlReply
from fatswarm.world.record import round_entry


class Rounds:
    """Rounds of physics: `begin` opens round k for its active set, `commit` applies its moves."""

    def __init__(self, books: Books) -> None:
        self.books = books

    def begin(self, req: Begin) -> tuple[ControlReply, bool]:
        w = self.books
        if req.round != w.committed + 1:
            return w.reply(False, f"next round is {w.committed + 1}, not {req.round}"), False
        if not req.active or req.active[-1] >= w.setup.n:
            return w.reply(False, "active set empty or not robots of this run"), False
        if w.open_round == req.round and w.active == req.active:
            return w.reply(True), False  # a coordinator retrying: keep what is held
        w.open_round, w.active = req.round, req.active
        w.active_set = frozenset(req.active)
        w.looked, w.held, w.noticed, w.failed = set(), {}, None, {}
        w.missing = {r for r in req.active if w.alive[r]}
        return w.reply(True), True

    def commit(self, req: Commit) -> tuple[ControlReply, bool]:
        w = self.books
        if req.round == w.committed and not w.open_round:
            return w.reply(True), False  # the reply to a commit was lost: it is durable
        if req.round != w.open_round:
            return w.reply(False, f"round {req.round} is not open"), False
        self.commit_open_round()
        return w.reply(True), True

    def reply_fields(self) -> dict[str, Any]:
        return {}

    def result_fields(self) -> dict[str, Any]:
        return {}

    def time(self) -> float | None:
        return None

    def commit_open_round(self) -> None:
        """Apply the held moves through physics, emit the round's record line, then book it.
        Where every move held is a straight line held as arrays (`Books.held_lines`) and no
        adversary cuts them, the round goes to physics as arrays (`apply_lines`), its paths a
        `LinePaths` that makes a Path only for what reads one."""
        w = self.books
        round_no, before = w.open_round, w.positions
        stuck = stuck_in(w.crash_plan, round_no)
        gone = w.stuck | frozenset(stuck)  # a crashed robot's moves are not applied
        lines = w.held_lines() if w.setup.non_rigid is None else None
        paths: Mapping[int, Path]
        if lines is not None:
            movers, ends = lines
            if gone and len(movers):
                keep = ~np.isin(movers, np.fromiter(gone, dtype=np.intp, count=len(gone)))
                movers, ends = movers[keep], ends[keep]
            # world frame: transform(path, start, False)'s `1.0 * x + start`, and 1.0 * x is x
            ends = ends + (before if len(movers) == len(before) else before[movers])
            paths, cut = LinePaths(movers, ends), []
        else:
            at = before.tolist()  # Python floats: the same values, read faster than numpy scalars
            held = {  # the lockstep runner applies and records non-empty paths only: so do we
                robot: transform(path, (at[robot][0], at[robot][1]), False)
                for robot, path in sorted(w.held.items())
                if path
            }
            for robot in gone:
                held.pop(robot, None)
            cut = self._cut(round_no, before, held)
            paths = held
        failed = dict(sorted(w.failed.items()))
        for robot in gone:
            failed.pop(robot, None)
        colours, w.held_colours = w.held_colours, {}
        relit = w.looks.show(colours, skip=gone)  # as the moves start
        points = w.looks.points  # point bodies: no contact (world/physics.py)
        if not paths:
            outcome = RoundOutcome(before.copy())
        elif isinstance(paths, LinePaths):
            outcome = apply_lines(before, paths.movers, paths.ends, points=points)
        else:
            outcome = apply_round(before, paths, points=points)
        after = np.asarray(outcome.positions, dtype=np.float64)
        if isinstance(paths, LinePaths):  # apply_lines: every mover's, as apply_round gives it
            traveled = outcome.traveled
        else:
            traveled = {r: float(outcome.traveled.get(r, 0.0)) for r in paths}
        holding = w.held_robots()
        timed_out = [] if holding >= w.active_set else [r for r in w.active if r not in holding]
        w.last_timed_out = tuple(timed_out)
        down, back = self._crashes(round_no)
        entry = round_entry(
            round_no,
            w.active,
            paths,
            traveled,
            after,
            outcome.collisions,
            robots=(
                ("timed_out", timed_out),
                ("crashed", down),
                ("recovered", back),
                ("cut", cut),
                ("crash", stuck),
            ),
            model=w.looks.round_fields(w.looked),
            failed=failed,
        )
        try:  # the round is the record's even when the goal raises while it is booked
            w.account(
                RoundBooking(
                    round=round_no,
                    active=w.active,
                    paths=paths,
                    timed_out=timed_out,
                    before=before,
                    after=after,
                    traveled=traveled,
                    collisions=outcome.collisions,
                    crashed=down,
                    recovered=back,
                    stuck=stuck,
                    relit=relit,
                    lengths=outcome.lengths,
                    line=entry.extra,
                )
            )
        finally:
            w.emit(Committed(entry, w.tracker.snapshot()))
        w.open_round, w.looked, w.held, w.missing, w.failed = 0, set(), {}, set(), {}
        if w.tracker.status is not None:
            w.finish()

    def _cut(self, round_no: int, before: Points, paths: dict[int, Path]) -> list[int]:
        """Non-rigid moves: the adversary stops each path of `paths` (world frame, replaced in
        place) where `cut_path` says; returns the robots it stopped short."""
        setup = self.books.setup
        delta = setup.non_rigid
        if delta is None:
            return []
        cut = []
        for robot, path in paths.items():
            start = (float(before[robot, 0]), float(before[robot, 1]))
            short = cut_path(start, path, delta, cut_fraction(setup.seed, round_no, robot))
            if short is not path:
                paths[robot] = short
                cut.append(robot)
        return cut

    def _crashes(self, round_no: int) -> tuple[list[int], list[int]]:
        """(robots that count as crashed from this round, crashed robots whose agent is back):
        the rule of the record's `crashed` and `recovered` round fields (README, "Faults")."""
        w = self.books
        limit = crash_after(w.setup.n)
        crashed, gone_since = w.tracker.crashed, w.gone_since
        down = (
            []
            if gone_since.count(None) == len(gone_since)  # every agent there (a lock step's)
            else [
                r
                for r, since in enumerate(gone_since)
                if since is not None and round_no - since >= limit and r not in crashed
            ]
        )
        back = sorted(r for r in crashed if w.alive[r] and r not in w.stuck) if crashed else []
        return down, back


class LinePaths(Mapping[int, Path]):
    """A round's moves that are all straight lines, as a mapping robot -> world path (what the
    round line and the books take): `movers` (m,) ascending, `ends` (m, 2) their lines' ends,
    world frame. Each Path, `Path((Line((x, y)),))` of Python floats, is made the first time a
    path is read, all at once; the keys, their number and membership make none."""

    __slots__ = ("_keys", "_paths", "ends", "movers")

    def __init__(self, movers: NDArray[np.intp], ends: Points) -> None:
        self.movers, self.ends = movers, ends
        self._keys: dict[int, None] = dict.fromkeys(movers.tolist())
        self._paths: dict[int, Path] | None = None

    def _made(self) -> dict[int, Path]:
        if self._paths is None:
            self._paths = {
                robot: Path((Line((x, y)),))
                for robot, (x, y) in zip(self._keys, self.ends.tolist(), strict=True)
            }
        return self._paths

    def __getitem__(self, robot: int) -> Path:
        return self._made()[robot]

    def __iter__(self) -> Iterator[int]:
        return iter(self._keys)

    def __len__(self) -> int:
        return len(self._keys)

    def __contains__(self, robot: object) -> bool:
        return robot in self._keys

    def keys(self) -> KeysView[int]:
        return self._keys.keys()

    def items(self) -> ItemsView[int, Path]:
        return self._made().items()

    def values(self) -> ValuesView[Path]:
        return self._made().values()


# SHIM (arrays branch): physics' `apply_lines` (fatswarm/world/physics.py) comes with the physics
# branch; until it is merged this stand-in makes the Paths and calls apply_round, the very round.
# At merge, delete it and import `apply_lines` from fatswarm.world.physics instead.
def apply_lines(
    positions: Points, movers: NDArray[np.intp], ends: Points, *, points: bool = False
) -> RoundOutcome:
    """`apply_round(positions, {movers[i]: Path((Line(ends[i]),))}, points=points)`."""
    paths = {
        robot: Path((Line((x, y)),))
        for robot, (x, y) in zip(movers.tolist(), ends.tolist(), strict=True)
    }
    return apply_round(positions, paths, points=points)


__all__ = ["LinePaths", "Rounds", "apply_lines"]
