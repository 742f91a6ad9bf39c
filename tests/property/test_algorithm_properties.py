"""Model properties of compute: mirror and translation invariance, anonymity, obliviousness."""

from __future__ import annotations

import dataclasses
import types

import numpy as np
import strategies
from agreement import assert_observers_agree
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fatswarm.agent.algorithm as algorithm_module
import fatswarm.agent.geometry as geometry_module
from fatswarm.agent.algorithm import canonical_view, compute, plan
from fatswarm.agent.canonical import SharedForm, canonical
from fatswarm.agent.geometry import mirror_matched, sec
from fatswarm.agent.params import Params
from fatswarm.domain.frames import Frame
from fatswarm.domain.path import Path, end_point, mirror, path_length
from fatswarm.domain.tolerance import snap

CELL = 2.6  # grid spacing; with jitter <= 0.25 every pair of centres is >= 2.1 apart


@st.composite
def configurations(draw: st.DrawFn, symmetric: bool | None = None) -> np.ndarray:
    """Valid starts: distinct jittered grid cells, optionally mirror symmetric about x = 0."""
    sym = draw(st.booleans()) if symmetric is None else symmetric
    size = draw(st.integers(2, 7))
    cells = draw(
        st.lists(
            st.tuples(st.integers(0, size), st.integers(-size, size)),
            min_size=1,
            max_size=8,
            unique=True,
        )
    )
    jitter = st.floats(-0.25, 0.25, allow_nan=False)
    pts = []
    for cx, cy in cells:
        x, y = cx * CELL + draw(jitter), cy * CELL + draw(jitter)
        if sym:
            if cx == 0:
                pts.append((0.0, y))
            else:
                pts.extend([(x, y), (-x, y)])
        else:
            pts.append((x if draw(st.booleans()) else -x, y))
    arr = np.array(pts, dtype=np.float64)
    d = np.hypot(arr[:, None, 0] - arr[None, :, 0], arr[:, None, 1] - arr[None, :, 1])
    np.fill_diagonal(d, np.inf)
    if len(arr) < 2 or d.min() < 2.05:
        arr = np.array([[0.0, 0.0], [5.0, 1.0]])
    return arr


def same_path(p: Path, q: Path, start: tuple[float, float] = (0.0, 0.0)) -> bool:
    if bool(p) != bool(q) or len(p) != len(q):
        return False
    ep, eq = end_point(start, p), end_point(start, q)
    return bool(
        np.allclose(ep, eq, atol=1e-7) and abs(path_length(start, p) - path_length(start, q)) < 1e-7
    )


SETTINGS = settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
side = st.sampled_from([4.0, 5.0, 7.5])


@SETTINGS
@given(configurations(), side, st.data())
def test_result_in_a_mirrored_frame_is_the_mirrored_path(
    pts: np.ndarray, a: float, data: st.DataObject
) -> None:
    me = data.draw(st.integers(0, len(pts) - 1))
    view = np.delete(pts, me, axis=0) - pts[me]
    params = Params(len(pts), a)
    direct = compute(view, params)
    flipped = view * np.array([-1.0, 1.0])
    in_mirror = compute(flipped, params)
    if same_path(in_mirror, mirror(direct)):
        return
    # The one allowed exception (G12): in a symmetric configuration a robot on L picks between
    # mirror targets by its own +X, so its choice does not flip with the frame.
    cx = sec(pts).center[0]
    assert mirror_matched(pts, cx, 1e-6).all(), "asymmetric configuration: must be equivariant"
    assert abs(pts[me, 0] - cx) <= 1e-6, "only a robot on L may keep its own side"
    canon = canonical_view(view, params)
    moves = plan(canon.points, params).moves
    assert moves.keys() == {canon.observer}, "and only when it is the single mover"
    assert same_path(in_mirror, direct)


