"""The algorithm under test: its parameters, its configuration for each n, its answer to a Look
(BadAnswer where it raises or answers what is not a Path), and how the hunt loads it."""

from __future__ import annotations

import itertools
import re
import sys
import types
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any

import numpy as np

from fatswarm.deploy.engine.config import input_errors
from fatswarm.domain.lights import LightsError, Lit, palette
from fatswarm.domain.path import Path
from fatswarm.domain.registry import check_algorithm as check_seam
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import (
    Algorithm,
    AlgorithmError,
    AlgorithmParamsError,
    Configured,
    assumed_frames,
    resolve_values,
)
from fatswarm.testing.look import Answer, Look, show_path
from fatswarm.testing.report import AlgorithmContractError
from fatswarm.world.physics import validate_configuration

_subjects = itertools.count(1)


class BadAnswer(Exception):
    """The algorithm raised, or answered something that is not a Path (a Lit)."""


class Subject:
    """The algorithm checked, its parameters, and its configuration for each n (cached)."""

    def __init__(self, algorithm: Algorithm[Any], ref: str | None, given: Mapping[str, object]):
        self.algorithm = algorithm
        self.ref = ref  # how to load it, when it was given that way
        self.given = dict(given)
        self.name = str(algorithm.name)
        self.colours = palette(algorithm)
        self.frames = assumed_frames(algorithm)
        self._settings: dict[int, Configured | None] = {}
        self.refusals: dict[int, str] = {}  # n -> why the algorithm refuses it

    @staticmethod
    def of(algorithm: object, params: Mapping[str, object] | None) -> Subject:
        """The subject; raises AlgorithmError for a reference that cannot be loaded and
        AlgorithmContractError ('seam') for an object that is not an algorithm."""
        if isinstance(algorithm, type):  # the seam's methods are an instance's (make_params)
            raise TypeError(
                f"check_algorithm takes an algorithm object, got the class {algorithm.__name__}; "
                f"pass an instance ({algorithm.__name__}(), or the module's ALGORITHM)"
            )
        ref = algorithm if isinstance(algorithm, str) else None
        try:
            loaded = load_algorithm(algorithm) if isinstance(algorithm, str) else algorithm
        except AlgorithmError as exc:  # worded for the CLI's --algorithm: here, the argument
            raise AlgorithmError(argument_words(str(exc))) from None
        label = str(getattr(loaded, "name", type(loaded).__name__))
        try:
            checked = check_seam(loaded, ref or label)
            subject = Subject(checked, ref, params or {})
        except (AlgorithmError, LightsError) as exc:
            detail = argument_words(str(exc))
            raise AlgorithmContractError(label, "seam", f"  {detail}") from None
        resolve_values(checked, subject.given)  # an unknown parameter, a bad value: ValueError
        return subject

    def setting(self, n: int) -> Configured | None:
        """The algorithm configured for n robots; None if it refuses n (AlgorithmParamsError)."""
        if n not in self._settings:
            try:
                self._settings[n] = Configured.of(self.algorithm, n, self.given)
            except AlgorithmParamsError as exc:
                self._settings[n] = None
                self.refusals[n] = str(exc)
        return self._settings[n]

    def accepts(self, look: Look) -> bool:
        """Whether the look is a robot's of a start the algorithm accepts (valid, not refused)."""
        setting = self.setting(look.n)
        if setting is None:
            return False
        try:
            setting.check_start(validate_configuration(look.configuration()))
        except input_errors():
            return False
        return True

    def answer(self, look: Look) -> Answer:
        """The Compute of the robot shown `look` (on a copy of its view); raises BadAnswer."""
        setting = self.setting(look.n)
        assert setting is not None  # looks come from starts configured for their n
        view = np.array(look.view, dtype=np.float64).reshape(-1, 2)
        try:
            if self.colours:
                lit: Any = self.algorithm
                given = lit.compute_lit(view, look.glance, setting.params)
                if not isinstance(given, Lit):
                    raise BadAnswer(f"compute_lit returned {type(given).__name__}, not a Lit")
                path, colour = given.path, given.colour
            else:
                path, colour = self.algorithm.compute(view, setting.params), None
        except BadAnswer:
            raise
        except Exception as exc:
            raise BadAnswer(f"{self.compute_name} raised {type(exc).__name__}: {exc}") from exc
        if not isinstance(path, Path):
            raise BadAnswer(f"{self.compute_name} returned {type(path).__name__}, not a Path")
        return path, colour

    @property
    def compute_name(self) -> str:
        return "compute_lit" if self.colours else "compute"

    def show(self, answer: Answer) -> str:
        path, colour = answer
        return show_path(path) + (f", colour {colour!r}" if self.colours else "")

    def describe_params(self, n: int) -> str:
        setting = self.setting(n)
        shown = setting.describe().partition(" ")[2] if setting is not None else ""
        return f"n = {n}" + (f", {shown}" if shown else "")

    @contextmanager
    def reference(self) -> Iterator[str]:
        """How the hunt loads the algorithm: its reference, or (an object given as is) a module
        made for it in this process for the time of the hunt."""
        if self.ref is not None:
            yield self.ref
            return
        module_name = f"_fatswarm_testing_subject_{next(_subjects)}"
        module = types.ModuleType(module_name)
        module.ALGORITHM = self.algorithm  # type: ignore[attr-defined]
        sys.modules[module_name] = module
        try:
            yield f"{module_name}:ALGORITHM"
        finally:
            sys.modules.pop(module_name, None)


def argument_words(message: str) -> str:
    """A message of the algorithm's loader, worded for `fatswarm run --algorithm`, worded for
    `check_algorithm`'s argument: `--algorithm: no file x.py` is `algorithm: no file x.py`."""
    return re.sub(r"(?<![\w-])--algorithm\b", "algorithm", message)


Broken = Callable[[Subject, Look], str | None]  # how a look breaks a property, or None
