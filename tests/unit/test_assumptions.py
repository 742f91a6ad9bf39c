"""Declared assumptions: one type for every axis, the built-in algorithms' declarations, and the
line a run outside them carries."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import numpy as np
import pytest

from fatswarm.coordinator.schedule import ROUND_NAMES
from fatswarm.domain.assumptions import SSYNC, Assumptions, Movement
from fatswarm.domain.frames import PAPER_FRAME, draw_frame
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import AXES, Frames, Lights, ModelError, RobotModel
from fatswarm.domain.seam import AlgorithmError, Configured, assumptions_of
from fatswarm.world.setup import WorldSetup, outside_assumption


def test_every_model_axis_is_a_field_of_the_declaration() -> None:
    names = {f.name for f in dataclasses.fields(Assumptions)}
    assert {a.name for a in AXES} <= names


def test_the_ssync_schedulers_are_the_round_schedulers() -> None:
    assert SSYNC == ROUND_NAMES


def test_words_are_taken_as_the_flags_give_them_and_bad_ones_refused() -> None:
    a = Assumptions(frames=("chirality",), lights=("full",), movement=("rigid",))  # type: ignore[arg-type]
    assert a.frames == (Frames.CHIRALITY,) and a.lights == (Lights.FULL,)
    assert a.movement == (Movement.RIGID,)
    with pytest.raises(ModelError, match="--frames must be one of"):
        Assumptions(frames=("sideways",))  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="non-empty tuple"):
        Assumptions(visibility=())
    with pytest.raises(ModelError, match="movement takes"):
        Assumptions(movement=("jumpy",))  # type: ignore[arg-type]


def test_the_papers_algorithm_declares_the_papers_model() -> None:
    a = assumptions_of(load_algorithm("uniform-circle"))
    assert a.lines() == (
        "visibility: transparent",
        "sight: unlimited",
        "lights: any",
        "frames: y-axis",
        "frame change: any",
        "noise: 0.0",
        "bodies: fat",
        "multiplicity: no",
        "knows n: yes",
        "schedulers: fsync, ssync, centralized, scripted",
        "movement: rigid",
    )


def test_a_run_within_the_assumptions_has_no_line() -> None:
    setting = Configured.of(load_algorithm("uniform-circle"), 4)
    assert outside_assumption(setting, RobotModel(), "ssync", None) == ""


def test_frames_alone_outside_read_as_they_always_have() -> None:
    setting = Configured.of(load_algorithm("uniform-circle"), 4)
    assert outside_assumption(setting, RobotModel.of(frames="chirality")) == (
        "algorithm uniform-circle assumes frames y-axis; this run gives it chirality "
        "(outside its assumption)"
    )


def test_the_lights_variant_under_internal_lights_says_it_is_outside() -> None:
    setting = Configured.of(load_algorithm("uniform-circle-lights"), 4)
    line = outside_assumption(setting, RobotModel.of(lights="internal"), "async", None)
    assert line == (
        "algorithm uniform-circle-lights assumes lights full; this run gives it internal "
        "(outside its assumption)"
    )


def test_the_papers_algorithm_under_async_and_non_rigid_moves_says_both() -> None:
    setting = Configured.of(load_algorithm("uniform-circle"), 4)
    line = outside_assumption(setting, RobotModel.of(visibility="opaque"), "async", 0.5)
    assert line == (
        "algorithm uniform-circle assumes visibility transparent; this run gives it opaque; "
        "assumes scheduler fsync, ssync, centralized, scripted; this run gives it async; "
        "assumes movement rigid; this run gives it non-rigid (outside its assumption)"
    )


def test_the_header_writes_the_line_only_when_outside() -> None:
    setting = Configured.of(load_algorithm("uniform-circle"), 2)
    start = np.array([[0.0, 0.0], [5.0, 0.0]])
    within = WorldSetup("s", 2, 1, "ssync", start, 10)
    assert "assumption" not in within.header(setting, start).extra
    outside = dataclasses.replace(within, scheduler="async")
    assert "scheduler" in outside.header(setting, start).extra["assumption"]


def test_an_algorithm_that_does_not_know_n_is_not_given_it() -> None:
    class Counting:
        name, summary, parameters = "counting", "", ()
        assumptions = Assumptions(knows_n=False)
        given: ClassVar[list[object]] = []

        def make_params(self, n: object, values: object) -> None:
            self.given.append(n)

        def compute(self, view: object, params: object) -> None: ...
        def goal(self, positions: object, params: object) -> bool:
            return True

    Configured.of(Counting(), 7)  # type: ignore[arg-type]
    assert Counting.given == [None]


def test_a_declaration_of_another_type_is_refused() -> None:
    class Odd:
        name = "odd"
        assumptions: ClassVar[dict[str, str]] = {"frames": "y-axis"}

    with pytest.raises(AlgorithmError, match="assumptions must be an Assumptions"):
        assumptions_of(Odd())


def test_an_old_frames_declaration_narrows_the_assumed_frames() -> None:
    class Old:
        frames = ("chirality",)

    assert assumptions_of(Old()) == Assumptions(frames=(Frames.CHIRALITY,))


def test_both_axes_frames_are_the_worlds_translated() -> None:
    model = RobotModel.of(frames="both-axes")
    for robot in range(5):
        assert draw_frame(model, 3, robot, 0) == PAPER_FRAME
    every = RobotModel.of(frames="both-axes", frame_change="every-look")
    assert draw_frame(every, 3, 2, 7) == PAPER_FRAME
