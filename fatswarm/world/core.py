"""The world's state machine: looks, moves, control requests and commits, with no I/O at all.

Each call handles one event and queues what the shell is to do (`world.effects`: append a line to
the run record, log a note); the shell takes them with `take_effects` and performs them. The
algorithm comes in configured: the core loads nothing.

The Zenoh shell (world/service.py) and the in-process lock step (deploy/engine/lockstep.py) drive
this very core, so a networked run and a lock-step run of the same configuration are one
computation; they read it through `WorldCore.readout` alone (world/readout.py). Physics and the
end test are the core's (`world.physics.apply_round`, `world.progress`).
"""

from __future__ import annotations

import functools
import math
from collections import Counter
from collections.abc import Collection, Iterable, KeysView, Mapping, Sequence
from dataclasses import dataclass
from itertools import compress
from typing import Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.draws import crash_plan
from fatswarm.domain.figures import known_numbers
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import STAY, Line, Path, Points, path_length
from fatswarm.domain.seam import AlgorithmFailure, Configured, failure_kind
from fatswarm.domain.tolerance import snap
from fatswarm.world.effects import Effect, Level, Note, Rejected
from fatswarm.world.faults import crash_after, stuck_in
from fatswarm.world.instants import Instants, async_setup, is_async
from fatswarm.world.looks import Looks, Seen
from fatswarm.world.model import Model, RoundBooking
from fatswarm.world.observers import AgentInfo, WorldState
from fatswarm.world.progress import ProgressTracker
from fatswarm.world.protocol import (
    Begin,
    ControlReply,
    ControlRequest,
    Hello,
    LookRequest,
    MovesHeld,
    MoveSubmitted,
    Snapshot,
)
from fatswarm.world.readout import CoreReadout
from fatswarm.world.record import Header, LineMoves, Result, RoundEntry, RunRecord
from fatswarm.world.rounds import Rounds
from fatswarm.world.setup import WorldSetup

FIRST_LOOK: Final = LookRequest()  # an agent's first Look: any round
_RUNNING: Final = Status.RUNNING  # (read off its Enum class once: ~20x a global's cost a read)
# The held move of a robot whose line is kept among the held lines (`HeldLines`) until `held` is
# read (then its Path takes this place): never seen outside the core; a NaN path, were it to leak,
# physics refuses loudly.
_IN_LINES: Final = Path((Line((math.nan, math.nan)),))


@functools.lru_cache(maxsize=8)
def _every_robot(n: int) -> tuple[range, tuple[int, ...]]:
    """Every robot of an n-robot run, as `range(n)` (how `account` tells the tracker that every
    robot moved) and as the tuple (0, ..., n-1): made once."""
    return range(n), tuple(range(n))


@dataclass(slots=True)
class HeldLines:
    """Moves of the open round held at once (`WorldCore.hold_lines`): robots[i] goes in a straight
    line to ends[i] (world axes, relative to it)."""

    robots: Sequence[int]  # in the order they were held (the active tuple itself, if all)
    ends: Points  # (m, 2)


