"""A robot's private frame: origin at the robot, then a rotation and possibly a mirror of X.

The world builds each view in the looker's frame and brings its path back to world axes, so the
frames stay the world's secret (docs/model.md, "Frames"). The paper's frames are the rotation 0:
a view is then mirrored by negation alone, the very bits it has always had.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np

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


__all__ = ["PAPER_FRAME", "Frame", "draw_frame"]
