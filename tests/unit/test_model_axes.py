"""The robot model's axes are declared once (`robot_model.AXES`): every carrier (the flags of run,
sweep and hunt, the API keywords, the header, the sweep's columns and labels, the --resume check)
follows from the declaration, so each axis reaches all of them with no edit of its own."""

from __future__ import annotations

import argparse
import inspect

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy.commands.resume import contradictions
from fatswarm.deploy.commands.run import add_arguments as add_run_arguments
from fatswarm.deploy.engine.config import model_from_args
from fatswarm.deploy.hunt.command import add_arguments as add_hunt_arguments
from fatswarm.deploy.sweep.command import add_arguments as add_sweep_arguments
from fatswarm.deploy.sweep.grid import (
    KEY_COLUMNS,
    MODEL_COLUMNS,
    model_argv,
    model_cells,
    model_of_cells,
    model_suffix,
    robot_models_of,
)
from fatswarm.domain.robot_model import AXES, PAPER_MODEL, Axis, RobotModel
from fatswarm.world.record import Header
from fatswarm.world.setup import WorldSetup


def other_value(axis: Axis) -> str:
    """A value of `axis` that is not the paper's, as its flag takes it."""
    return axis.words[1] if axis.words else "2.5"


def parser(add: object) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser()
    assert callable(add)
    add(p)
    return p


@pytest.mark.parametrize("axis", AXES, ids=[a.name for a in AXES])
def test_every_axis_is_a_flag_of_run_and_a_list_of_sweep_and_hunt(axis: Axis) -> None:
    text = other_value(axis)
    args = parser(add_run_arguments).parse_args([axis.flag, text])
    model = model_from_args(args)
    assert model.value(axis.name) == axis.parse(text) and model.changed() == (axis,)
    for add in (add_sweep_arguments, add_hunt_arguments):
        lists = parser(add).parse_args([axis.flag, f"{text},{axis.text(axis.default) or text}"])
        assert model in robot_models_of(lists)


@pytest.mark.parametrize("axis", AXES, ids=[a.name for a in AXES])
def test_every_axis_reaches_the_header_the_columns_and_the_command(axis: Axis) -> None:
    model = RobotModel.of(**{axis.name: axis.parse(other_value(axis))})
    assert RobotModel.from_header(model.to_header()) == model
    assert axis.flag in model.describe()
    assert axis.name in MODEL_COLUMNS and axis.name in KEY_COLUMNS
    cells = model_cells(model)
    assert model_of_cells(cells) == model and cells[axis.name]
    assert model_suffix(model).startswith(f"+{axis.tag}")
    argv = model_argv(model)
    assert model_from_args(parser(add_run_arguments).parse_args(argv)) == model


@pytest.mark.parametrize("axis", AXES, ids=[a.name for a in AXES])
def test_every_axis_is_a_keyword_of_the_api_and_a_resume_check(axis: Axis) -> None:
    parameter = inspect.signature(fatswarm.run).parameters[axis.name]
    assert parameter.kind is inspect.Parameter.KEYWORD_ONLY
    header = Header(3, 0, "fsync", np.zeros((3, 2)))  # the paper's model: no `model`
    args = parser(add_run_arguments).parse_args([axis.flag, other_value(axis)])
    (found,) = contradictions(args, WorldSetup.from_header(header, "s", None))
    assert found.flag == axis.flag


def test_a_later_axis_at_its_default_leaves_the_header_model_as_it_was() -> None:
    always = [a.name for a in AXES if a.always]
    assert list(RobotModel.of(frames="chirality").to_header()) == always
    assert PAPER_MODEL.changed() == ()