@SETTINGS
@given(
    configurations(), side, st.tuples(st.integers(-(10**6), 10**6), st.integers(-(10**6), 10**6))
)
def test_the_canonical_form_ignores_translation_and_mirror(
    pts: np.ndarray, a: float, d: tuple[int, int]
) -> None:
    # On the grid, every robot's view is an exact translate (and maybe mirror) of the others':
    # the canonical form, where the algorithm decides, is then the very same bits.
    grid = snap(pts)
    shift = snap(np.array(d, dtype=np.float64) / 7.0)
    base = canonical(grid).key()
    assert canonical(grid + shift).key() == base
    assert canonical(grid * np.array([-1.0, 1.0])).key() == base


@SETTINGS
@given(configurations(), side, st.randoms(use_true_random=False))
def test_order_of_the_view_does_not_matter(pts: np.ndarray, a: float, rnd: object) -> None:
    params = Params(len(pts), a)
    view = pts[1:] - pts[0]
    perm = list(range(len(view)))
    rnd.shuffle(perm)  # type: ignore[attr-defined]
    assert same_path(compute(view[perm], params), compute(view, params))


@SETTINGS
@given(configurations(), configurations(), side)
def test_no_state_survives_a_call(p1: np.ndarray, p2: np.ndarray, a: float) -> None:
    v1, v2 = p1[1:] - p1[0], p2[1:] - p2[0]
    first = compute(v1, Params(len(p1), a))
    compute(v2, Params(len(p2), a))
    assert same_path(compute(v1, Params(len(p1), a)), first)


def test_algorithm_and_geometry_modules_hold_no_mutable_state() -> None:
    for module in (algorithm_module, geometry_module):
        for name, value in vars(module).items():
            if name.startswith("__") or name == "annotations":  # the __future__ flag
                continue
            if isinstance(value, (types.ModuleType, type, float, int, str)):
                continue
            params = getattr(value, "__dataclass_params__", None)
            frozen = dataclasses.is_dataclass(value) and params is not None and params.frozen
            immutable = frozen or isinstance(value, (tuple, frozenset))
            assert callable(value) or immutable, (module, name)


@SETTINGS
@given(configurations(), side)
def test_every_observer_agrees_on_who_moves(pts: np.ndarray, a: float) -> None:
    # G11: the plan is a property of the configuration, whatever the observer's origin and flip
    assert_observers_agree(pts, Params(len(pts), a))


def test_observers_agree_when_a_mirror_pair_is_exactly_one_from_l() -> None:
    # Found by the lockstep matrix (touching rosette, round 3): robots at x = +-1 from L exactly;
    # the origin's rounding decided whether the pair counted as 1 from L, so the robot on L and
    # the pair both moved, and touched.
    pts = np.array(
        [
            [0.0, 0.0],
            [4.727912514773747, 4.092340582224696],
            [2.1041190169024038, 7.382473562772653],
            [-2.104119016902402, 7.3824735627726525],
            [-4.727912514773745, 4.092340582224694],
            [-1.0000000000000009, -1.7320508075688767],
            [1.0000000000000002, -1.7320508075688772],
        ]
    )
    assert_observers_agree(pts, Params(7, 4.0))


@SETTINGS
@given(st.one_of(configurations(), strategies.any_adversarial_start()), st.data())
def test_the_shared_form_gives_every_robot_its_own_canonical_form(
    pts: np.ndarray, data: st.DataObject
) -> None:
    # Lockstep makes the canonical form once a round (SharedForm) instead of once per robot: it
    # must be exactly what each robot computes on its own shuffled view in its own frame.
    world = snap(pts)
    shared = SharedForm.of(world)
    params = Params(len(world), 4.0)
    for robot in range(len(world)):
        flip = data.draw(st.booleans())
        others = np.delete(world, robot, axis=0)
        others = others[data.draw(st.permutations(range(len(others))))]
        own = canonical_view(Frame(0.0, flip).to_local(others - world[robot]), params)
        mine = shared.for_robot(robot, flip)
        assert mine.key() == own.key()
        assert (mine.observer, mine.flip, mine.mirror_symmetric) == (
            own.observer,
            own.flip,
            own.mirror_symmetric,
        )
        assert np.array(mine.offset).tobytes() == np.array(own.offset).tobytes()
        assert shared.observer(robot, flip) == own.observer  # the shortcut for robots that stay
        assert robot in shared.robots_at(own.observer)  # and the way back from a mover's row
