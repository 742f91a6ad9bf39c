"""`uniform-circle-lights`: the paper's algorithm for asynchronous robots, with three colours.

The paper's proof is for semi-synchronous robots: the robots that move in a round all Looked at
the same configuration, and nobody Looks while a robot moves. Under ASYNC neither holds. A robot
that decided to move is invisible until its move starts (a long Compute), and a robot that Looks
while another moves plans on a configuration that is not at rest. This variant keeps the paper's
plan (`agent/algorithm.py`: one mover or one mirror pair per configuration, `M(Q)`) and adds a
rule with lights so that every move is made from a configuration at rest, and every two moves
that overlap in time were planned on the same configuration, by the two robots of `M(Q)`: an
SSYNC round whose two movers run at any relative speed, which the paper's pair rule (G11) covers.

Colours (the first is every robot's at the start):

- `off`: idle;
- `ready`: elected by the plan and announced; it moves only in a later cycle;
- `moving`: shown from the start of the move; after the move it stays shown while any other
  robot is `ready` (one of those may still be about to move on the configuration before this
  move), then goes back to `off`.

One Look, in this order (Q: the positions seen; M(Q): the plan's movers):

1. own `moving` (the move has ended): stay; `moving` while another robot is `ready`, else `off`;
2. another robot `moving`: stay; `off` (a `ready` robot gives up its turn);
3. own `off`: stay; `ready` if every other robot is `off` and it is in M(Q), else `off`;
4. own `ready`: not in M(Q): stay, `off`; some `ready` robot not in M(Q): stay, `ready`;
   otherwise move on the paper's path from Q, showing `moving`.

docs/algorithm.md ("A luminous variant") argues why no two moves from different configurations
can overlap, and what is argued rather than proven.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from fatswarm.agent import algorithm, uniform_circle
from fatswarm.agent.canonical import SharedForm
from fatswarm.agent.params import Params
from fatswarm.domain.assumptions import PAPER_ASSUMPTIONS, Assumptions
from fatswarm.domain.lights import Glance, Lit
from fatswarm.domain.path import STAY, Path, Points
from fatswarm.domain.robot_model import Lights
from fatswarm.domain.seam import ParamSpec, ParamValue
from fatswarm.domain.tolerance import snap

OFF: Final = "off"
READY: Final = "ready"
MOVING: Final = "moving"
COLOURS: Final = (OFF, READY, MOVING)


@dataclass(frozen=True, slots=True)
class Election:
    """The paper's plan of one view: whether the observer and each robot of the view (its rows)
    are movers, and the observer's own path in its frame (STAY if it is not a mover)."""

    own: bool
    rows: tuple[bool, ...]
    path: Path


def elect(view: Points, params: Params) -> Election:
    """The plan of the configuration the observer sees (the paper's, on the canonical form, the
    same bits in every robot), with every robot of the view placed in it."""
    canon = algorithm.canonical_view(view, params)  # checks the view, snaps it to the grid
    points = np.vstack([np.zeros((1, 2)), np.asarray(view, dtype=np.float64).reshape(-1, 2)])
    form = SharedForm.of(snap(points))
    made = algorithm.plan(form.points, params)
    movers = frozenset(made.moves)
    rank = form.rank_up if form.form.sign > 0.0 else form.rank_down
    rows = tuple(int(rank[i]) in movers for i in range(1, len(points)))
    mine = made.moves.get(canon.observer, STAY)
    return Election(canon.observer in movers, rows, canon.to_frame(mine))


def read_glance(glance: Glance | None, rows: int) -> tuple[str, tuple[str, ...]]:
    """(own colour, the others' colours lined up with the view); what the model hides reads as
    `off` (the rule needs `--lights full`: docs/algorithm.md)."""
    own = OFF if glance is None or glance.own is None else glance.own
    others = glance.others if glance is not None and glance.others is not None else None
    if others is None or len(others) != rows:
        others = (OFF,) * rows
    return own, tuple(others)


def decide(view: Points, own: str, others: Sequence[str], params: Params) -> Lit:
    """One Look of the rule (module docstring), from the colours already read."""
    if own == MOVING:
        return Lit(STAY, MOVING if READY in others else OFF)
    if MOVING in others:
        return Lit(STAY, OFF)
    if own != READY and any(c != OFF for c in others):
        return Lit(STAY, OFF)
    chosen = elect(view, params)
    if own != READY:
        return Lit(STAY, READY if chosen.own else OFF)
    if not chosen.own:
        return Lit(STAY, OFF)
    if any(c == READY and not mover for c, mover in zip(others, chosen.rows, strict=True)):
        return Lit(STAY, READY)
    return Lit(chosen.path, MOVING)


class LitUniformCircle:
    """The paper's algorithm made safe for ASYNC robots by three colours (docs/algorithm.md)."""

    name = "uniform-circle-lights"
    summary = "the paper's algorithm with 3 colours: announce, move, clear (for async robots)"
    parameters: tuple[ParamSpec, ...] = uniform_circle.UniformCircle.parameters
    colours: tuple[str, ...] = COLOURS
    # the paper's model, but for any scheduler (async its aim), reading every colour: under
    # --lights internal it collided in 2 of 42 async runs
    assumptions: Assumptions = dataclasses.replace(
        PAPER_ASSUMPTIONS, lights=(Lights.FULL,), schedulers=None
    )

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> Params:
        return uniform_circle.ALGORITHM.make_params(n, values)

    def compute(self, view: Points, params: Params) -> Path:
        """The path of a robot that sees every robot, itself included, `off` (the start)."""
        return self.compute_lit(view, Glance(OFF, (OFF,) * len(view)), params).path

    def compute_lit(self, view: Points, glance: Glance | None, params: Params) -> Lit:
        own, others = read_glance(glance, len(view))
        return decide(view, own, others, params)

    def goal(self, positions: Points, params: Params) -> bool:
        return uniform_circle.ALGORITHM.goal(positions, params)

    def check_start(self, positions: Points, params: Params) -> None:
        uniform_circle.ALGORITHM.check_start(positions, params)

    def figures(self, positions: Points, params: Params) -> dict[str, float]:
        return uniform_circle.ALGORITHM.figures(positions, params)


ALGORITHM: Final = LitUniformCircle()

__all__ = [
    "ALGORITHM",
    "COLOURS",
    "MOVING",
    "OFF",
    "READY",
    "Election",
    "LitUniformCircle",
    "decide",
    "elect",
    "read_glance",
]
