"""The robot model a run enforces, beyond its scheduler: what a robot sees, whose lights it reads,
and how its private frame relates to the world's (docs/model.md).

The default is the reference paper's model: transparent discs, unlimited sight, full lights (for
an algorithm that has any) and one-axis agreement (shared Y, X mirrored at random) fixed for the
run. A record's header names a model only when it is not this one, so the records of the paper's
model read as they always have.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Final, TypeVar


class ModelError(ValueError):
    """A model setting that no run can use (the message says which, and what is allowed)."""


class Visibility(enum.StrEnum):
    """Whether bodies hide one another from an observer."""

    TRANSPARENT = "transparent"  # nothing hides anything (the paper's)
    OPAQUE = "opaque"  # seen iff some point of the disc is reachable from the observer's centre
    OPAQUE_CENTRES = "opaque-centres"  # seen iff the segment between the centres is clear


class Lights(enum.StrEnum):
    """Whose colours a robot reads (only for an algorithm that declares colours)."""

    FULL = "full"  # its own and those of the robots it sees (LUMI)
    INTERNAL = "internal"  # only its own (FSTA: a finite state)
    EXTERNAL = "external"  # only the others' (FCOM: finite communication)


class Frames(enum.StrEnum):
    """What robots agree on about their private frames (origin always at the robot, unit 1)."""

    Y_AXIS = "y-axis"  # shared Y direction and sense, X mirrored at random (the paper's)
    CHIRALITY = "chirality"  # a random rotation each, a common handedness
    DISORIENTED = "disoriented"  # a random rotation and a random reflection each


class FrameChange(enum.StrEnum):
    """How long a robot's private frame lasts."""

    FIXED = "fixed"  # one frame per robot for the whole run
    EVERY_LOOK = "every-look"  # a new frame at each Look (the variable-frames adversary)


MODEL_KEYS: Final = ("visibility", "sight", "lights", "frames", "frame_change")


@dataclass(frozen=True, slots=True)
class RobotModel:
    """One run's model axes; `sight` None is unlimited. Build it with `RobotModel.of`."""

    visibility: Visibility = Visibility.TRANSPARENT
    sight: float | None = None
    lights: Lights = Lights.FULL
    frames: Frames = Frames.Y_AXIS
    frame_change: FrameChange = FrameChange.FIXED

    @staticmethod
    def of(
        visibility: str = Visibility.TRANSPARENT,
        sight: float | None = None,
        lights: str = Lights.FULL,
        frames: str = Frames.Y_AXIS,
        frame_change: str = FrameChange.FIXED,
    ) -> RobotModel:
        """The model these names give; raises ModelError naming the bad value and the choices."""
        if sight is not None and (
            isinstance(sight, bool)
            or not isinstance(sight, (int, float))
            or not (math.isfinite(sight) and sight > 0)
        ):
            raise ModelError(f"--sight must be a finite distance > 0 (robot radii), got {sight!r}")
        return RobotModel(
            _choice(Visibility, visibility, "--visibility"),
            None if sight is None else float(sight),
            _choice(Lights, lights, "--lights"),
            _choice(Frames, frames, "--frames"),
            _choice(FrameChange, frame_change, "--frame-change"),
        )

    @property
    def is_paper(self) -> bool:
        """Whether this is the reference paper's model (the default)."""
        return self == PAPER_MODEL

    @property
    def sees_all(self) -> bool:
        """Whether every robot sees every other (transparent, unlimited sight)."""
        return self.visibility is Visibility.TRANSPARENT and self.sight is None

    def to_header(self) -> dict[str, Any]:
        """The record header's `model` object (every axis, by its flag's value)."""
        return {
            "visibility": str(self.visibility),
            "sight": self.sight,
            "lights": str(self.lights),
            "frames": str(self.frames),
            "frame_change": str(self.frame_change),
        }

    @staticmethod
    def from_header(obj: object) -> RobotModel:
        """The model of a record's header `model` object (None or absent: the paper's);
        raises ModelError for one that is not of this shape."""
        if obj is None:
            return PAPER_MODEL
        if not isinstance(obj, Mapping) or set(obj) - set(MODEL_KEYS):
            raise ModelError(f"a record's model must be an object with keys {MODEL_KEYS}")
        defaults = PAPER_MODEL.to_header()
        given = {key: obj.get(key, defaults[key]) for key in MODEL_KEYS}
        for key in ("visibility", "lights", "frames", "frame_change"):
            if not isinstance(given[key], str):
                raise ModelError(f"a record's model {key} must be a name, got {given[key]!r}")
        return RobotModel.of(**given)

    def describe(self) -> str:
        """The axes that differ from the paper's, as flags (`paper model` if none do)."""
        differ = [
            f"--{key.replace('_', '-')} {value}"
            for key, value in self.to_header().items()
            if value != PAPER_MODEL.to_header()[key]
        ]
        return " ".join(differ) or "paper model"


PAPER_MODEL: Final = RobotModel()


E = TypeVar("E", bound=enum.StrEnum)


def _choice(kind: type[E], value: str, flag: str) -> E:
    """`value` as a member of `kind`; raises ModelError listing the choices."""
    try:
        return kind(value)
    except ValueError:
        choices = ", ".join(member.value for member in kind)
        raise ModelError(f"{flag} must be one of {choices}, got {value!r}") from None


__all__ = [
    "MODEL_KEYS",
    "PAPER_MODEL",
    "FrameChange",
    "Frames",
    "Lights",
    "ModelError",
    "RobotModel",
    "Visibility",
]
