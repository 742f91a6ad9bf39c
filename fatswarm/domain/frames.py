"""A robot's private frame: origin at the robot, then a rotation and possibly a mirror of X.

The world builds each view in the looker's frame and brings its path back to world axes, so the
frames stay the world's secret (docs/model.md, "Frames"). The paper's frames are the rotation 0:
a view is then mirrored by negation alone, the very bits it has always had.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.draws import FRAME_LOOK_STREAM, ROTATION_STREAM, draw_flip, keyed_fraction
from fatswarm.domain.path import Arc, Line, Path, Point, Points, Segment
from fatswarm.domain.robot_model import FrameChange, Frames, RobotModel


@dataclass(frozen=True, slots=True)
class Frame:
    """local = R(rotation) . M . (world - robot), M mirroring X when `mirror`."""

    rotation: float = 0.0  # radians, counter-clockwise
    mirror: bool = False

    def to_local(self, relative: Points) -> Points:
        """Positions relative to the robot (world axes) in this frame (a new array)."""
        view = np.array(relative, dtype=np.float64)
        if self.mirror:
            view[:, 0] *= -1.0
        if self.rotation:
            c, s = math.cos(self.rotation), math.sin(self.rotation)
            x, y = view[:, 0].copy(), view[:, 1].copy()
            view[:, 0] = c * x - s * y
            view[:, 1] = s * x + c * y
        return view

    def path_to_world(self, path: Path) -> Path:
        """A path computed in this frame, relative to the robot, in world axes."""
        if not self.rotation and not self.mirror:
            return path
        sx = -1.0 if self.mirror else 1.0
        if not self.rotation:  # a mirror alone (the paper's frames): the common case inline
            return Path(
                tuple(
                    [
                        Line((sx * seg.end[0], seg.end[1]))
                        if isinstance(seg, Line)
                        else Arc((sx * seg.center[0], seg.center[1]), sx * seg.sweep)
                        for seg in path.segments
                    ]
                )
            )
        c, s = math.cos(-self.rotation), math.sin(-self.rotation)

        def back(p: Point) -> Point:
            x, y = c * p[0] - s * p[1], s * p[0] + c * p[1]
            return (sx * x, y)

        segments: list[Segment] = [
            Line(back(seg.end)) if isinstance(seg, Line) else Arc(back(seg.center), sx * seg.sweep)
            for seg in path.segments
        ]
        return Path(tuple(segments))


PAPER_FRAME: Final = Frame()


@dataclass(frozen=True, slots=True, eq=False)  # holds arrays
class FrameRows:
    """k frames as arrays, row i frame i's: what `Frame` does to one robot's path, done to k
    robots' straight lines at once (`lines_to_world`)."""

    sign: NDArray[np.float64]  # (k,) -1.0 where the frame is a mirror alone, else 1.0
    turns: NDArray[np.bool_]  # (k,) whether the frame turns (a rotation other than 0)
    cos_back: NDArray[np.float64]  # (k,) math.cos(-rotation) (1.0 where it does not turn)
    sin_back: NDArray[np.float64]  # (k,) math.sin(-rotation) (0.0 where it does not turn)
    turned_sign: NDArray[np.float64]  # (k,) -1.0 where the frame mirrors, else 1.0
    factors: NDArray[np.float64]  # (k, 2) row i (sign[i], 1.0): x mirrored alone, y as it is
    turning: int  # how many frames turn (turns' count)

    @staticmethod
    def of(frames: Sequence[Frame]) -> FrameRows:
        """The rows of `frames`, in order (each number as `path_to_world` computes it)."""
        back = [
            (math.cos(-f.rotation), math.sin(-f.rotation)) if f.rotation else (1.0, 0.0)
            for f in frames
        ]
        return FrameRows.made(
            sign=np.array([-1.0 if f.mirror and not f.rotation else 1.0 for f in frames]),
            turns=np.array([bool(f.rotation) for f in frames], dtype=np.bool_),
            cos_back=np.array([c for c, _ in back], dtype=np.float64),
            sin_back=np.array([s for _, s in back], dtype=np.float64),
            turned_sign=np.array([-1.0 if f.mirror else 1.0 for f in frames]),
        )

    @staticmethod
    def made(
        sign: NDArray[np.float64],
        turns: NDArray[np.bool_],
        cos_back: NDArray[np.float64],
        sin_back: NDArray[np.float64],
        turned_sign: NDArray[np.float64],
    ) -> FrameRows:
        """The rows of these arrays, with what every round would ask of them made once."""
        factors = np.ones((len(sign), 2), dtype=np.float64)
        factors[:, 0] = sign
        turning = int(np.count_nonzero(turns))
        return FrameRows(sign, turns, cos_back, sin_back, turned_sign, factors, turning)

    def take(self, rows: NDArray[np.intp]) -> FrameRows:
        """The frames of `rows`, in their order."""
        return FrameRows.made(
            self.sign[rows],
            self.turns[rows],
            self.cos_back[rows],
            self.sin_back[rows],
            self.turned_sign[rows],
        )

    def lines_to_world(self, ends: Points) -> Points:
        """(k, 2): row i the end of a straight line computed in frame i (relative to its robot),
        in world axes (a new array): `Frame.path_to_world` of `Path((Line(ends[i]),))` for every
        row, with its very operations, so the very bits (x * 1.0 is x, y * 1.0 is y; the turned
        rows alone are turned, each float as `back` makes it)."""
        local = np.asarray(ends, dtype=np.float64)
        world: Points = local * self.factors  # the mirror alone: -x, bit for bit; x elsewhere
        if self.turning == len(self.turns):  # every frame turns (as drawn rotations do)
            x, y, c, s = local[:, 0], local[:, 1], self.cos_back, self.sin_back
            world[:, 0] = self.turned_sign * (c * x - s * y)
            world[:, 1] = s * x + c * y
        elif self.turning:
            at = np.flatnonzero(self.turns)
            x, y = local[at, 0], local[at, 1]
            c, s = self.cos_back[at], self.sin_back[at]
            world[at, 0] = self.turned_sign[at] * (c * x - s * y)
            world[at, 1] = s * x + c * y
        return world


def draw_frame(model: RobotModel, seed: int, robot: int, look_round: int) -> Frame:
    """Robot `robot`'s frame for its Look in round `look_round` under `model`: a pure function of
    the seed, the robot and (with `--frame-change every-look`) the round of its Look."""
    if model.frames is Frames.BOTH_AXES:
        return PAPER_FRAME  # both axes agreed: the world's, translated to the robot
    every = model.frame_change is FrameChange.EVERY_LOOK
    keys = (robot, look_round) if every else (robot,)
    if model.frames is Frames.Y_AXIS:
        if not every:
            return Frame(0.0, draw_flip(seed, robot))  # the paper's draw, unchanged
        return Frame(0.0, keyed_fraction(FRAME_LOOK_STREAM, seed, *keys) < 0.5)
    rotation = 2.0 * math.pi * keyed_fraction(ROTATION_STREAM, seed, *keys)
    if model.frames is Frames.CHIRALITY:
        return Frame(rotation, False)
    return Frame(rotation, keyed_fraction(FRAME_LOOK_STREAM, seed, *keys) < 0.5)


__all__ = ["PAPER_FRAME", "Frame", "FrameRows", "draw_frame"]