class WorldCore:
    """The world's state and its answers to looks, moves and control requests (no I/O at all).

    Its model of time (`world.model`: rounds, or async instants) opens and commits; the core keeps
    the books. Robot identity comes from the key a message arrives on and must match the robot it
    names; a move counts only for the open round, from an active robot that has looked, once. A
    Look that comes before its robot may look (`may_look`) is for the shell to hold and answer
    once the robot is activated; `moves_notice` says when every live active robot has moved.
    """

    def __init__(
        self,
        setup: WorldSetup,
        algorithm: Configured,
        history: RunRecord | None = None,
        epoch: int = 0,
    ) -> None:
        """`algorithm`: the run's algorithm, configured for `setup`. `history`: the record of the
        run to resume (its committed rounds are replayed, not recorded again). `epoch`: this world
        process among the run's (a restarted world draws a new one).

        Raises the algorithm's own refusal of the start (`check_start`).
        """
        if is_async(setup):
            setup = async_setup(setup, history)
        self.setup, self.epoch, self.algorithm = setup, epoch, algorithm
        self._outside = setup.outside(algorithm)  # the run goes ahead outside its assumptions
        self._effects: list[Effect] = []
        n = setup.n
        # On the grid, so that every robot's view is exact (fatswarm/domain/tolerance.py); a start
        # that came through validate_configuration is there already.
        self.positions: Points = snap(np.array(setup.initial, dtype=np.float64).reshape(n, 2))
        if history is None:
            algorithm.check_start(self.positions)
        # the crash adversary's plan (robot -> round it crashes in) and the robots crashed so far
        self.crash_plan = {} if setup.crash is None else crash_plan(setup.seed, n, setup.crash)
        self.stuck: frozenset[int] = frozenset()
        self._live_goals: dict[int, Configured | None] = {n: algorithm}
        self.tracker = ProgressTracker(n, self._goal, setup.max_rounds)
        self.status = Status.RUNNING
        self.committed = 0
        self.open_round = 0
        self.active: tuple[int, ...] = ()
        self.active_set: frozenset[int] = frozenset()  # the same, for O(1) membership
        # `active` as rows (read only) and whether it ascends, for the very tuple `active` is
        # (a model keeps that tuple while the set stays the same: fsync's whole run)
        self._active_rows: tuple[tuple[int, ...], NDArray[np.intp], bool] | None = None
        # the held moves of every active robot's line held at once, for the active tuple that
        # came the round before too (`_held_of_lines` copies it)
        self._lines_held: tuple[Sequence[int], dict[int, Path] | None] = ((), None)
        self._then_checked: tuple[int, ...] = ()  # the last Commit's next active set checked
        self.looked: set[int] = set()
        # the held moves (`held`): every held robot's, world axes, relative to it; the lines held
        # at once are kept as arrays (`held_lines`) and their place here is _IN_LINES until read
        self._held: dict[int, Path] = {}
        self._lines: HeldLines | None = None
        self._apart = False  # a robot holds a move (not a stay) of its own: not among the lines
        self.held_colours: dict[int, int] = {}  # the colours of the held moves (luminous)
        self.failed: dict[int, str] = {}  # held robots whose compute raised: why (they stay)
        self.failure_kinds: set[str] = set()  # the kinds of failure said on the log so far
        self.looks = Looks(setup.robot_model, algorithm, n, setup.seed, setup.record_views)
        self.missing: set[int] = set()  # live active robots of the open round without a move
        self.noticed: tuple[int, tuple[int, ...]] | None = None  # last moves notice sent
        self.moved: tuple[int, ...] = ()
        self.stopped: tuple[int, ...] = ()
        self.collisions_total = 0
        self.alive = [False] * n
        self.gone_since: list[int | None] = [0] * n  # committed round its agent was last seen
        # (None while it is alive)
        self.last_active = [-1] * n
        self.last_length = [0.0] * n
        self.timeouts = [0] * n
        self.rejected: Counter[str] = Counter()
        self._agents: tuple[AgentInfo, ...] | None = None  # cache of state().agents
        self._figures: dict[str, float] | None = None  # cache of state().figures
        self.last_timed_out: tuple[int, ...] = ()  # of the round committed last (its reply says)
        self._figures_failed = False
        self.model: Model = Instants(self) if is_async(setup) else Rounds(self)
        self.readout = CoreReadout(self)  # what the shells read of it (they send it commands)
        if history is None:
            self.emit(self._header())
        else:
            self._replay(history)
        self.gone_since = [self.committed] * n  # no agent seen yet: counted from here

    @property
    def held(self) -> dict[int, Path]:
        """The open round's held moves: robot -> its path, world axes, relative to it (the lines
        held at once made Paths here, once: `held_lines` reads them without)."""
        if self._lines is not None:
            self._settle_lines()
        return self._held

    @held.setter
    def held(self, held: dict[int, Path]) -> None:
        self._held, self._lines, self._apart = held, None, False

    def held_robots(self) -> KeysView[int]:
        """The robots whose move is held (`held`'s keys, no Path made)."""
        return self._held.keys()

    def held_lines(self) -> tuple[NDArray[np.intp], Points] | None:
        """The open round's held moves that are not stays, as arrays, if every one is a line
        held at once (`hold_lines`): the robots ascending (m,) and their ends (m, 2), world axes,
        relative to each, each the very floats `held` gives; None otherwise (then read `held`)."""
        lines = self._lines
        if self._apart:
            return None
        if lines is None:
            return np.empty(0, dtype=np.intp), np.empty((0, 2), dtype=np.float64)
        listed = lines.robots
        if listed is self.active:  # every active robot's line, held at once
            robots, ascending = self._rows()
        else:
            robots = np.asarray(listed, dtype=np.intp)
            ascending = len(listed) < 2 or list(listed) == sorted(listed)
        if not ascending:  # (no robot twice: sorted is ascending)
            order = np.argsort(robots, kind="stable")
            return robots[order], lines.ends[order]
        return robots, lines.ends

    def _rows(self) -> tuple[NDArray[np.intp], bool]:
        """`active` as an array of rows (read only: it is kept) and whether it ascends strictly
        (each robot once), made once for each tuple `active` is."""
        active, kept = self.active, self._active_rows
        if kept is None or kept[0] is not active:
            rows = np.array(active, dtype=np.intp)
            rows.flags.writeable = False
            kept = self._active_rows = (active, rows, list(active) == sorted(set(active)))
        return kept[1], kept[2]

    def _settle_lines(self) -> None:
        """The held lines made Paths in `held` (Python floats: `Path((Line((x, y)),))`)."""
        lines, self._lines = self._lines, None
        assert lines is not None
        held = self._held
        for robot, (x, y) in zip(lines.robots, lines.ends.tolist(), strict=True):
            held[robot] = Path((Line((x, y)),))
        self._apart = self._apart or bool(lines.robots)

    def _header(self) -> Header:
        """The record's first line for this run (`WorldSetup.header`: the settings' codec)."""
        return self.setup.header(self.algorithm, self.positions)

    # -- effects --------------------------------------------------------------------------------

    def emit(self, effect: Effect) -> None:
        """Queue something for the shell to do."""
        self._effects.append(effect)

    def views_changed(self) -> None:
        """The positions or the agents changed: the observers' figures and agents are made again."""
        self._agents, self._figures = None, None

    def take_effects(self) -> list[Effect]:
        """What the shell is to do since it last asked, in order (record lines, log notes)."""
        effects, self._effects = self._effects, []
        return effects

    def _note(self, level: Level, text: str) -> None:
        self.emit(Note(level, text))

    # -- resume ---------------------------------------------------------------------------------

    def _replay(self, record: RunRecord) -> None:
        """Rebuild the state from the committed rounds of a state file."""
        for entry in record.rounds:
            self._replay_round(entry)
        if record.result is not None:
            self.status = record.result.status
        elif self.tracker.status is not None:
            self.finish()  # died between the last round line and the result line

    def _replay_round(self, entry: RoundEntry) -> None:
        relit = self.looks.restore(entry.extra.get("lights"))
        self.account(
            RoundBooking(
                round=entry.round,
                active=entry.active,
                paths={m.robot: m.path for m in entry.moves},
                timed_out={int(r) for r in entry.extra.get("timed_out", [])},
                before=self.positions,
                after=np.asarray(entry.positions, dtype=np.float64),
                traveled={m.robot: m.traveled for m in entry.moves},
                collisions=entry.collisions,
                crashed=entry.extra.get("crashed", ()),
                recovered=entry.extra.get("recovered", ()),
                stuck=stuck_in(self.crash_plan, entry.round),
                relit=relit,
                line=entry.extra,
            )
        )

    def account(self, booking: RoundBooking) -> None:
        """Book one committed round (live or replayed) into the state and the progress tracker:
        the crash adversary's and the gone agents' crashes, the agents' books, the figures."""
        round_no, active, paths = booking.round, booking.active, booking.paths
        stuck, crashed, timed_out = booking.stuck, booking.crashed, booking.timed_out
        if stuck:
            self._note(
                Level.INFO,
                f"robots {sorted(stuck)} crash in round {round_no} (the crash adversary): they "
                "stay where they are for good",
            )
            self.stuck |= frozenset(stuck)
            self.tracker.crash(stuck)
        if crashed:
            self._note(
                Level.WARNING,
                f"robots {sorted(crashed)} count as crashed from round {round_no}: their agents "
                f"have been gone for {crash_after(self.setup.n)} rounds; they stay where they "
                "are, and are not waited for",
            )
            self.tracker.crash(crashed)
        if booking.recovered:
            self.tracker.recover(booking.recovered)
        self.views_changed()
        n, last_active = self.setup.n, self.last_active
        every_robot, all_robots = _every_robot(n)
        if len(active) == n and active == all_robots:  # every robot active
            last_active[:] = [round_no] * n
        else:
            for robot in active:
                last_active[robot] = round_no
        for robot in timed_out:
            self.timeouts[robot] += 1
        before, collisions = booking.before, booking.collisions
        movers: Collection[int]
        traveled: Mapping[int, float] | list[float] | None
        if isinstance(paths, LineMoves):  # the common round as arrays: no Path per robot
            if paths.every(n):  # every robot moved, each once: told the tracker as range(n)
                movers, moved = every_robot, all_robots
            else:
                movers = moved = tuple(paths.robots())
            traveled = paths.traveled.tolist()
        else:
            movers, traveled = paths.keys(), booking.traveled
            moved = tuple(sorted(paths))
        self._book_lengths(before, paths, booking.lengths, moved, movers is every_robot)
        self.collisions_total += len(collisions)
        self.tracker.observe(
            [r for r in active if r not in timed_out] if timed_out else active,
            movers,
            before,
            booking.after,
            traveled,
            len(collisions),
            changed=True if booking.relit else None,
            line=booking.line,
        )
        self.positions, self.committed = booking.after, round_no
        if active is not self.active:  # (the open round's own: its set was made as it opened)
            self.active = tuple(active)
            self.active_set = frozenset(self.active)
        self.moved = moved
        self.stopped = tuple(sorted({c.robot for c in collisions})) if collisions else ()

    def _book_lengths(
        self,
        before: Points,
        paths: Mapping[int, Path] | LineMoves,
        measured: Mapping[int, float] | NDArray[np.float64] | None,
        moved: tuple[int, ...],
        every: bool,
    ) -> None:
        """Each mover's path length (the agents' books): physics' where it measured it (a
        mapping of movers, or with LineMoves an array of every one), else measured here as
        `path_length` from its position `before`. `moved`: the movers, increasing; `every`:
        they are every robot, 0..n-1."""
        last_length = self.last_length
        if isinstance(paths, LineMoves):
            lengths: Iterable[tuple[int, float]]
            if isinstance(measured, np.ndarray):
                if every:  # (0..n-1, in order)
                    last_length[:] = measured.tolist()
                    return
                lengths = zip(moved, measured.tolist(), strict=True)
            elif measured is not None and len(measured) == len(paths):
                lengths = measured.items()  # every mover's (its keys are movers'): none to measure
            elif measured is None and every:
                last_length[:] = paths.lengths(before)  # every robot's, in order
                return
            else:
                known = {} if measured is None else measured
                lengths = (
                    (robot, known.get(robot, here))
                    for robot, here in zip(moved, paths.lengths(before), strict=True)
                )
            for robot, each in lengths:
                last_length[robot] = each
            return
        assert not isinstance(measured, np.ndarray), "lengths as an array go with LineMoves"
        known = {} if measured is None else measured
        for robot, path in paths.items():
            length = known.get(robot)
            if length is None:
                length = path_length((float(before[robot, 0]), float(before[robot, 1])), path)
            last_length[robot] = length

    # -- requests -------------------------------------------------------------------------------

    def reject(self, reason: str, detail: str) -> None:
        """Count a refused input and say so (never raised, never applied)."""
        self.rejected[reason] += 1
        self.emit(Rejected(reason, detail, self.rejected[reason]))

    def may_look(self, robot: int, request: LookRequest = FIRST_LOOK) -> bool:
        """Whether robot `robot`'s Look is answered now: it is active in the open round, has not
        moved in it, and asks for a round after the last it moved in (at this world process);
        otherwise the shell holds the Look until this becomes true."""
        after = request.after if request.epoch == self.epoch else 0
        return self.open_round > after and robot in self.active_set and robot not in self._held

    def lookers(self, robots: Sequence[int]) -> Sequence[int]:
        """The robots of `robots` whose first Look is answered now (`may_look` of each, at once):
        a lock step's round, its Looks all asked as it opens."""
        if not self.open_round:
            return []
        held, active = self._held, self.active
        if not held and (robots is active or robots == active):
            return active  # a round just opened: all of its active robots (the tuple itself)
        active_set = self.active_set
        return [robot for robot in robots if robot in active_set and robot not in held]

    def look(self, robot: int) -> Snapshot | None:
        """Robot `robot`'s snapshot, or None (refused, counted) if it is not active now."""
        seen = self.view_of(robot)
        if seen is None:
            return None
        view, colours, own = seen
        return Snapshot(
            round=self.open_round,
            n=self.setup.n,
            algorithm=self.algorithm.name,
            params=dict(self.algorithm.values),
            view=view,
            epoch=self.epoch,
            colours=colours,
            own=own,
        )

    def view_of(self, robot: int) -> Seen | None:
        """What robot `robot`'s Look shows (its view, the colours it reads of those it sees, its
        own), or None (refused, counted) if it is not active now: `look` without the snapshot
        around it, for a lock step that hands the view to the algorithm in process."""
        if not 0 <= robot < self.setup.n:
            self.reject("look-bad-key", f"robot {robot}")
            return None
        if not self.open_round or robot not in self.active_set:
            self.reject("look-not-active", f"robot {robot} round {self.open_round}")
            return None
        self.looked.add(robot)
        return self.looks.view(self.positions, robot, self.open_round)

    def prepare_looks(self, robots: Sequence[int]) -> None:
        """The open round's views of `robots` built at once, ahead of their Looks (`look` hands
        each the very view it would build alone): a lock step's whole round."""
        if self.open_round:
            self.looks.prepare(self.positions, self.open_round, robots)

    def views_of(self, robots: Sequence[int]) -> Points | None:
        """(k, n-1, 2): the open round's views of `robots` (their Looks admitted: `admit_look`),
        row i robot robots[i]'s, each the very view `view_of` gives it; None where the model's
        views are not all alike (then `view_of` each): a lock step's round hook."""
        if not self.open_round:
            return None
        return self.looks.views_at_once(self.positions, self.open_round, robots)

    def admit_look(self, robot: int) -> bool:
        """Count robot `robot`'s Look without building its view (a lock step that plans the round
        at once); False (refused, counted) if it is not active now."""
        if not self.open_round or robot not in self.active_set:
            self.reject("look-not-active", f"robot {robot} round {self.open_round}")
            return False
        self.looked.add(robot)
        return True

    def admit_looks(self, robots: Sequence[int]) -> list[bool]:
        """`admit_look` of each of `robots` in turn (whether each was admitted), at once where
        every one is active in the open round (a lock step's round hook)."""
        if self.open_round and self._every_active(robots):  # (the set as it is: no new one)
            self.looked.update(self.active_set)
            return [True] * len(robots)
        if self.open_round and self.active_set.issuperset(robots):
            self.looked.update(robots)
            return [True] * len(robots)
        return [self.admit_look(robot) for robot in robots]

    def _every_active(self, robots: Sequence[int]) -> bool:
        """Whether `robots` are the open round's active robots, in their order, each once."""
        active = self.active
        if robots is active:  # (a lock step's lookers: the tuple itself)
            return len(active) == len(self.active_set)
        return (
            len(robots) == len(active) == len(self.active_set)
            and (robots if type(robots) is tuple else tuple(robots)) == active
        )

    def move(self, robot: int | None, msg: MoveSubmitted) -> bool:
        """Hold a move for the open round from the robot `robot` it came from (None: a key with no
        robot); False if refused (counted)."""
        if robot != msg.robot:
            self.reject("move-wrong-robot", f"robot {msg.robot} sent as robot {robot}")
            return False
        return self.hold(robot, msg.round, msg.path, msg.colour, msg.failed)

    def hold(
        self,
        robot: int,
        round_no: int,
        path: Path,
        colour: int | None,
        failed: str | None = None,
    ) -> bool:
        """`move` of what a MoveSubmitted from robot `robot` itself carries (the lock step hands
        it over without the message); False if refused (counted). `failed`: its compute raised
        (why, one line): it stays, and the round line says why (`failed`)."""
        if round_no != self.open_round:
            self.reject("move-wrong-round", f"robot {robot} round {round_no} != {self.open_round}")
        elif robot not in self.active_set:
            self.reject("move-not-active", f"robot {robot} round {round_no}")
        elif robot not in self.looked:
            self.reject("move-without-look", f"robot {robot} round {round_no}")
        elif robot in self._held:
            self.reject("move-duplicate", f"robot {robot} round {round_no}")
        elif not self._colour_ok(colour):
            self.reject("move-bad-colour", f"robot {robot} colour {colour}")
        elif failed is not None:
            self._held[robot] = Path()
            self.failed[robot] = failed
            self.missing.discard(robot)
            self._said(robot, round_no, failed)
            return True
        else:
            world = self.looks.to_world(robot, round_no, path)
            self._held[robot] = world
            if world.segments:
                self._apart = True
            if colour is not None:
                self.held_colours[robot] = colour
            self.missing.discard(robot)
            return True
        return False

    def hold_lines(
        self,
        robots: Sequence[int],
        round_no: int,
        ends: Points,
        goes: NDArray[np.bool_] | None = None,
    ) -> None:
        """`hold` of k moves at once, row i robot robots[i]'s: a straight line to ends[i] (in
        the frame of its Look, relative to it) where goes[i] (None: every one goes), else a
        stay; no colour, none failed. The moves are checked as `hold` checks each, refusals
        counted the same (in turn, by `hold` itself, if any would be refused); the lines are
        kept as arrays (`held_lines`, world axes) and made Paths only if `held` is read."""
        held = self._held
        chosen: Collection[int]
        if (
            not held
            and round_no == self.open_round
            and len(self.looked) == len(self.active_set)  # (only active robots look)
            and self._every_active(robots)
        ):  # every active robot, each once, all looked, none held: the set as it is
            chosen = self.active_set
        else:
            chosen = set(robots)
            if not (
                round_no == self.open_round
                and len(chosen) == len(robots)
                and self.active_set.issuperset(chosen)
                and self.looked.issuperset(chosen)
                and (not held or held.keys().isdisjoint(chosen))
            ):  # some would be refused: each in turn, as `hold` refuses and counts them
                each = [True] * len(robots) if goes is None else goes.tolist()
                for robot, (x, y), go in zip(robots, ends.tolist(), each, strict=True):
                    self.hold(robot, round_no, Path((Line((x, y)),)) if go else STAY, None)
                return
        if goes is None or np.count_nonzero(goes) == len(robots):
            movers = robots
        else:  # the others stay (to_world of a stay is a stay)
            movers = list(compress(robots, goes.tolist()))
            held.update(dict.fromkeys(robots, STAY))
            ends = ends[goes]
        if movers:
            # (a list: `Looks.lines_to_world` knows every robot's rows by a list of them)
            world = self.looks.lines_to_world(
                movers if type(movers) is list else list(movers), round_no, ends
            )
            if held:
                held.update(dict.fromkeys(movers, _IN_LINES))
            else:  # (the same dict, made at once)
                self._held = self._held_of_lines(movers)
            lines = self._lines
            if lines is None:  # (a list of the caller's copied: kept beyond this call)
                self._lines = HeldLines(movers if type(movers) is tuple else list(movers), world)
            else:  # a second batch in one round
                lines.robots = [*lines.robots, *movers]
                lines.ends = np.concatenate((lines.ends, world))
        if chosen is self.active_set:  # (the missing are active robots: none is left)
            self.missing.clear()
        else:
            self.missing.difference_update(chosen)

    def _held_of_lines(self, movers: Sequence[int]) -> dict[int, Path]:
        """`dict.fromkeys(movers, _IN_LINES)`, made as a copy of one kept where `movers` is the
        active tuple of the round before too (a copy is about ten times cheaper than a dict made
        key by key: fsync's every round but the first two)."""
        kept, template = self._lines_held
        if kept is movers:
            if template is None:
                template = dict.fromkeys(movers, _IN_LINES)
                self._lines_held = (movers, template)
            return template.copy()
        if movers is self.active:
            self._lines_held = (movers, None)
        return dict.fromkeys(movers, _IN_LINES)

    def _said(self, robot: int, round_no: int, failed: str) -> None:
        """Log a failed compute the first time one of its kind comes (`failure_kind`: the
        numbers masked); the rest are counted (the round lines' `failed`, the run's failures)."""
        kind = failure_kind(failed)
        if kind not in self.failure_kinds:
            self.failure_kinds.add(kind)
            now = self.model.time()  # an async run's instant is its virtual time
            when = f"round {round_no}" if now is None else f"time {now:g}"
            self._note(
                Level.WARNING,
                f"robot {robot}, {when}: the algorithm failed ({failed}); it stays "
                "(failures of this kind are counted, not logged again)",
            )

    def _colour_ok(self, colour: int | None) -> bool:
        """Whether a move may carry `colour`: none, or one of a luminous algorithm's palette."""
        return colour is None or colour < len(self.algorithm.colours)

    def moves_notice(self) -> MovesHeld | None:
        """The notice to send the coordinator when every live active robot of the open round has
        moved (once, and again only when a late move joins them); None otherwise."""
        if not self.open_round or self.missing:
            return None
        held = self._held
        robots = (
            self.active  # every active robot (held are active): sorted, if it ascends
            if len(held) == len(self.active_set) and self._rows()[1]
            else tuple(sorted(held))
        )
        if self.noticed == (self.open_round, robots):
            return None
        self.noticed = (self.open_round, robots)
        return MovesHeld(self.open_round, robots, self.epoch)

    def control(self, req: ControlRequest) -> tuple[ControlReply, bool]:
        """Answer a coordinator request; the flag says whether the state changed (publish it)."""
        if isinstance(req, Hello):
            return self.reply(True), False
        if self.status != _RUNNING:
            return self.reply(False, f"the run has ended ({self.status})"), False
        if isinstance(req, Begin):
            refused, changed = self.model.begin(req)
            return self.reply(refused is None, refused or ""), changed
        then_active = req.then_active
        if then_active and then_active is not self._then_checked:
            if max(then_active) >= self.setup.n:  # refused whole, not halfway
                why = "next round's active set names robots not of this run"
                return self.reply(False, why), False
            if type(then_active) is tuple:  # (a tuple that passed passes again: not checked)
                self._then_checked = then_active
        refused, changed = self.model.commit(req)
        if refused is None and changed:
            then = req.then
            if then is not None and self.status == _RUNNING:
                refused = self.model.begin(then)[0]
            if refused is None:  # the round committed (and the next one opened, if asked)
                return self.reply(True, timed_out=self.last_timed_out), True
        return self.reply(refused is None, refused or ""), changed

    def reply(self, ok: bool, reason: str = "", timed_out: tuple[int, ...] = ()) -> ControlReply:
        """A reply to the coordinator: the world as it stands (and the model's fields).
        `timed_out`: the reply to a Commit's, the robots of the round it committed without a move.
        """
        held = self._held
        return ControlReply(
            ok,
            reason,
            self.setup.n,
            self.committed,
            self.open_round,
            self.status,
            self.collisions_total,
            tuple(sorted(held)) if held and self.open_round else (),
            epoch=self.epoch,
            timed_out=timed_out,
            **self.model.reply_fields(),
        )

    def _goal(self, positions: Points) -> bool:
        """The run's goal: the algorithm's for all robots, or once the crash adversary has crashed
        some, the algorithm's for the live robots alone, configured for their number (False if
        the algorithm refuses that number): README, "Faults"."""
        if not self.stuck:
            return self.algorithm.goal(positions)
        live = [r for r in range(self.setup.n) if r not in self.stuck]
        if len(live) not in self._live_goals:
            try:
                self._live_goals[len(live)] = Configured.of(
                    self.algorithm.algorithm, len(live), self.algorithm.values
                )
            except ValueError:  # AlgorithmParamsError, or a refusal of that n
                self._live_goals[len(live)] = None
        setting = self._live_goals[len(live)]
        return setting is not None and setting.goal(positions[live])

    def finish(self) -> None:
        progress = self.tracker.snapshot()
        status = progress.status or Status.STALLED
        self.emit(
            Result(
                status,
                progress.rounds,
                self.positions,
                epochs=progress.epochs,
                moves=progress.moves,
                total_distance=progress.total_distance,
                collisions=progress.collisions,
                **self.model.result_fields(),
            )
        )
        self.status = status

    def set_alive(self, robot: int, alive: bool) -> bool:
        """Note an agent's liveliness; True if it changed."""
        if not 0 <= robot < self.setup.n or self.alive[robot] == alive:
            return False
        self.alive[robot] = alive
        self.gone_since[robot] = None if alive else self.committed
        self._agents = None  # only the agents' view changed
        if alive and robot in self.active_set and robot not in self._held:
            self.missing.add(robot)
        elif not alive:
            self.missing.discard(robot)  # a robot gone mid-round is not waited for
        return True

    def state(self) -> WorldState:
        """The observers' view of the world now."""
        n = self.setup.n
        return WorldState(
            round=self.committed,
            n=n,
            algorithm=self.algorithm.name,
            params=dict(self.algorithm.values),
            figures=self._algorithm_figures(),
            scheduler=self.setup.scheduler,
            swarm=self.setup.swarm,
            positions=self.positions,
            active=self.active,
            open_round=self.open_round,
            moved=self.moved,
            stopped=self.stopped,
            collisions_total=self.collisions_total,
            status=self.status,
            agents=self._agent_infos(),
            lights=self.looks.names(),
            palette=self.algorithm.colours,
            derived=known_numbers(self.tracker.snapshot().derived),
            outside=self._outside,
            model=self.setup.robot_model,
        )

    def _algorithm_figures(self) -> dict[str, float]:
        """The algorithm's figures for the positions, made once per committed round."""
        if self._figures is None:
            try:
                self._figures = self.algorithm.figures(self.positions)
            except AlgorithmFailure as exc:  # only the dashboard misses them: say it once
                if not self._figures_failed:
                    self._note(Level.WARNING, f"{exc}; the dashboard goes without figures")
                self._figures_failed, self._figures = True, {}
        return self._figures

    def _agent_infos(self) -> tuple[AgentInfo, ...]:
        """Per-robot agent info, rebuilt only after it changed (it is published twice a round)."""
        if self._agents is None:
            self._agents = tuple(
                AgentInfo(self.alive[i], self.last_active[i], self.last_length[i], self.timeouts[i])
                for i in range(self.setup.n)
            )
        return self._agents
