"""Replaying one of oblot-sim's recorded runs (tests/data/oblot) with a port, round by round,
without the world: each active robot gets the view the peer's robot had (the others' positions in
its frame as the peer draws it), the port's path is mapped back and the move applied as the data
says (rigid, or cut after the round's distance). docs/ports.md says what is compared.

Two ways to move along a path: `FATSWARM` (unit speed along the path as the port gives it, as
fatswarm's world moves) and `PEER` (the peer's world as it behaves, its quirks included: an arc
turned clockwise in global coordinates whatever the frame, a line-then-arc path timed wrongly past
its line, and the crash when a move of such a path ends exactly at its end; docs/ports.md,
"Disagreements"). Nothing here is the peer's code: it is our model of what its runs show.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fatswarm.agent.geometry import sec
from fatswarm.agent.oblot_common import OblotParams
from fatswarm.domain.path import (
    Arc,
    Line,
    Path,
    Point,
    Points,
    end_point,
    path_length,
    point_at,
    segment_length,
)
from fatswarm.domain.seam import Algorithm

PEER_ALGORITHMS: dict[str, str] = {
    "GoToCoG": "oblot-go-to-cog",
    "GoToRightMost": "oblot-go-to-rightmost",
    "GatheringWithMultiplicity": "oblot-gathering-multiplicity",
    "MoveAlongSEC": "oblot-move-along-sec",
}
"""The peer's class name -> the port's registered name."""

COMPARE_REL = 1e-9
"""Positions agree when within COMPARE_REL * max(1, the largest coordinate of the peer's round)."""


class Mover(enum.Enum):
    """How a replayed robot follows its path (module docstring)."""

    FATSWARM = "fatswarm"
    PEER = "peer"


class PeerCrash(RuntimeError):
    """The peer's world throws here (its line-then-arc interpolation runs off its end)."""


@dataclass(frozen=True, slots=True)
class PeerFrame:
    """A robot's frame as the peer draws it: a global point p is seen at ((p - own) * unit)
    turned anticlockwise by `rotation`, then x negated if `chirality`
    (`positiontransformations/RotationTransformation.java:47-51`; back by the inverse, `:55-61`)."""

    unit: float
    rotation: float
    chirality: bool

    def to_local(self, p: Point, origin: Point) -> Point:
        x, y = (p[0] - origin[0]) * self.unit, (p[1] - origin[1]) * self.unit
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        lx, ly = c * x - s * y, s * x + c * y
        return (-lx if self.chirality else lx, ly)

    def to_global(self, q: Point, origin: Point) -> Point:
        x = -q[0] if self.chirality else q[0]
        y = q[1]
        c, s = math.cos(-self.rotation), math.sin(-self.rotation)
        gx, gy = c * x - s * y, s * x + c * y
        return (gx * (1.0 / self.unit) + origin[0], gy * (1.0 / self.unit) + origin[1])

    def path_to_global(self, path: Path, origin: Point) -> Path:
        """The path in global coordinates: points mapped, sweeps negated by a mirror."""
        out: list[Line | Arc] = []
        for seg in path.segments:
            if isinstance(seg, Line):
                out.append(Line(self.to_global(seg.end, origin)))
            else:
                sweep = -seg.sweep if self.chirality else seg.sweep
                out.append(Arc(self.to_global(seg.center, origin), sweep))
        return Path(tuple(out))


@dataclass(frozen=True, slots=True)
class RoundResult:
    """One replayed round: the largest disagreement with the peer (relative) and who failed."""

    round: int
    error_rel: float
    failed: Mapping[int, str]


@dataclass(slots=True)
class Replay:
    """A replayed case: per-round results, the first round that disagrees (None: none), and
    what the port did in the round the peer threw (`error_round_failed`, robot -> message)."""

    case_id: str
    rounds: list[RoundResult] = field(default_factory=list)
    first_disagreement: int | None = None
    error_round_failed: dict[int, str] | None = None
    crashed: str | None = None

    @property
    def max_error_rel(self) -> float:
        return max((r.error_rel for r in self.rounds), default=0.0)


def frames_of(case: Mapping[str, Any]) -> list[PeerFrame]:
    """One PeerFrame per robot (a shared frame repeated)."""
    n = len(case["start"])
    drawn = [PeerFrame(float(u), float(r), bool(c)) for u, r, c in case["frames"]]
    return drawn * n if case["frames_mode"] == "shared" else drawn


def view_of(positions: Points, i: int, frame: PeerFrame) -> Points:
    """(n - 1, 2): the others' positions in robot i's frame (the robot itself left out)."""
    own = (float(positions[i, 0]), float(positions[i, 1]))
    rows = [
        frame.to_local((float(p[0]), float(p[1])), own) for j, p in enumerate(positions) if j != i
    ]
    return np.asarray(rows, dtype=np.float64).reshape(-1, 2)


def _peer_point(start: Point, path: Path, budget: float) -> Point:
    """Where the peer's world puts a robot after travelling `budget` along `path` (global)."""
    if not path.segments:
        return start
    segs = list(path.segments)
    arc = segs[-1] if isinstance(segs[-1], Arc) else None
    if arc is None:  # straight lines: the peer follows them as we do
        return point_at(start, path, budget)
    # the peer's arc always turns clockwise in global coordinates (its CircularPath applies the
    # angle found in the robot's frame, negated, to global points)
    line = segs[0] if len(segs) == 2 and isinstance(segs[0], Line) else None
    l1 = segment_length(start, line) if line is not None else 0.0
    on_circle = line.end if line is not None else start
    l2 = segment_length(on_circle, arc)
    total = l1 + l2
    clockwise = Arc(arc.center, -abs(arc.sweep))
    if budget == total:
        raise PeerCrash("a line-then-arc move ends exactly at its end (CombinedPath.java:60-67)")
    if budget > total:
        return end_point(on_circle, Path((clockwise,)))
    if budget < l1:
        return point_at(start, Path((Line(on_circle),)), budget)
    # past the line, the peer times the arc from l1 to l2 (not to l1 + l2): when l2 <= l1 it is
    # already at the arc's end; else it turns (budget - l1) / (l2 - l1) of it
    if l2 <= l1:
        return end_point(on_circle, Path((clockwise,)))
    f = (budget - l1) / (l2 - l1)
    return end_point(on_circle, Path((Arc(arc.center, clockwise.sweep * f),)))


def move(start: Point, path: Path, rigid: bool, budget: float, mover: Mover) -> Point:
    """Where the robot is after its move: the path's end if rigid (the peer crashes when the
    longest path is a line-then-arc: see `replay`), else after `budget` of arc length."""
    if rigid:
        return end_point(start, path)
    if mover is Mover.FATSWARM:
        return point_at(start, path, budget)
    return _peer_point(start, path, budget)


def _rigid_crash(paths: Sequence[tuple[Point, Path]]) -> bool:
    """The peer's rigid round ends when its longest path does (at least 1 unit of time), placing
    that robot by interpolation at exactly its end, where a path with an arc runs off its array
    (`RobotPaths/CombinedPath.java:60-67`, `Schedulers/SSyncScheduler.java:96`)."""
    if not paths:
        return False
    lengths = [path_length(start, path) for start, path in paths]
    longest = max(lengths)
    return longest >= 1.0 and any(
        length == longest and any(isinstance(s, Arc) for s in path.segments)
        for length, (_, path) in zip(lengths, paths, strict=True)
    )


def replay(
    case: Mapping[str, Any],
    algorithm: Algorithm[Any],
    mover: Mover = Mover.PEER,
    params: OblotParams | None = None,
) -> Replay:
    """Replay `case` (one entry of a tests/data/oblot file) with `algorithm`, from the recorded
    start, the recorded active sets and the recorded move distances; positions run free (ours
    carry on from ours). Compares every stored round; past the last one, if the peer threw, runs
    the port once more on every robot and records which of them refused."""
    n = len(case["start"])
    params = params if params is not None else OblotParams(n, 0.0)
    frames = frames_of(case)
    rigid = case["movement"] == "rigid"
    pos = np.asarray(case["start"], dtype=np.float64)
    out = Replay(str(case["id"]))
    for rnd in case["rounds"]:
        failed: dict[int, str] = {}
        planned: list[tuple[int, Point, Path]] = []
        for i in rnd["active"]:
            own = (float(pos[i, 0]), float(pos[i, 1]))
            try:
                local = algorithm.compute(view_of(pos, i, frames[i]), params)
            except ValueError as exc:
                failed[i] = f"{type(exc).__name__}: {exc}"
                continue
            planned.append((i, own, frames[i].path_to_global(local, own)))
        if mover is Mover.PEER and rigid and _rigid_crash([(s, p) for _, s, p in planned]):
            out.crashed = f"round {rnd['round']}: rigid line-then-arc move ends at its end"
            break
        new = pos.copy()
        try:
            for i, own, path in planned:
                new[i] = move(own, path, rigid, float(rnd["move_time"]), mover)
        except PeerCrash as exc:
            out.crashed = f"round {rnd['round']}: {exc}"
            break
        peer = np.asarray(
            [[np.nan if v is None else v for v in p] for p in rnd["positions"]], dtype=np.float64
        )
        scale = max(1.0, float(np.nanmax(np.abs(peer)))) if np.isfinite(peer).any() else 1.0
        err = float(np.nanmax(np.abs(new - peer))) / scale if np.isfinite(peer).all() else math.inf
        out.rounds.append(RoundResult(int(rnd["round"]), err, failed))
        if out.first_disagreement is None and (failed or not err <= COMPARE_REL):
            out.first_disagreement = int(rnd["round"])
        pos = new
    else:
        if case["stopped"] == "error":
            out.error_round_failed = _refusals(algorithm, pos, frames, params, rigid)
    return out


def _refusals(
    algorithm: Algorithm[Any],
    pos: Points,
    frames: Sequence[PeerFrame],
    params: OblotParams,
    rigid: bool,
) -> dict[int, str]:
    """Every robot's refusal (robot -> message) on `pos`, or the predicted crash of a rigid move
    (key -1) when nobody refuses."""
    failed: dict[int, str] = {}
    planned: list[tuple[Point, Path]] = []
    for i in range(len(pos)):
        own = (float(pos[i, 0]), float(pos[i, 1]))
        try:
            local = algorithm.compute(view_of(pos, i, frames[i]), params)
        except ValueError as exc:
            failed[i] = f"{type(exc).__name__}: {exc}"
            continue
        planned.append((own, frames[i].path_to_global(local, own)))
    if not failed and rigid and _rigid_crash(planned):
        failed[-1] = "PeerCrash: rigid line-then-arc move ends at its end"
    return failed


@dataclass(frozen=True, slots=True)
class Outcome:
    """A free run: the first round after which the goal held (None: never), the rounds run, and
    how it stopped: "goal", "cap" or "error" (with the refusal in `error`)."""

    goal_round: int | None
    rounds_run: int
    stopped: str
    error: str | None = None


def peer_goal(peer: str, start: Points) -> Callable[[Points], bool]:
    """The goal the peer's recorded runs were cut at (tests/data/oblot/README.md): every robot
    within 1e-9 * max(1, the start's diameter) of robot 0; for MoveAlongSEC, every robot on the
    smallest enclosing circle of the current positions within 1e-9 * max(1, its radius)."""
    if peer == "MoveAlongSEC":

        def on_circle(pos: Points) -> bool:
            circle = sec(pos)
            cx, cy = circle.center
            off = np.abs(np.hypot(pos[:, 0] - cx, pos[:, 1] - cy) - circle.radius)
            return bool(float(off.max()) <= 1e-9 * max(1.0, circle.radius))

        return on_circle
    diff = start[:, np.newaxis, :] - start[np.newaxis, :, :]
    bound = 1e-9 * max(1.0, float(np.hypot(diff[..., 0], diff[..., 1]).max()))

    def gathered(pos: Points) -> bool:
        return bool(float(np.hypot(pos[:, 0] - pos[0, 0], pos[:, 1] - pos[0, 1]).max()) <= bound)

    return gathered


def simulate(
    start: Points,
    frames: Sequence[PeerFrame],
    algorithm: Algorithm[Any],
    goal: Callable[[Points], bool],
    ssync: bool,
    rigid: bool,
    rng: np.random.Generator,
    cap: int,
    mover: Mover = Mover.FATSWARM,
) -> Outcome:
    """A free run of the port from `start` with draws of the peer's kind (not its draws): under
    SSYNC a uniformly random subset of 1 to n - 1 robots a round (for n = 1, the robot), under
    non-rigid moves one distance a round, uniform in [1, 5), for every active robot."""
    pos = np.asarray(start, dtype=np.float64).copy()
    n = len(pos)
    params = OblotParams(n, 0.0)
    for k in range(1, cap + 1):
        if ssync and n > 1:
            active = sorted(int(i) for i in rng.permutation(n)[: 1 + int(rng.integers(n - 1))])
        else:
            active = list(range(n))
        budget = 0.0 if rigid else float(rng.uniform(1.0, 5.0))
        new = pos.copy()
        for i in active:
            own = (float(pos[i, 0]), float(pos[i, 1]))
            try:
                local = algorithm.compute(view_of(pos, i, frames[i]), params)
            except ValueError as exc:
                return Outcome(None, k, "error", f"{type(exc).__name__}: {exc}")
            new[i] = move(own, frames[i].path_to_global(local, own), rigid, budget, mover)
        pos = new
        if goal(pos):
            return Outcome(k, k, "goal")
    return Outcome(None, cap, "cap")


__all__ = [
    "COMPARE_REL",
    "PEER_ALGORITHMS",
    "Mover",
    "Outcome",
    "PeerCrash",
    "PeerFrame",
    "Replay",
    "RoundResult",
    "frames_of",
    "move",
    "peer_goal",
    "replay",
    "simulate",
    "view_of",
]
