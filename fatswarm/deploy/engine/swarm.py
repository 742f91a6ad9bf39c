"""A swarm to step through, as Mesa's `model.step()`: `fatswarm.Swarm(...)` takes `fatswarm.run`'s
keywords and advances the lock step one record line at a time (a round; an ended cycle under the
async models), shows what any robot would see now, and writes the very record `fatswarm.run`
and `fatswarm run --lockstep` write.

It is the lock step itself (deploy/engine/lockstep.py: `start_lockstep`, the coordinator's one
loop advanced an exchange at a time), not a second engine; its state is read off the record
lines it has stepped to, and its views are built by the world's own `Looks`.
"""

from __future__ import annotations

import inspect
import math
import numbers
import reprlib
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from typing import Any, Final

import numpy as np

from fatswarm.deploy.engine import api
from fatswarm.deploy.engine.config import input_errors
from fatswarm.deploy.engine.lockstep import Lockstep, RoundReport
from fatswarm.deploy.engine.notebook import RunRecord, RunResult, frame_svg, outcome_text, run_text
from fatswarm.domain import figures as declared
from fatswarm.domain.adversary import ASYNC_NAMES
from fatswarm.domain.figures import FigureValue
from fatswarm.domain.frames import Frame
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points
from fatswarm.domain.robot_model import AXIS_NAMES, RobotModel
from fatswarm.world.looks import Looks
from fatswarm.world.physics import Collision
from fatswarm.world.progress import Progress
from fatswarm.world.record import Header, Move, RecordWriter, Result, RoundEntry
from fatswarm.world.record import RunRecord as RecordLines

# `fatswarm.run`'s keywords, the robot model's axes among them (its derived signature): the
# Swarm's, word for word
RUN_SIGNATURE: Final = inspect.signature(api.run)


class SwarmEndedError(RuntimeError):
    """`Swarm.step()` after the run has ended."""


class NoSuchRobotError(ValueError, IndexError):
    """A robot number outside the swarm (a ValueError, as every refused input, and an
    IndexError)."""


@dataclass(frozen=True, slots=True, eq=False, repr=False)
class Step:
    """What one `Swarm.step()` did: one record line (a round; an ended cycle under an async
    model). `moves`: each mover's world-frame path and the arc length it covered; `figures`: the
    round's own declared figures (fatswarm.domain.figures: min_gap, failures...); `time`: an
    async cycle's end (virtual time), else None; `line`: the record line whole."""

    round: int
    active: tuple[int, ...]
    moves: tuple[Move, ...]
    collisions: tuple[Collision, ...]
    figures: Mapping[str, FigureValue]
    time: float | None
    line: RoundEntry

    @staticmethod
    def of(line: RoundEntry) -> Step:
        return Step(
            line.round,
            line.active,
            tuple(line.moves),  # (a round's moves are made when read: a tuple here)
            line.collisions,
            line.derived,
            _end(line),
            line,
        )

    def __repr__(self) -> str:
        time = "" if self.time is None else f", time={self.time:.6g}"
        figures = "".join(f", {k}={v!r}" for k, v in self.figures.items() if v is not None)
        return (
            f"Step(round={self.round}, active={self.active}, "
            f"moved={tuple(m.robot for m in self.moves)}, "
            f"collisions={len(self.collisions)}{time}{figures})"
        )


@dataclass(frozen=True, slots=True, eq=False, repr=False)
class View:
    """What robot `robot` would see if it Looked now (`Swarm.view`), as the world would serve it
    for a Look in round `round`: the robots it sees (`seen`, in the order of the rows below), their
    centres in its private frame (`local`, (k, 2), itself at the origin: what its algorithm's
    compute is given) and the same points in world coordinates (`world`, (k, 2): where it sees
    them; with `noise`, where it believes they are), the colours it reads of them and its own
    (names; None where the model lets it read none), and its `frame`."""

    robot: int
    round: int
    seen: tuple[int, ...]
    local: Points
    world: Points
    colours: tuple[str, ...] | None
    own: str | None
    frame: Frame

    def __repr__(self) -> str:
        lights = "" if self.colours is None else f", colours={self.colours}"
        own = "" if self.own is None else f", own={self.own!r}"
        return (
            f"View(robot={self.robot}, round={self.round}, seen={self.seen}{lights}{own}, "
            f"frame={self.frame})"
        )


