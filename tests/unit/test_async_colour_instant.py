"""Rule 7 under async (docs/model.md, "When a colour takes effect"): a colour shows at its Look's
time plus the compute delay; a Look at that very instant reads it, except the Looks of the very
instant at which that Compute began (a compute delay of 0: async-slowest's fastest robot), which
are simultaneous with it and read the colour before."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.domain.adversary import STALE_STEP, make_async
from fatswarm.domain.lights import Glance, Lit
from fatswarm.domain.path import Path, Points
from fatswarm.domain.seam import Configured, ParamSpec, ParamValue
from fatswarm.world import instants, looks


@dataclass(frozen=True, slots=True)
class _Params:
    n: int | None


class LightUp:
    """Every robot stays and shows `on` (a probe: what the others read is the test's)."""

    name = "light-up"
    summary = "stay and show on (test)"
    parameters: tuple[ParamSpec, ...] = ()
    colours = ("off", "on")
    frames = ("y-axis", "chirality", "disoriented")

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> _Params:
        del values
        return _Params(n)

    def compute(self, view: Points, params: _Params) -> Path:
        return self.compute_lit(view, Glance("off", None), params).path

    def compute_lit(self, view: Points, glance: Glance | None, params: _Params) -> Lit:
        del view, glance, params
        return Lit(Path(), "on")

    def goal(self, positions: Points, params: _Params) -> bool:
        del positions, params
        return True


@pytest.mark.parametrize("seed", range(6))
def test_a_look_reads_a_colour_from_the_instant_it_shows_but_not_a_simultaneous_looks(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    n = 4
    clock: list[Any] = []
    read: list[tuple[float, int, int]] = []  # (time, robot, how many `on` it read)
    init, view = instants.Instants.__init__, looks.Looks.view

    def keep(self: Any, books: Any) -> None:
        init(self, books)
        clock.append(self.clock)

    def served(self: Any, positions: Points, robot: int, look_round: int) -> Any:
        seen = view(self, positions, robot, look_round)
        read.append((clock[0].now, robot, sum(c == 1 for c in seen[1] or ())))
        return seen

    monkeypatch.setattr(instants.Instants, "__init__", keep)
    monkeypatch.setattr(looks.Looks, "view", served)
    model = make_async("async-slowest", n, seed)
    start = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [10.0, 10.0]])
    run_lockstep(start, Configured.of(LightUp(), n), model, seed=seed)
    # every robot Looks first at 0 and shows `on` after its compute delay, 2 * its rank
    shows = {r: STALE_STEP * model.rank(r) for r in range(n)}
    assert read and read[0][0] == 0.0
    for t, robot, on in read:
        expected = sum(
            1
            for j, at in shows.items()
            if j != robot and (at < t or (at == t and at > 0.0))  # not the Looks of its own Look
        )
        assert on == expected, (t, robot)
    # both halves happen: a Look at the very instant a delayed colour shows, and Looks at 0
    assert any(t == at > 0.0 for t, _, _ in read for at in shows.values())
    assert sum(t == 0.0 for t, _, _ in read) == n
