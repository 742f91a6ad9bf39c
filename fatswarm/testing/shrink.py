"""The shrinking of a failing view: robots dropped while it still breaks the property, then its
coordinates rounded to the fewest decimals that still break it."""

from __future__ import annotations

from typing import Final

from fatswarm.testing.look import Look
from fatswarm.testing.subject import Broken, Subject

# decimals a shrunk view's coordinates are rounded to, the fewest first, if it still breaks then
SHRINK_DECIMALS: Final = (0, 1, 2, 3, 4, 6)


def shrink_look(subject: Subject, broken: Broken, look: Look) -> Look:
    """The smallest look found that still breaks the property: robots dropped one at a time while
    it still breaks (down to one robot seen), then the coordinates rounded to the fewest decimals
    that still break it. Every look tried is of a start the algorithm accepts."""
    best = look
    dropped = True
    while dropped and len(best.view) > 1:
        dropped = False
        for row in range(len(best.view)):
            smaller = best.without(row)
            if subject.accepts(smaller) and broken(subject, smaller) is not None:
                best, dropped = smaller, True
                break
    for places in SHRINK_DECIMALS:
        simpler = best.rounded(places)
        if subject.accepts(simpler) and broken(subject, simpler) is not None:
            return simpler
    return best
