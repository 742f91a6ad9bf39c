"""The test kit's report: the properties of the model's contract (RULES, CHECKS, in the order they
are checked), the error that names the one broken, and what a check that passed checked."""

from __future__ import annotations

import types
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

from fatswarm.deploy.hunt.search import Case
from fatswarm.domain.lights import Glance
from fatswarm.domain.path import Points

# The properties, in the order they are checked: a later one compares Computes, so it means
# something only once the earlier ones hold.
RULES: Final[Mapping[str, str]] = types.MappingProxyType(
    {
        "seam": "it must be an algorithm fatswarm can load (docs/algorithms.md, 'The contract')",
        "path": "compute must return a Path the world accepts (a Lit for a luminous algorithm), "
        "without raising, for every robot of a start it accepts",
        "palette": "compute_lit must show one of the algorithm's colours",
        "oblivious": "the same view must give the same path: nothing may survive a call (no state, "
        "no randomness), and the view must be left as it was",
        "order": "the path (and colour) must not depend on the order of the view's rows",
        "mirror": "mirroring the view (x -> -x) must mirror the path (frames 'y-axis')",
        "rotation": "rotating the view must rotate the path (frames 'chirality')",
        "rotation-mirror": "rotating and mirroring the view must rotate and mirror the path "
        "(frames 'disoriented')",
        "params": "a parameter value the algorithm cannot use must be refused with "
        "AlgorithmParamsError, in one line",
        "hunt": "a seeded hunt over the start families must find no collision and no stall",
    }
)
CHECKS: Final = tuple(RULES)


class AlgorithmContractError(AssertionError):
    """An algorithm breaks a property of the model's contract. `property` names it (one of
    CHECKS); `view` is the smallest view found that breaks it ((k, 2), the robot at the origin,
    in its own frame; None where no view is at fault), `glance` the colours shown with it (a
    luminous algorithm); for a hunt's failure, `positions` is the smallest start, `kind` the
    failure's kind (collision, stalled, max_rounds...) and `case` the run that replays it (a
    `fatswarm.deploy.hunt.search.Case`: start, active sets by round, seed)."""

    # A failing test shows it by this name, as it did before the kit was a package.
    __module__ = "fatswarm.testing"

    def __init__(
        self,
        algorithm: str,
        prop: str,
        detail: str,
        *,
        view: Points | None = None,
        glance: Glance | None = None,
        positions: Points | None = None,
        kind: str | None = None,
        case: Case | None = None,
    ) -> None:
        super().__init__(f"algorithm {algorithm!r} breaks {prop!r}: {RULES[prop]}\n{detail}")
        self.algorithm = algorithm
        self.property = prop
        self.detail = detail
        self.view = view
        self.glance = glance
        self.positions = positions
        self.kind = kind
        self.case = case


@dataclass(frozen=True, slots=True)
class Checked:
    """What `check_algorithm` checked: the properties, how many views (Looks) and hunt runs, how
    many hunt starts the algorithm refused, and the seconds it took."""

    algorithm: str
    checks: tuple[str, ...]
    looks: int
    hunt_runs: int
    refused: int
    seconds: float
