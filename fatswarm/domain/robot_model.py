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
from dataclasses import Field, dataclass, field, fields
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
    BOTH_AXES = "both-axes"  # every frame a translation of the world's: both axes agreed


class Bodies(enum.StrEnum):
    """What a robot is: a disc of radius 1 (the unit of every distance) or a point."""

    FAT = "fat"  # unit discs that touch but never overlap (the paper's)
    POINTS = "points"  # radius 0: robots may meet and share a position (multiplicity)


class FrameChange(enum.StrEnum):
    """How long a robot's private frame lasts."""

    FIXED = "fixed"  # one frame per robot for the whole run
    EVERY_LOOK = "every-look"  # a new frame at each Look (the variable-frames adversary)


Value = str | float | None  # an axis's value as the header, a flag and a CSV cell carry it


@dataclass(frozen=True, slots=True)
class Axis:
    """One axis of the robot model, declared once: the flag of run, sweep and hunt, the API
    keyword, the header's `model` key, the sweep's CSV column and the `--resume` check all follow
    from it (`AXES`). A word axis has `choices` (its enum); a number axis has none.

    `unset`: the flag's word for a number axis's None (sight: `unlimited`). `above`: a number
    must be > it (`inclusive`: >= it). `tag`: the axis in a model label (`+sight5`, `+noise0.5`).
    `always`: the header's `model` writes it even at its default (the axes the model object had
    from its first record); a later axis is written only when set, so a record that leaves it at
    its default is the record of the release before it, byte for byte.
    """

    name: str  # header key, CSV column and API keyword (`frame_change`)
    default: Value
    help: str
    literature: str  # the axis's name in the literature (docs/model.md, "Vocabulary")
    choices: type[enum.StrEnum] | None = None  # a word axis's enum; None: a number (robot radii)
    unset: str | None = None  # a number axis's word for None
    above: float = 0.0
    inclusive: bool = False
    tag: str = ""
    always: bool = True
    metavar: str = "V"  # a number axis's value in `--help`

    @property
    def flag(self) -> str:
        """`--frame-change` for frame_change."""
        return "--" + self.name.replace("_", "-")

    @property
    def words(self) -> tuple[str, ...]:
        """A word axis's values, the default first; () for a number axis."""
        return () if self.choices is None else tuple(m.value for m in self.choices)

    def check(self, value: object) -> Value:
        """`value` as this axis holds it (a member, a float or None); ModelError naming the flag
        and what it takes."""
        if self.choices is not None:
            if isinstance(value, str):
                return _choice(self.choices, value, self.flag)
            raise ModelError(f"{self.flag} must be a name, got {value!r}")
        if value is None and self.unset is not None:
            return None
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
            or not (value >= self.above if self.inclusive else value > self.above)
        ):
            bound = (">= " if self.inclusive else "> ") + f"{self.above:g}"
            raise ModelError(
                f"{self.flag} must be a finite distance {bound} (robot radii), got {value!r}"
            )
        return float(value)

    def parse(self, text: str) -> Value:
        """A flag's or a CSV cell's text as a value (`unset`'s word: None); ModelError."""
        if self.choices is not None:
            return self.check(text)
        if self.unset is not None and text.lower() == self.unset:
            return None
        try:
            number = float(text)
        except ValueError:
            number = math.nan
        try:
            return self.check(number)
        except ModelError:
            words = "" if self.unset is None else f" or {self.unset}"
            bound = (">= " if self.inclusive else "> ") + f"{self.above:g}"
            raise ModelError(
                f"{self.flag} takes distances {bound} (robot radii){words}, got {text!r}"
            ) from None

    def text(self, value: Value) -> str:
        """A value as its flag takes it back exactly (numbers by repr; None: `unset`)."""
        if value is None:
            return self.unset or ""
        return repr(value) if isinstance(value, float) else str(value)

    def label(self, value: Value) -> str:
        """The value in a model label, after `tag` (`5` for sight 5.0, `opaque`; None: `unset`)."""
        if value is None:
            return self.unset or "none"
        return f"{value:g}" if isinstance(value, float) else str(value)


