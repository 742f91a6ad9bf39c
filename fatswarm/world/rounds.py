"""The world's model for the round schedulers: a round opens for an active set, its held moves are
applied at once through physics when it commits, and the round becomes one record line.

The non-rigid adversary cuts moves and the crash adversary stops robots here (`world.faults`);
a robot whose agent stays gone counts as crashed by the rule of the record's `crashed` field.
"""

from __future__ import annotations

from collections.abc import Mapping
from itertools import compress
from typing import Any

import numpy as np

from fatswarm.domain.draws import cut_fraction
from fatswarm.domain.path import Path, Points, transform
from fatswarm.world.effects import Committed
from fatswarm.world.faults import crash_after, cut_path, stuck_in
from fatswarm.world.model import Answer, Books, RoundBooking
from fatswarm.world.physics import RoundOutcome, apply_lines, apply_round
from fatswarm.world.protocol import Begin, Commit
from fatswarm.world.record import LineMoves, round_entry


class Rounds:
    """Rounds of physics: `begin` opens round k for its active set, `commit` applies its moves."""

    def __init__(self, books: Books) -> None:
        self.books = books
        # the run's settings that hold for every round (looked up once)
        self._rigid = books.setup.non_rigid is None
        self._crash_limit = crash_after(books.setup.n)

    def begin(self, req: Begin) -> Answer:
        w = self.books
        if req.round != w.committed + 1:
            return f"next round is {w.committed + 1}, not {req.round}", False
        if not req.active or req.active[-1] >= w.setup.n:
            return "active set empty or not robots of this run", False
        if w.open_round == req.round and w.active == req.active:
            return None, False  # a coordinator retrying: keep what is held
        if req.active is not w.active and req.active != w.active:
            w.active_set, w.active = frozenset(req.active), req.active
        # (else the last round's active robots: their set, and the very tuple, kept)
        if w.open_round:  # a round was open: what it held goes (else its commit cleared it)
            w.looked, w.held, w.failed = set(), {}, {}
        w.open_round, w.noticed = req.round, None
        # the live ones (every one: the set as it is)
        w.missing = (
            set(w.active_set)
            if all(w.alive)
            else set(compress(req.active, map(w.alive.__getitem__, req.active)))
        )
        return None, True

    def commit(self, req: Commit) -> Answer:
        w = self.books
        if req.round == w.committed and not w.open_round:
            return None, False  # the reply to a commit was lost: it is durable
        if req.round != w.open_round:
            return f"round {req.round} is not open", False
        self.commit_open_round()
        return None, True

    def reply_fields(self) -> dict[str, Any]:
        return {}

    def result_fields(self) -> dict[str, Any]:
        return {}

    def time(self) -> float | None:
        return None

    def commit_open_round(self) -> None:
        """Apply the held moves through physics, emit the round's record line, then book it.
        Where every move held is a straight line held as arrays (`Books.held_lines`) and no
        adversary cuts them, the round goes to physics as arrays (`apply_lines`) and on to the
        round line and the books as arrays (`LineMoves`), no Path made for any robot."""
        w = self.books
        round_no, before = w.open_round, w.positions
        stuck = stuck_in(w.crash_plan, round_no) if w.crash_plan else []
        gone = w.stuck | frozenset(stuck) if stuck else w.stuck  # their moves are not applied
        lines = w.held_lines() if self._rigid else None
        line_moves: LineMoves | None = None
        paths: Mapping[int, Path] = {}
        if lines is not None:
            movers, ends = lines
            if gone and len(movers):
                keep = ~np.isin(movers, np.fromiter(gone, dtype=np.intp, count=len(gone)))
                movers, ends = movers[keep], ends[keep]
            # world frame: transform(path, start, False)'s `1.0 * x + start`, and 1.0 * x is x
            ends = ends + (before if len(movers) == len(before) else before[movers])
            cut: list[int] = []
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
        failed = dict(sorted(w.failed.items())) if w.failed else {}
        for robot in gone if failed else ():
            failed.pop(robot, None)
        colours = w.held_colours
        relit = False
        if colours:  # (none: no colour shown changes, nothing to renew)
            w.held_colours = {}
            relit = w.looks.show(colours, skip=gone)  # as the moves start
        points = w.looks.points  # point bodies: no contact (world/physics.py)
        traveled: Mapping[int, float] | None
        if lines is not None:  # physics' traveled is in the movers' order: the line's arrays
            outcome = (
                apply_lines(before, movers, ends, points=points)
                if len(movers)
                else RoundOutcome(before.copy())
            )
            covered = np.fromiter(outcome.traveled.values(), dtype=np.float64, count=len(movers))
            line_moves, traveled = LineMoves(movers, ends, covered), None
        elif paths:
            outcome = apply_round(before, paths, points=points)
            traveled = {r: float(outcome.traveled.get(r, 0.0)) for r in paths}
        else:
            outcome, traveled = RoundOutcome(before.copy()), {}
        after = np.asarray(outcome.positions, dtype=np.float64)
        moved: Mapping[int, Path] | LineMoves = paths if line_moves is None else line_moves
        holding = w.held_robots()
        timed_out = (  # (the held are active: as many as the active are every one)
            []
            if len(holding) == len(w.active_set) or holding >= w.active_set
            else [r for r in w.active if r not in holding]
        )
        w.last_timed_out = tuple(timed_out)
        down, back = self._crashes(round_no)
        entry = round_entry(
            round_no,
            w.active,
            moved,
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
                    paths=moved,
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
        crashed, gone_since = w.tracker.crashed, w.gone_since
        if gone_since.count(None) == len(gone_since):  # every agent there (a lock step's)
            down = []
        else:
            limit = self._crash_limit
            down = [
                r
                for r, since in enumerate(gone_since)
                if since is not None and round_no - since >= limit and r not in crashed
            ]
        back = sorted(r for r in crashed if w.alive[r] and r not in w.stuck) if crashed else []
        return down, back


__all__ = ["Rounds"]
