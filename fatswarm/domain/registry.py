"""Finding an algorithm: by registered name (entry points) or by `module:attribute` of your own.

`--algorithm NAME` looks in the entry point group `fatswarm.algorithms` (fatswarm's own and any
installed package's); `--algorithm pkg.mod:OBJ` or `--algorithm path/to/file.py:OBJ` loads an
object from a module or a file. Every process of a run loads the algorithm by the same reference.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import re
import sys
from importlib.metadata import entry_points
from typing import Any

from fatswarm.domain.seam import MAX_PARAMS, MAX_TEXT, Algorithm, AlgorithmError, ParamSpec

GROUP = "fatswarm.algorithms"
DEFAULT = "uniform-circle"
# fatswarm's own, also when it runs from a source tree that was never installed
BUILTIN = {
    "uniform-circle": "fatswarm.agent.uniform_circle:ALGORITHM",
    "gathering": "fatswarm.agent.gathering:ALGORITHM",
    "uniform-circle-stepped": "fatswarm.agent.stepped:ALGORITHM",
    "uniform-circle-lights": "fatswarm.agent.luminous:ALGORITHM",
    # oblot-sim's four algorithms, ported (docs/ports.md)
    "oblot-go-to-cog": "fatswarm.agent.oblot_go_to_cog:ALGORITHM",
    "oblot-go-to-rightmost": "fatswarm.agent.oblot_go_to_rightmost:ALGORITHM",
    "oblot-gathering-multiplicity": "fatswarm.agent.oblot_gathering_multiplicity:ALGORITHM",
    "oblot-move-along-sec": "fatswarm.agent.oblot_move_along_sec:ALGORITHM",
}
_NAME = re.compile(r"[A-Za-z0-9_.-]{1,64}")


def available() -> dict[str, str]:
    """Registered algorithm name -> `module:attribute`, fatswarm's own first."""
    found = dict(BUILTIN)
    for ep in entry_points(group=GROUP):
        found.setdefault(ep.name, ep.value)
    return found


def load_algorithm(ref: str) -> Algorithm[Any]:
    """The algorithm `ref` names; raises AlgorithmError with one line saying what to fix."""
    if not isinstance(ref, str) or not ref.strip():
        raise AlgorithmError("--algorithm needs a name or module:attribute")
    ref = ref.strip()
    if ":" not in ref:
        known = available()
        target = known.get(ref)
        if target is None:
            raise AlgorithmError(
                f"no algorithm named {ref!r}; registered: {', '.join(sorted(known))} "
                "(or give module:attribute, or path/to/file.py:attribute)"
            )
        return check_algorithm(_load_object(target), target)
    return check_algorithm(_load_object(ref), ref)


def _load_object(ref: str) -> object:
    where, _, attribute = ref.rpartition(":")
    if not where or not attribute:
        raise AlgorithmError(f"--algorithm {ref!r}: expected module:attribute")
    if where.endswith(".py"):
        module = _module_from_file(where)
    else:
        try:
            module = importlib.import_module(where)
        except ImportError as exc:
            raise AlgorithmError(f"--algorithm {ref!r}: cannot import {where}: {exc}") from None
        except Exception as exc:  # the user's module raised while importing
            raise AlgorithmError(
                f"--algorithm {ref!r}: importing {where} raised {type(exc).__name__}: {exc}"
            ) from None
    obj = module
    for part in attribute.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise AlgorithmError(
                f"--algorithm {ref!r}: {where} has no attribute {attribute!r}"
            ) from None
    return obj


def _module_from_file(path: str) -> Any:
    """Import a file as a module (named for the file), once per process."""
    full = os.path.abspath(path)
    if not os.path.isfile(full):
        raise AlgorithmError(f"--algorithm: no file {path}")
    name = "fatswarm_user_" + re.sub(r"\W", "_", os.path.splitext(os.path.basename(full))[0])
    loaded = sys.modules.get(name)
    if loaded is not None and getattr(loaded, "__file__", None) == full:
        return loaded
    spec = importlib.util.spec_from_file_location(name, full)
    if spec is None or spec.loader is None:
        raise AlgorithmError(f"--algorithm: cannot load {path} as Python")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's file raised while loading
        del sys.modules[name]
        raise AlgorithmError(
            f"--algorithm: loading {path} raised {type(exc).__name__}: {exc}"
        ) from None
    return module


def check_algorithm(obj: object, ref: str) -> Algorithm[Any]:
    """`obj` if it has what `Algorithm` asks for; raises AlgorithmError naming what is missing."""
    candidate: Any = obj
    missing = [
        attr
        for attr in ("name", "summary", "parameters", "make_params", "compute", "goal")
        if not hasattr(obj, attr)
    ]
    if missing:
        raise AlgorithmError(
            f"--algorithm {ref}: not an algorithm (missing {', '.join(missing)}; "
            "see docs/algorithms.md)"
        )
    name = candidate.name
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise AlgorithmError(
            f"--algorithm {ref}: its name must be 1-64 letters, digits, '-', "
            f"'_' or '.', got {name!r}"
        )
    _check_parameters(candidate.parameters, ref)
    for method in ("make_params", "compute", "goal"):
        if not callable(getattr(obj, method)):
            raise AlgorithmError(f"--algorithm {ref}: {method} is not callable")
    if getattr(obj, "colours", ()) != () and not callable(getattr(obj, "compute_lit", None)):
        raise AlgorithmError(
            f"--algorithm {ref}: it declares colours but has no compute_lit(view, glance, params)"
        )
    assert isinstance(obj, Algorithm)
    return obj


def _check_parameters(params: Any, ref: str) -> None:
    """Refuse an algorithm's `parameters` unless a short tuple of ParamSpec with plain, distinct
    names and plain defaults (AlgorithmError)."""
    if (
        not isinstance(params, tuple)
        or len(params) > MAX_PARAMS
        or not all(isinstance(p, ParamSpec) and _NAME.fullmatch(p.name) for p in params)
    ):
        raise AlgorithmError(
            f"--algorithm {ref}: 'parameters' must be a tuple of at most "
            f"{MAX_PARAMS} ParamSpec with plain names"
        )
    if len({p.name for p in params}) != len(params):
        raise AlgorithmError(f"--algorithm {ref}: two parameters share a name")
    for p in params:
        if not isinstance(p.default, (bool, int, float, str)) or (
            isinstance(p.default, str) and len(p.default) > MAX_TEXT
        ):
            raise AlgorithmError(
                f"--algorithm {ref}: parameter {p.name} needs a bool, int, "
                "float or short str default"
            )


__all__ = ["BUILTIN", "DEFAULT", "GROUP", "available", "check_algorithm", "load_algorithm"]