@dataclass(slots=True)
class _Lines:
    """The run's journal: the header and the result line as the world emits them (its round
    lines reach the swarm with the figures after them, through the round callback)."""

    header: Header | None = None
    result: Result | None = None

    def append(self, line: Header | RoundEntry | Result) -> None:
        if isinstance(line, Header):
            self.header = line
        elif isinstance(line, Result):
            self.result = line

    def close(self) -> None:
        pass


@dataclass(frozen=True, slots=True)
class _Written:
    """What the file at `record=` holds: the header, so many round lines, the result line."""

    header: bool = False
    rounds: int = 0
    result: bool = False


class Swarm:
    """A lock-step run to advance by hand: `fatswarm.run`'s keywords (`help(fatswarm.run)`; the
    robot model's axes among them), one record line at a time.

        swarm = fatswarm.Swarm(8, seed=1, scheduler="ssync")
        swarm.step()               # one round: Step(round=1, active=..., moved=..., ...)
        swarm.positions            # (8, 2), world frame, after it
        swarm.view(3)              # what robot 3 would see now: its frame, and world axes
        swarm.run(until=10)        # on to round 10 (or a function of the swarm, or None: the end)
        swarm.record               # the record so far, as fatswarm.read_record gives it
        swarm.run().result         # at the end: the RunResult fatswarm.run gives

    `step()` takes the next record line: a round under the round schedulers; under the async
    models, the next ended Look-Compute-Move cycle (the record's next line; the world may end
    several at one instant of virtual time, and each is a step of its own). The swarm is as of
    the last line stepped to: `positions`, `lights`, `figures` and `time` are the line's, and
    `view(i)` is what robot i would see if it Looked then (the lock step may have served the
    next round's Looks already, a Commit opening the next round at once, so an algorithm's
    compute may run a round ahead of `step`: `view` shows what those Looks were shown). Stepped
    to the end, or run through, its record (in memory, and at `record=` if given) is byte for
    byte `fatswarm.run`'s and `fatswarm run --lockstep`'s with the same settings (`command`
    aside: the API has none).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        asked = api.run_asked(_keywords(args, kwargs))
        try:
            setup = asked.config.resolve()
        except input_errors() as exc:
            raise api.refusal(exc) from None
        self._asked, self._setup = asked, setup
        self._lines = _Lines()
        self._pending: deque[RoundReport] = deque()
        self._palette = api.Palette(asked.on_round)  # the colours the lines show, for pictures
        self._lockstep: Lockstep = api.started(setup, self._lines, self._pending.append)
        readout = self._lockstep.readout
        self.n: Final = setup.params.n
        self.settings: Final = readout.setup  # the run's settings whole (what its header says)
        self._stepped: list[RoundEntry] = []
        self._last: RoundReport | None = None
        self._start = (readout.lights(), readout.progress(), readout.time())
        self._looks_seen = 0  # robots active in the lines stepped to (the record's `looks`)
        self._result: RunResult | None = None
        # the world's own Looks, for views asked now (none recorded, nothing of the run touched)
        self._looks = Looks(self.settings.robot_model, setup.params, self.n, setup.seed, False)
        self._written = _Written()  # what the file at `record=` holds so far
        self._write()

    # -- stepping -------------------------------------------------------------------------------

    def step(self) -> Step:
        """Advance to the next record line (a round; an ended cycle under an async model) and say
        what it did. Raises SwarmEndedError once the run has ended, and what the run raises (an
        algorithm's goal that fails; after that, every step raises LockstepStoppedError)."""
        try:
            if not self._next():
                raise SwarmEndedError(
                    f"the run has ended ({self._outcome()}): nothing left to step "
                    "(read .result and .record)"
                )
        finally:
            self._write()
        assert self._last is not None
        return Step.of(self._last.entry)

    def run(self, until: int | Callable[[Swarm], bool] | None = None) -> Swarm:
        """Step on until round (ended cycle) `until`, or until `until(swarm)` is true (asked
        before each step), or to the end (None); stops at the end in any case. Returns the swarm.
        Raises ValueError for a round already passed."""
        stop: Callable[[], bool]
        if until is None:
            stop = _never
        elif isinstance(until, numbers.Integral) and not isinstance(until, bool):
            target = int(until)
            if target < self.round:
                raise ValueError(
                    f"{self._word} {target} has passed: the swarm is at {self._word} {self.round}"
                )
            stop = lambda: self.round >= target  # noqa: E731
        elif callable(until):
            test = until
            stop = lambda: bool(test(self))  # noqa: E731
        else:
            raise api.RunArgumentError(
                "until must be a round number, a function of the swarm or None, "
                f"got {reprlib.repr(until)}"
            )
        try:
            while not stop() and self._next():
                pass
        finally:
            self._write()
        return self

    def _next(self) -> bool:
        """Take the next record line (advancing the lock step until the world commits one); False
        if the run has ended."""
        while not self._pending:
            if self._result is not None or not self._lockstep.advance():
                self._end()
                return False
        report = self._pending.popleft()
        self._last = report
        self._stepped.append(report.entry)
        self._looks_seen += len(report.entry.active)
        self._palette.committed(report)  # and the user's round callback
        if not self._pending and self._lockstep.readout.status != Status.RUNNING:
            self._end()  # that was the last line: the world has ended the run
        return True

    def _end(self) -> None:
        """The run has ended: finish the lock step, and its result as `fatswarm.run`'s."""
        if self._result is None:
            done = self._lockstep.finish()
            self._result = api.api_result(done, self._asked, self._setup, self._palette.names)

    def _write(self) -> None:
        """The record lines taken since the last call, to the file at `record=` (if given): the
        header first (a new file), the result line once the run has ended."""
        path = self._asked.record
        if path is None:
            return
        todo: list[Header | RoundEntry | Result] = []
        if not self._written.header:
            todo.append(self._header)
        todo += self._stepped[self._written.rounds :]
        ended = self._result is not None and not self._written.result
        if ended:
            assert self._lines.result is not None  # the world records it as the run ends
            todo.append(self._lines.result)
        if not todo:
            return
        with RecordWriter(path, append=self._written.header) as writer:
            for line in todo:
                writer.append(line)
        self._written = _Written(True, len(self._stepped), self._written.result or ended)

    @property
    def _header(self) -> Header:
        header = self._lines.header
        assert header is not None  # the lock step records it as it starts
        return header

    # -- the swarm now --------------------------------------------------------------------------

    @property
    def round(self) -> int:
        """The last round stepped to (an ended cycle under an async model); 0 at the start."""
        return 0 if self._last is None else self._last.entry.round

    @property
    def status(self) -> Status:
        """Running until the run has ended and its last line was stepped to; then how it ended
        (formed, stalled, max_rounds)."""
        return Status.RUNNING if self._result is None else self._result.status

    @property
    def positions(self) -> Points:
        """Every robot's centre (n, 2), world frame, after the last line stepped to (a copy)."""
        last = self._last
        return np.array(self._header.initial if last is None else last.entry.positions)

    @property
    def lights(self) -> tuple[str, ...]:
        """Every robot's colour name now (a luminous algorithm's), else ()."""
        if self._last is None:
            return self._start[0]
        names = self._last.entry.extra.get("lights")
        return tuple(names) if isinstance(names, list) else self._start[0]

    @property
    def time(self) -> float | None:
        """The virtual time of the last line stepped to (an async cycle's end; 0 at the start),
        None under the round schedulers."""
        return self._start[2] if self._last is None else _end(self._last.entry)

    @property
    def figures(self) -> dict[str, FigureValue]:
        """The run's declared figures so far (fatswarm.domain.figures, each summarised over the
        lines stepped to as the run's result does: min_gap its minimum...), those a run knows as
        it goes: status, rounds, time, epochs, looks, moves, collisions, total_distance and the
        derived ones (the sweep's bound, ratio and wall_s are not)."""
        progress = self._start[1] if self._last is None else self._last.progress
        known: dict[str, FigureValue] = {
            **{f.name: getattr(progress, f.name) for f in fields(Progress) if f.name != "derived"},
            **progress.derived,
            "status": str(self.status),
            "time": self.time,
            "looks": self._looks_seen,
        }
        return {f.name: known[f.name] for f in declared.FIGURES if f.name in known}  # read now

    @property
    def record(self) -> RunRecord:
        """The record so far (the lines stepped to; the result line once the run has ended), as
        `fatswarm.read_record` gives it; its `path` is the file at `record=`, if one was given
        (which holds the very same lines)."""
        result = self._lines.result if self._result is not None else None
        lines = RecordLines(self._header, tuple(self._stepped), result)
        return RunRecord.of(lines, self._asked.record)

    @property
    def result(self) -> RunResult | None:
        """How the run ended, as `fatswarm.run` returns it; None while it goes on."""
        return self._result

    def view(self, robot: int) -> View:
        """What robot `robot` would see if it Looked now (after the last line stepped to; under
        an async model, at that line's time), as the world would serve its Look in the next
        round (under an async model, the world's next instant): in its private frame and in
        world coordinates. Raises NoSuchRobotError for a robot not in the swarm."""
        if isinstance(robot, bool) or not isinstance(robot, numbers.Integral):
            raise api.RunArgumentError(f"robot must be an int, got {reprlib.repr(robot)}")
        if not 0 <= robot < self.n:
            raise NoSuchRobotError(
                f"robot {robot} is not in this swarm: its robots are 0 to {self.n - 1}"
            )
        robot = int(robot)
        look_round = self._lockstep.readout.committed + 1
        positions = self.positions
        looks = self._looks
        looks.restore(list(self.lights))
        local, colours, own = looks.view(positions, robot, look_round)
        frame = looks.frame(robot, look_round)
        palette = self._setup.params.colours
        return View(
            robot=robot,
            round=look_round,
            seen=tuple(int(i) for i in looks.shown(positions, robot, look_round)),
            local=local,
            world=_to_world(frame, local) + positions[robot],
            colours=None if colours is None else tuple(palette[c] for c in colours),
            own=None if own is None else palette[own],
            frame=frame,
        )

    # -- as text and as a picture ---------------------------------------------------------------

    @property
    def _word(self) -> str:
        return "cycle" if self.settings.scheduler in ASYNC_NAMES else "round"

    def _outcome(self) -> str:
        collisions = self.figures.get("collisions")
        count = collisions if isinstance(collisions, int) else 0
        return outcome_text(str(self.status), self.round, count)

    def __repr__(self) -> str:
        time = "" if self.time is None else f", time={self.time:.6g}"
        s = self.settings
        adversary = "" if s.non_rigid is None else f", non_rigid={s.non_rigid:g}"
        adversary += "" if s.crash is None else f", crash={s.crash}"
        return (
            f"Swarm(n={self.n}, algorithm={self._setup.params.name!r}, "
            f"model={model_text(s.robot_model)!r}, scheduler={s.scheduler!r}{adversary}, "
            f"{self._word}={self.round}{time}, status={str(self.status)!r})"
        )

    def _repr_svg_(self) -> str:
        """Jupyter's picture: the start, the robots now and their smallest enclosing circle."""
        caption = (self._outcome(), run_text(self.n, self.settings.scheduler, self.settings.seed))
        return frame_svg(self._header.initial, self.positions, caption)


def model_text(model: RobotModel) -> str:
    """The robot model in short: `paper`, or its axes that are not the paper's as keywords
    (`visibility=opaque sight=5`)."""
    changed = model.changed()
    return " ".join(f"{a.name}={a.label(model.value(a.name))}" for a in changed) or "paper"


def _keywords(args: tuple[Any, ...], kwargs: dict[str, Any]) -> dict[str, Any]:
    """`fatswarm.run`'s keywords as `run_asked` takes them, bound from a call with `args` and
    `kwargs` (each unset one at run's default; `model`: the axes given); RunArgumentError for a
    keyword `run` does not take."""
    try:
        given = RUN_SIGNATURE.bind(*args, **kwargs).arguments
    except TypeError as exc:
        raise api.RunArgumentError(f"Swarm() {exc}") from None
    keywords = {
        name: given.get(name, p.default)
        for name, p in RUN_SIGNATURE.parameters.items()
        if name not in AXIS_NAMES
    }
    keywords["model"] = {name: value for name, value in given.items() if name in AXIS_NAMES}
    return keywords


def _end(line: RoundEntry) -> float | None:
    """An async cycle line's end (virtual time); None for a round's line."""
    end = line.extra.get("end")
    return float(end) if isinstance(end, (int, float)) else None


def _to_world(frame: Frame, local: Points) -> Points:
    """Points of a view in `frame` (relative to the robot) in world axes: `Frame.to_local`
    undone (the rotation turned back, then the mirror)."""
    rel = np.array(local, dtype=np.float64).reshape(-1, 2)
    if frame.rotation:
        c, s = math.cos(-frame.rotation), math.sin(-frame.rotation)
        x, y = rel[:, 0].copy(), rel[:, 1].copy()
        rel[:, 0] = c * x - s * y
        rel[:, 1] = s * x + c * y
    if frame.mirror:
        rel[:, 0] *= -1.0
    return rel


def _never() -> bool:
    return False


Swarm.__signature__ = RUN_SIGNATURE.replace(return_annotation=inspect.Signature.empty)  # type: ignore[attr-defined]


__all__ = ["NoSuchRobotError", "Step", "Swarm", "SwarmEndedError", "View", "model_text"]