def axis(*, help: str, literature: str, **more: Any) -> dict[str, Any]:
    """The metadata that makes a field of `RobotModel` an axis: the rest of its `Axis` (its name
    and default are the field's)."""
    return {AXIS: {"help": help, "literature": literature, **more}}


AXIS: Final = "axis"  # the metadata key of an axis field


def _axis_of(f: Field[Any]) -> Axis:
    """The `Axis` a field of `RobotModel` declares (a word axis: its default's enum)."""
    default: Value = f.default  # type: ignore[assignment]  # every axis has a default
    choices = type(default) if isinstance(default, enum.StrEnum) else None
    return Axis(name=f.name, default=default, choices=choices, **f.metadata[AXIS])


@dataclass(frozen=True, slots=True)
class RobotModel:
    """One run's model axes, each declared once here (`AXES` lists them); `sight` None is
    unlimited. Build it with `RobotModel.of`."""

    visibility: Visibility = field(
        default=Visibility.TRANSPARENT,
        metadata=axis(
            help="transparent: robots never hide one another (the paper's); opaque: a robot "
            "sees another if some point of its disc is reachable from the observer's centre by a "
            "segment crossing no third disc; opaque-centres: if the segment between the centres "
            "crosses none",
            literature="transparent / obstructed (opaque) visibility",
        ),
    )
    sight: float | None = field(
        default=None,
        metadata=axis(
            help="a robot sees only the robots whose centre is within V of its own (V > 0, robot "
            "radii; default unlimited)",
            literature="limited visibility (visibility radius V)",
            unset="unlimited",
            tag="sight",
        ),
    )
    lights: Lights = field(
        default=Lights.FULL,
        metadata=axis(
            help="whose colours a luminous algorithm reads: full (its own and the seen robots'), "
            "internal (only its own: FSTA), external (only the others': FCOM)",
            literature="luminous robots: LUMI (FULL) / FSTA / FCOM",
            tag="lights-",
        ),
    )
    frames: Frames = field(
        default=Frames.Y_AXIS,
        metadata=axis(
            help="the robots' private frames: y-axis (shared Y, X mirrored at random: the "
            "paper's), chirality (a random rotation, common handedness), disoriented (a random "
            "rotation and reflection), both-axes (every frame a translation of the world's: "
            "oblot-sim's default)",
            literature="one-axis agreement / chirality / disorientation / total agreement",
        ),
    )
    frame_change: FrameChange = field(
        default=FrameChange.FIXED,
        metadata=axis(
            help="fixed: one frame per robot for the run; every-look: a new frame at each Look",
            literature="fixed / variable frames",
        ),
    )
    noise: float = field(
        default=0.0,
        metadata=axis(
            help="inaccurate sensors: each position a Look shows is off by a Gaussian error of "
            "standard deviation SIGMA in each axis (>= 0, robot radii; default 0: exact), drawn "
            "by the world from the seed, the robot and its Look",
            literature="inaccurate sensors (error sigma; Cohen and Peleg 2008)",
            above=0.0,
            inclusive=True,
            tag="noise",
            always=False,
            metavar="SIGMA",
        ),
    )
    bodies: Bodies = field(
        default=Bodies.FAT,
        metadata=axis(
            help="fat: unit discs that touch but never overlap (the paper's); points: radius 0, "
            "robots may meet and share a point (multiplicity), meeting is no collision",
            literature="fat robots / point robots",
            tag="",
            always=False,
        ),
    )

    @staticmethod
    def of(*values: object, **named: object) -> RobotModel:
        """The model these values give, by axis (positional ones in `AXES` order; unset ones:
        the paper's); raises ModelError naming the bad value and what is allowed."""
        if len(values) > len(AXES):
            raise ModelError(f"a robot model has {len(AXES)} axes, got {len(values)} values")
        given = dict(zip(AXIS_NAMES, values, strict=False))
        unknown = set(named) - set(AXIS_NAMES) | set(given) & set(named)
        if unknown:
            raise ModelError(f"a robot model's axes are {', '.join(AXIS_NAMES)}, got {unknown}")
        given.update(named)
        return RobotModel(*(a.check(given.get(a.name, a.default)) for a in AXES))  # type: ignore[arg-type]

    def value(self, name: str) -> Value:
        """The value of the axis `name`."""
        value: Value = getattr(self, name)
        return value

    @property
    def is_paper(self) -> bool:
        """Whether this is the reference paper's model (the default)."""
        return self == PAPER_MODEL

    @property
    def sees_all(self) -> bool:
        """Whether every robot sees every other (transparent, unlimited sight)."""
        return self.visibility is Visibility.TRANSPARENT and self.sight is None

    def changed(self) -> tuple[Axis, ...]:
        """The axes whose value is not the paper's."""
        return tuple(a for a in AXES if self.value(a.name) != a.default)

    def to_header(self) -> dict[str, Any]:
        """The record header's `model` object: every axis by its flag's value (an axis declared
        after the model object, only when set: `Axis.always`)."""
        return {
            a.name: _plain(self.value(a.name))
            for a in AXES
            if a.always or self.value(a.name) != a.default
        }

    @staticmethod
    def from_header(obj: object) -> RobotModel:
        """The model of a record's header `model` object (None or absent: the paper's);
        raises ModelError for one that is not of this shape."""
        if obj is None:
            return PAPER_MODEL
        if not isinstance(obj, Mapping) or set(obj) - set(AXIS_NAMES):
            raise ModelError(f"a record's model must be an object with keys {AXIS_NAMES}")
        for a in AXES:
            if a.choices is not None and not isinstance(obj.get(a.name, a.default), str):
                raise ModelError(f"a record's model {a.name} must be a name, got {obj[a.name]!r}")
        return RobotModel.of(**obj)

    @property
    def short(self) -> str:
        """The model in one word, as a sweep's label ends (`fsync+opaque+sight5`): the axes that
        are not the paper's, each `TAGVALUE`, joined by `+` (`opaque+sight5+chirality`); `paper`
        for the paper's model. What the dashboard, the summary and a result's repr name."""
        changed = (f"{a.tag}{a.label(self.value(a.name))}" for a in self.changed())
        return "+".join(changed) or PAPER_WORD

    def describe(self) -> str:
        """The axes that differ from the paper's, as flags (`paper model` if none do)."""
        differ = [f"{a.flag} {_plain(self.value(a.name))}" for a in self.changed()]
        return " ".join(differ) or "paper model"


