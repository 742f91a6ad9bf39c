"""The entry point: `check_algorithm` refuses arguments it cannot use, chooses the properties that
apply, and checks them in order (the views', the parameters', the hunt)."""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping, Sequence
from typing import Final

from fatswarm.deploy.hunt.search import hunt_models
from fatswarm.domain.robot_model import Frames
from fatswarm.domain.seam import AlgorithmParamsError, Configured
from fatswarm.testing.hunt import run_hunt
from fatswarm.testing.params import check_params
from fatswarm.testing.properties import LOOK_PROPERTIES, check_looks
from fatswarm.testing.report import CHECKS, Checked
from fatswarm.testing.starts import draw_looks
from fatswarm.testing.subject import Subject

DEFAULT_BUDGET_S: Final = 3.0  # seconds of hunting (the checks of views take well under one more)
DEFAULT_SIZES: Final = tuple(range(2, 9))  # n the views and the hunt are drawn with
# Round schedulers only: the async models are a model an algorithm has to claim (gathering, say,
# collides under them); pass schedulers=hunt_models() for every one.
DEFAULT_SCHEDULERS: Final = ("fsync", "ssync", "centralized")
_FRAME_CHECKS: Final = {
    Frames.Y_AXIS: "mirror",
    Frames.CHIRALITY: "rotation",
    Frames.DISORIENTED: "rotation-mirror",
}


def _chosen(subject: Subject, checks: Iterable[str] | None) -> tuple[str, ...]:
    """The properties to check, in CHECKS order: those asked for (ValueError for an unknown
    name), else every one that applies (the frames the algorithm declares; the palette of a
    luminous one). `seam` is always checked, first."""
    if checks is not None:
        asked = set(checks) if not isinstance(checks, str) else {checks}
        unknown = sorted(asked - set(CHECKS))
        if unknown:
            raise ValueError(f"unknown checks {unknown}; choose from {', '.join(CHECKS)}")
    else:
        asked = {"path", "palette", "oblivious", "order", "params", "hunt"}
        # both-axes frames are the world's, translated: no invariance to check
        asked |= {_FRAME_CHECKS[f] for f in subject.frames if f in _FRAME_CHECKS}
    if not subject.colours:
        asked.discard("palette")
    return tuple(name for name in CHECKS if name in asked and name != "seam")


def _check_arguments(
    seed: object, budget: object, sizes: Sequence[int], schedulers: Sequence[str]
) -> None:
    """Refuse arguments check_algorithm cannot use (ValueError, one line)."""
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ValueError(f"seed must be an int, got {seed!r}")
    if isinstance(budget, bool) or not isinstance(budget, (int, float)) or not budget >= 0:
        raise ValueError(f"budget must be a number of seconds >= 0, got {budget!r}")
    if not sizes or any(isinstance(n, bool) or not isinstance(n, int) or n < 2 for n in sizes):
        raise ValueError(f"sizes must be whole numbers of robots >= 2, got {list(sizes)!r}")
    known = hunt_models()
    if not schedulers or any(s not in known for s in schedulers):
        raise ValueError(f"schedulers must be some of {', '.join(known)}, got {list(schedulers)!r}")


def check_algorithm(
    algorithm: object,
    *,
    params: Mapping[str, object] | None = None,
    seed: int = 0,
    budget: float = DEFAULT_BUDGET_S,
    sizes: Sequence[int] = DEFAULT_SIZES,
    schedulers: Sequence[str] = DEFAULT_SCHEDULERS,
    checks: Iterable[str] | None = None,
) -> Checked:
    """Hold `algorithm` (the object, or a reference as `--algorithm` takes it) to the model's
    contract; raise AlgorithmContractError at the first property it breaks.

    In order (RULES says each): `seam` (it is an algorithm; always checked), `path`, `palette`
    (luminous only), `oblivious`, `order`, the frames it declares (`mirror` for y-axis, `rotation`
    for chirality, `rotation-mirror` for disoriented), `params` and `hunt`. The views are every
    robot's of two starts of each of `fatswarm hunt`'s start families (n from `sizes`, drawn from
    `seed`), with `params` (defaults for the rest); a broken property is shown on the smallest view
    found (robots dropped while it still breaks, then coordinates rounded). The hunt runs lock-step
    runs drawn from `seed` over the start families, `sizes` and `schedulers` for `budget` seconds,
    and shrinks a failure as `fatswarm hunt` does. `checks`: only these (names of CHECKS).

    Raises ValueError for arguments it cannot use (TypeError for a class given in place of an
    instance; AlgorithmError for a reference that cannot be loaded; AlgorithmParamsError when the
    algorithm refuses `params` for every n of `sizes`), or when the algorithm refuses every start
    drawn. `Checked.checks` names every property checked, `seam` first.
    """
    started = time.monotonic()
    sizes, schedulers = tuple(sizes), tuple(schedulers)
    _check_arguments(seed, budget, sizes, schedulers)
    subject = Subject.of(algorithm, params)  # checks `seam`
    _check_given_params(subject, sizes)
    names = _chosen(subject, checks)
    looks = draw_looks(subject, seed, sizes) if set(names) & set(LOOK_PROPERTIES) else []
    runs = refused = 0
    for name in names:
        if name in LOOK_PROPERTIES:
            check_looks(subject, name, looks)
        elif name == "params":
            check_params(subject, sizes)
        else:
            runs, refused = run_hunt(subject, seed, float(budget), sizes, schedulers)
    seconds = time.monotonic() - started
    return Checked(subject.name, ("seam", *names), len(looks), runs, refused, seconds)


def _check_given_params(subject: Subject, sizes: Sequence[int]) -> None:
    """Blame `params` (AlgorithmParamsError, one line) when the algorithm refuses every n of
    `sizes` with them but takes some n with its defaults: the sizes are not at fault."""
    if not subject.given or any(subject.setting(n) is not None for n in sizes):
        return
    for n in sizes:
        try:
            Configured.of(subject.algorithm, n, {})
        except AlgorithmParamsError:
            continue
        given = ", ".join(f"{k!r}: {v!r}" for k, v in subject.given.items())
        raise AlgorithmParamsError(
            f"params={{{given}}}: algorithm {subject.name} refuses them ({subject.refusals[n]})"
        )
