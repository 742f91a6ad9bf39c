"""The robot model's values, frames and lights seam: parsing, the header form, frame transforms,
what a Look shows, and a luminous Compute's answer checked."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.domain.draws import draw_flip
from fatswarm.domain.frames import Frame, draw_frame
from fatswarm.domain.lights import Glance, LightsError, Lit, glance_of, palette
from fatswarm.domain.path import Arc, Line, Path, end_point
from fatswarm.domain.robot_model import PAPER_MODEL, ModelError, RobotModel
from fatswarm.domain.seam import AlgorithmError, Configured
from fatswarm.world.protocol import MoveSubmitted, Snapshot


def test_the_paper_model_is_the_default_and_has_no_flags() -> None:
    assert RobotModel.of() == PAPER_MODEL and PAPER_MODEL.is_paper and PAPER_MODEL.sees_all
    assert PAPER_MODEL.describe() == "paper model"
    assert RobotModel.from_header(None) == PAPER_MODEL


def test_a_model_round_trips_through_its_header_form() -> None:
    model = RobotModel.of("opaque-centres", 4.5, "external", "disoriented", "every-look")
    assert RobotModel.from_header(model.to_header()) == model
    assert not model.is_paper and not model.sees_all
    assert model.describe().split() == [
        "--visibility",
        "opaque-centres",
        "--sight",
        "4.5",
        "--lights",
        "external",
        "--frames",
        "disoriented",
        "--frame-change",
        "every-look",
    ]


@pytest.mark.parametrize(
    ("kwargs", "says"),
    [
        ({"visibility": "foggy"}, "--visibility must be one of transparent, opaque"),
        ({"sight": 0.0}, "--sight must be a finite distance > 0"),
        ({"sight": math.inf}, "--sight must be a finite distance > 0"),
        ({"lights": "on"}, "--lights must be one of full, internal, external"),
        ({"frames": "north"}, "--frames must be one of y-axis, chirality, disoriented"),
        ({"frame_change": "often"}, "--frame-change must be one of fixed, every-look"),
    ],
)
def test_a_bad_model_value_is_refused_in_one_line_naming_the_choices(
    kwargs: dict[str, Any], says: str
) -> None:
    with pytest.raises(ModelError, match=says):
        RobotModel.of(**kwargs)


def test_a_header_model_of_another_shape_is_refused() -> None:
    with pytest.raises(ModelError):
        RobotModel.from_header({"visibility": "opaque", "colour": "red"})
    with pytest.raises(ModelError):
        RobotModel.from_header({"frames": 3})


def test_the_paper_frames_are_the_seeded_x_mirror_of_every_earlier_run() -> None:
    for robot in range(20):
        frame = draw_frame(PAPER_MODEL, 7, robot, look_round=5)
        assert frame == Frame(0.0, draw_flip(7, robot))


def test_fixed_frames_do_not_change_and_every_look_frames_do() -> None:
    fixed = RobotModel.of(frames="chirality")
    every = RobotModel.of(frames="chirality", frame_change="every-look")
    assert draw_frame(fixed, 1, 3, 1) == draw_frame(fixed, 1, 3, 99)
    rotations = {draw_frame(every, 1, 3, k).rotation for k in range(1, 20)}
    assert len(rotations) == 19
    assert not any(draw_frame(fixed, 1, r, 1).mirror for r in range(50))
    disoriented = RobotModel.of(frames="disoriented")
    mirrors = [draw_frame(disoriented, 1, r, 1).mirror for r in range(200)]
    assert 60 < sum(mirrors) < 140


frames = st.builds(Frame, st.floats(0.0, 2 * math.pi, allow_nan=False), st.booleans())
coords = st.floats(-50.0, 50.0, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(frames, coords, coords, coords, coords, st.floats(-3.0, 3.0, allow_nan=False))
def test_a_path_made_in_a_frame_lands_where_the_frame_says(
    frame: Frame, x: float, y: float, cx: float, cy: float, sweep: float
) -> None:
    # the world path: to (x, y), then about (cx, cy) by `sweep`; seen in the frame, a mirror
    # reverses the turning sense
    local = frame.to_local(np.array([[x, y], [cx, cy]]))
    seen_sweep = -sweep if frame.mirror else sweep
    path = Path(
        (
            Line((float(local[0, 0]), float(local[0, 1]))),
            Arc((float(local[1, 0]), float(local[1, 1])), seen_sweep),
        )
    )
    got = end_point((0.0, 0.0), frame.path_to_world(path))
    want = end_point((0.0, 0.0), Path((Line((x, y)), Arc((cx, cy), sweep))))
    assert math.isclose(got[0], want[0], abs_tol=1e-7)
    assert math.isclose(got[1], want[1], abs_tol=1e-7)


def test_a_rotation_keeps_distances_and_a_mirror_reverses_turning() -> None:
    view = np.array([[3.0, 4.0], [-1.0, 2.0]])
    turned = Frame(1.1, True).to_local(view)
    assert np.allclose(np.hypot(turned[:, 0], turned[:, 1]), np.hypot(view[:, 0], view[:, 1]))
    arc = Path((Arc((1.0, 0.0), 0.5),))
    back = Frame(0.0, True).path_to_world(arc)
    assert back.segments[0] == Arc((-1.0, 0.0), -0.5)


class _Lamp:
    name = "lamp"
    summary = "test"
    parameters = ()
    colours = ("off", "on")

    def make_params(self, n: int, values: object) -> None:
        return None

    def compute(self, view: Any, params: None) -> Path:
        return Path()

    def compute_lit(self, view: Any, glance: Glance | None, params: None) -> Any:
        assert glance is not None
        return Lit(Path(), "on" if glance.own == "off" else "dim")

    def goal(self, positions: Any, params: None) -> bool:
        return True


def test_a_luminous_compute_gives_a_palette_index_and_a_foreign_colour_is_refused() -> None:
    setting = Configured.of(_Lamp(), 3)  # type: ignore[arg-type]
    assert setting.luminous and setting.colours == ("off", "on")
    assert setting.decide(np.zeros((2, 2)), Glance("off", ("off", "on"))) == (Path(), 1)
    with pytest.raises(LightsError, match="returned colour 'dim', not one of off, on"):
        setting.decide(np.zeros((2, 2)), Glance("on", None))


def test_a_palette_that_is_not_a_tuple_of_distinct_names_is_refused() -> None:
    lamp = _Lamp()
    lamp.colours = ("on", "on")
    with pytest.raises(LightsError):
        palette(lamp)
    with pytest.raises(AlgorithmError, match="colours must be a tuple"):
        Configured.of(lamp, 3)  # type: ignore[arg-type]


def test_a_glance_names_what_the_snapshot_shows_and_nothing_else() -> None:
    assert glance_of((), 0, (0,)) is None
    assert glance_of(("a", "b"), 1, (0, 1)) == Glance("b", ("a", "b"))
    assert glance_of(("a", "b"), None, (1,)) == Glance(None, ("b",))
    assert glance_of(("a", "b"), 0, None) == Glance("a", None)


def test_a_snapshot_of_some_robots_with_colours_round_trips_and_lies_are_refused() -> None:
    snap = Snapshot(3, 6, "x", {}, np.array([[1.0, 2.0], [3.0, -4.0]]), 0, (1, 0), 1)
    back = Snapshot.decode(snap.encode())
    assert np.array_equal(back.view, snap.view) and (back.colours, back.own) == ((1, 0), 1)
    empty = Snapshot.decode(Snapshot(3, 6, "x", {}, np.zeros((0, 2))).encode())
    assert empty.view.shape == (0, 2) and empty.colours is None and empty.own is None
    from fatswarm.domain.wire import ProtocolError

    too_many = Snapshot(3, 2, "x", {}, np.zeros((3, 2))).encode()
    with pytest.raises(ProtocolError):
        Snapshot.decode(too_many)
    bad = Snapshot(3, 6, "x", {}, np.zeros((2, 2)), 0, (1,), None).encode()
    with pytest.raises(ProtocolError, match="colours"):
        Snapshot.decode(bad)


def test_a_move_carries_its_colour_and_an_unpalettable_one_is_refused() -> None:
    move = MoveSubmitted(1, 2, Path(), 3)
    assert MoveSubmitted.decode(move.encode()) == move
    assert MoveSubmitted.decode(MoveSubmitted(1, 2, Path()).encode()).colour is None
    from fatswarm.domain.wire import ProtocolError

    with pytest.raises(ProtocolError):
        MoveSubmitted.of(1, 2, Path(), 99)


def test_the_observers_state_carries_every_robots_colour_for_the_live_dashboard() -> None:
    from fatswarm.deploy.view.dashboard import frame_from_state
    from fatswarm.domain.outcome import Status
    from fatswarm.domain.wire import ProtocolError
    from fatswarm.world.observers import AgentInfo, WorldState

    agents = (AgentInfo(True, 0, 0.0, 0),) * 2
    state = WorldState(
        3, 2, "x", {}, {}, "fsync", "s", np.zeros((2, 2)), (), 0, (), (), 0, Status.RUNNING,
        agents, ("on", "off"), ("off", "on"),
    )  # fmt: skip
    back = WorldState.decode(state.encode())
    assert (back.lights, back.palette) == (("on", "off"), ("off", "on"))
    assert frame_from_state(back).lights == ("on", "off")
    plain = WorldState.decode(replace(state, lights=(), palette=()).encode())
    assert (plain.lights, plain.palette) == ((), ())
    with pytest.raises(ProtocolError, match="lights"):
        WorldState.decode(replace(state, lights=("on", "red")).encode())