AXES: Final = tuple(_axis_of(f) for f in fields(RobotModel) if AXIS in f.metadata)
"""Every axis of the robot model, in declaration order: what every carrier iterates."""
AXIS_NAMES: Final = tuple(a.name for a in AXES)
MODEL_KEYS: Final = AXIS_NAMES  # the header's `model` keys (the sweep's model columns)


PAPER_MODEL: Final = RobotModel()
PAPER_WORD: Final = "paper"  # `RobotModel.short` of the paper's model


E = TypeVar("E", bound=enum.StrEnum)


def _plain(value: Value) -> Any:
    """An axis's value as JSON holds it (a member by its name)."""
    return str(value) if isinstance(value, enum.StrEnum) else value


def short_of_header(obj: object) -> str:
    """`RobotModel.short` of a record header's `model` object (None: `paper`), `unreadable` for
    one that no run writes: the one word a summary names a record's model by."""
    try:
        return RobotModel.from_header(obj).short
    except ModelError:
        return "unreadable"


def axis_named(name: str) -> Axis:
    """The axis `name` (`frame_change`); KeyError for none."""
    return AXES[AXIS_NAMES.index(name)]


def _choice(kind: type[E], value: str, flag: str) -> E:
    """`value` as a member of `kind`; raises ModelError listing the choices."""
    try:
        return kind(value)
    except ValueError:
        choices = ", ".join(member.value for member in kind)
        raise ModelError(f"{flag} must be one of {choices}, got {value!r}") from None


__all__ = [
    "AXES",
    "AXIS_NAMES",
    "MODEL_KEYS",
    "PAPER_MODEL",
    "PAPER_WORD",
    "Axis",
    "Bodies",
    "FrameChange",
    "Frames",
    "Lights",
    "ModelError",
    "RobotModel",
    "Value",
    "Visibility",
    "axis_named",
    "short_of_header",
]
