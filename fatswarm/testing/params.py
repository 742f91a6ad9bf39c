"""The parameters' check: every n refused (if at all) by AlgorithmParamsError alone, values of the
wrong type refused, values at the edges of a parameter's type taken or refused in one line."""

from __future__ import annotations

import types
from collections.abc import Mapping, Sequence
from typing import Final

from fatswarm.domain.seam import MAX_TEXT, AlgorithmParamsError, Configured, ParamValue
from fatswarm.testing.report import AlgorithmContractError
from fatswarm.testing.subject import Subject

_WRONG_TYPES: Final[Mapping[type, tuple[object, ...]]] = types.MappingProxyType(
    {
        bool: ("maybe", 1.5, None),
        int: ("many", 1.5, True, None),
        float: ("not-a-number", "nan", True, None),
        str: (1.5, True, None),
    }
)
_EDGE_VALUES: Final[Mapping[type, tuple[ParamValue, ...]]] = types.MappingProxyType(
    {
        bool: (True, False),
        int: (0, -1, 1, 2**31),
        float: (0.0, -0.0, -1.0, 1e-12, 1e12, -1e12),
        str: ("", "?", "x" * MAX_TEXT),
    }
)


def _refusal_problem(subject: Subject, n: int, values: Mapping[str, object], wrong: bool) -> str:
    """What is wrong with how the algorithm takes `values` for n robots ('' if nothing): it must
    refuse with AlgorithmParamsError in one line (and must refuse a value of the wrong type)."""
    what = ", ".join(f"{k}={v!r}" for k, v in values.items()) or "its defaults"
    try:
        Configured.of(subject.algorithm, n, {**subject.given, **values})
    except AlgorithmParamsError as exc:
        text = str(exc).strip()
        if not text or "\n" in text:
            return f"{what} (n = {n}) was refused with {text.count(chr(10)) + 1} lines: {text!r}"
        return ""
    except Exception as exc:
        return (
            f"make_params raised {type(exc).__name__}: {exc} for {what} (n = {n}); raise "
            "AlgorithmParamsError with one line saying what to fix"
        )
    return f"{what} (n = {n}) was accepted, a value of the wrong type" if wrong else ""


def check_params(subject: Subject, sizes: Sequence[int]) -> None:
    """Every n (refused or not, by AlgorithmParamsError only); then, for n the algorithm takes,
    each parameter with values of the wrong type (through the seam, as `--param` gives them) and
    values at the edges of its type (taken, or refused in one line)."""
    problems = (_refusal_problem(subject, n, {}, False) for n in sorted({1, 2, *sizes}))
    problem = next((p for p in problems if p), "")
    n = next((n for n in sizes if subject.setting(n) is not None), None)
    if not problem and n is not None:
        tries = (
            (spec.name, value, wrong)
            for spec in subject.algorithm.parameters
            for wrong, values in ((True, _WRONG_TYPES[spec.kind]), (False, _EDGE_VALUES[spec.kind]))
            for value in values
        )
        problems = (_refusal_problem(subject, n, {name: v}, wrong) for name, v, wrong in tries)
        problem = next((p for p in problems if p), "")
    if problem:
        raise AlgorithmContractError(subject.name, "params", f"  {problem}")
