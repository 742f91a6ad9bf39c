"""Lights: the colours a luminous algorithm declares, what a robot reads of them in a Look, and
what its Compute returns (docs/model.md, "Lights"; docs/algorithms.md shows one).

An algorithm is luminous when it declares `colours`, a tuple of names whose first is every
robot's colour at the start; fatswarm then calls its `compute_lit(view, glance, params)` for a
`Lit` (a path and the colour to show from the start of the move) instead of `compute`. The world
holds the colours by index; names are for the algorithm, the record and the pictures.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

from fatswarm.domain.path import Path

MAX_COLOURS: Final = 16  # the palettes of the literature have 2 to 7
# The colours every picture draws lights in (replay, plot, the notebook's): a record's colour names,
# sorted, get these in order (deploy/view/lights.py says why). Okabe and Ito's colours (told apart
# under the common colour blindnesses) first, then Paul Tol's "muted" scheme for palettes of more
# than seven (MAX_COLOURS of them).
LIGHT_HEX: Final = (
    "#E69F00",  # orange
    "#56B4E9",  # sky blue
    "#009E73",  # bluish green
    "#F0E442",  # yellow
    "#0072B2",  # blue
    "#D55E00",  # vermillion
    "#CC79A7",  # reddish purple
    "#88CCEE",  # cyan
    "#44AA99",  # teal
    "#117733",  # green
    "#999933",  # olive
    "#DDCC77",  # sand
    "#CC6677",  # rose
    "#882255",  # wine
    "#AA4499",  # purple
    "#332288",  # indigo
)
_NAME = re.compile(r"[A-Za-z0-9_.-]{1,32}")


class LightsError(ValueError):
    """A palette or a colour an algorithm gives that fatswarm cannot use (the message says why)."""


@dataclass(frozen=True, slots=True)
class Glance:
    """The colours a Look shows: `others` lines up with the view's rows (None when the model hides
    them: `--lights internal`), `own` is the robot's (None under `--lights external`)."""

    own: str | None
    others: tuple[str, ...] | None


@dataclass(frozen=True, slots=True)
class Lit:
    """A luminous Compute's answer: the path, and the colour shown from the start of the move."""

    path: Path
    colour: str


def palette(algorithm: Any) -> tuple[str, ...]:
    """The colours `algorithm` declares (empty: not luminous); raises LightsError for a palette
    that is not 1 to MAX_COLOURS distinct short names."""
    colours = getattr(algorithm, "colours", ())
    if colours == ():
        return ()
    if (
        not isinstance(colours, tuple)
        or not 0 < len(colours) <= MAX_COLOURS
        or not all(isinstance(c, str) and _NAME.fullmatch(c) for c in colours)
        or len(set(colours)) != len(colours)
    ):
        raise LightsError(
            f"algorithm {getattr(algorithm, 'name', '?')}: colours must be a tuple of 1 to "
            f"{MAX_COLOURS} distinct names (letters, digits, '-', '_', '.'), got {colours!r}"
        )
    return colours


def colour_index(colours: Sequence[str], colour: object, who: str) -> int:
    """The index of `colour` in the palette; raises LightsError naming the palette."""
    if isinstance(colour, str) and colour in colours:
        return list(colours).index(colour)
    raise LightsError(f"{who} returned colour {colour!r}, not one of {', '.join(colours)}")


def glance_of(
    colours: Sequence[str], own: int | None, others: Sequence[int] | None
) -> Glance | None:
    """What a Look shows of the lights, by name, from the palette indices a snapshot carries
    (None for an algorithm without lights)."""
    if not colours:
        return None
    return Glance(
        None if own is None else colours[own],
        None if others is None else tuple(colours[c] for c in others),
    )


__all__ = [
    "LIGHT_HEX",
    "MAX_COLOURS",
    "Glance",
    "LightsError",
    "Lit",
    "colour_index",
    "glance_of",
    "palette",
]
