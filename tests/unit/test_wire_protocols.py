"""Wire protocols: round trips, and every kind of peer garbage is refused with ProtocolError."""

from __future__ import annotations

import math

import msgpack
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Arc, Line, Path
from fatswarm.domain.wire import (
    MAX_ROBOTS,
    PROTOCOL_VERSION,
    ProtocolError,
    check_swarm,
    pack,
    robot_of_key,
)
from fatswarm.world.observers import AgentInfo, WorldState
from fatswarm.world.protocol import (
    MAX_CONTROL_BYTES,
    MAX_LOOK_BYTES,
    MAX_MOVE_BYTES,
    MAX_NOTICE_BYTES,
    Begin,
    Commit,
    ControlReply,
    Hello,
    LookRequest,
    MovesHeld,
    MoveSubmitted,
    Snapshot,
    decode_control,
    move_key,
    moves_held_key,
    robot_of_alive_key,
    snapshot_key,
    state_key,
)


def _state(n: int = 3) -> WorldState:
    return WorldState(
        round=4,
        n=n,
        algorithm="uniform-circle",
        params={"a": 4.0},
        figures={},
        scheduler="ssync",
        swarm="s1",
        positions=np.arange(2 * n, dtype=np.float64).reshape(n, 2) / 3,
        active=(0, 2),
        open_round=5,
        moved=(2,),
        stopped=(),
        collisions_total=1,
        status=Status.RUNNING,
        agents=tuple(AgentInfo(i != 1, i - 1, 0.5 * i, i) for i in range(n)),
    )


def test_world_state_round_trips_exactly() -> None:
    s = _state()
    d = WorldState.decode(s.encode())
    assert np.array_equal(d.positions, s.positions)
    assert (d.round, d.n, d.a, d.scheduler, d.swarm) == (4, 3, 4.0, "ssync", "s1")
    assert (d.active, d.open_round, d.moved, d.stopped, d.collisions_total, d.status) == (
        (0, 2),
        5,
        (2,),
        (),
        1,
        "running",
    )
    assert d.agents == s.agents


def test_world_state_never_carries_the_seed() -> None:
    # The seed would give away every robot's private frame: it is not on the wire at all.
    fields = msgpack.unpackb(_state().encode(), raw=False)
    assert not any("seed" in key for key in fields)
    assert not hasattr(WorldState.decode(_state().encode()), "seed")


def test_keys_live_under_the_swarm_prefix() -> None:
    assert state_key("s1") == "fatswarm/s1/world/state"
    assert snapshot_key("s1", 3) == "fatswarm/s1/robot/3/snapshot"
    assert move_key("s1", 3) == "fatswarm/s1/robot/3/move"
    assert moves_held_key("s1") == "fatswarm/s1/world/moves"
    assert robot_of_key("fatswarm/s1/robot/12/move") == 12
    assert robot_of_key("fatswarm/s1/robot/012/move") is None
    assert robot_of_key("fatswarm/s1/robot/x/move") is None
    assert robot_of_alive_key("fatswarm/s1/alive/agent/5") == 5
    with pytest.raises(ValueError, match="swarm name"):
        check_swarm("a/b")
    with pytest.raises(ValueError, match="swarm name"):
        check_swarm("*")


@given(
    robot=st.integers(0, 4095),
    round_no=st.integers(1, 2**40),
    pts=st.lists(
        st.tuples(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6), st.floats(-6.0, 6.0)),
        max_size=4,
    ),
)
def test_move_round_trips(robot: int, round_no: int, pts: list[tuple[float, float, float]]) -> None:
    segs = tuple(Line((x, y)) if i % 2 else Arc((x, y), w) for i, (x, y, w) in enumerate(pts))
    msg = MoveSubmitted(robot=robot, round=round_no, path=Path(segs))
    assert MoveSubmitted.decode(msg.encode()) == msg


@given(
    pts=st.lists(
        st.tuples(st.floats(-2e9, 2e9), st.floats(-2e9, 2e9), st.floats(-40.0, 40.0)),
        max_size=4,
    ),
)
def test_a_lock_step_move_passes_the_checks_of_the_wire(
    pts: list[tuple[float, float, float]],
) -> None:
    # The lock step hands the world its moves through `MoveSubmitted.of`: what the wire would
    # give the world, or the same refusal, for every path (out-of-range ones included).
    segs = tuple(Line((x, y)) if i % 2 else Arc((x, y), w) for i, (x, y, w) in enumerate(pts))
    path = Path(segs)
    try:
        wire: MoveSubmitted | str = MoveSubmitted.decode(MoveSubmitted(3, 9, path).encode())
    except ProtocolError as exc:
        wire = str(exc)
    try:
        direct: MoveSubmitted | str = MoveSubmitted.of(3, 9, path)
    except ProtocolError as exc:
        direct = str(exc)
    assert direct == wire


def test_async_control_fields_round_trip_and_stay_optional() -> None:
    begin = Begin(3, (0, 4), at=12.5, looks=((0, 1.25), (4, 12.5)))
    assert decode_control(begin.encode()) == begin
    commit = Commit(3, (4,), delays=((0, 0.5, 1.75), (4, 0.0, 2.0)))
    assert decode_control(commit.encode()) == commit
    reply = ControlReply(
        True, "", 5, 2, 0, Status.RUNNING, now=7.5, looks=((1, 8.0),), unset=(2, 3)
    )
    assert ControlReply.decode(reply.encode()) == reply
    assert "at" not in msgpack.unpackb(Begin(3, (0,)).encode())  # round models send none
    assert "delays" not in msgpack.unpackb(Commit(3, ()).encode())
    assert "now" not in msgpack.unpackb(ControlReply(True, "", 5, 2, 3, Status.RUNNING).encode())


def test_notices_and_replies_name_their_world_process() -> None:
    assert MovesHeld.decode(MovesHeld(3, (0, 1), 2**63 - 1).encode()).epoch == 2**63 - 1
    reply = ControlReply(True, "", 5, 2, 3, Status.RUNNING, epoch=42)
    assert ControlReply.decode(reply.encode()) == reply


def test_a_commits_reply_names_the_robots_that_timed_out_and_only_then_carries_the_key() -> None:
    reply = ControlReply(True, "", 5, 2, 3, Status.RUNNING, timed_out=(1, 4))
    assert ControlReply.decode(reply.encode()) == reply
    assert "timed_out" not in msgpack.unpackb(
        ControlReply(True, "", 5, 2, 3, Status.RUNNING).encode()
    )


@pytest.mark.parametrize(
    ("fields", "reason"),
    [
        ({"at": -1.0}, "'at'"),
        ({"at": float("nan")}, "'at'"),
        ({"at": "soon"}, "'at'"),
        ({"looks": [[0]]}, "rows"),
        ({"looks": [[0, -1.0]]}, "'t0'"),
        ({"looks": "all"}, "'looks'"),
        ({"looks": [[MAX_ROBOTS, 1.0]]}, "'robot'"),
        ({"looks": [[True, 1.0]]}, "'robot'"),
    ],
)
def test_an_async_begin_with_bad_times_is_refused(fields: dict[str, object], reason: str) -> None:
    good = {"v": PROTOCOL_VERSION, "t": "begin", "round": 2, "active": [0]}
    with pytest.raises(ProtocolError, match=reason):
        decode_control(_raw(**good, **fields))


def test_control_messages_round_trip() -> None:
    assert decode_control(Hello().encode()) == Hello()
    assert decode_control(Begin(3, (0, 4)).encode()) == Begin(3, (0, 4))
    assert decode_control(Commit(3, (4,)).encode()) == Commit(3, (4,))
    chained = Commit(3, (4,), then_active=(0, 2))
    assert decode_control(chained.encode()) == chained
    r = ControlReply(True, "", 5, 2, 3, Status.RUNNING)
    assert ControlReply.decode(r.encode()) == r
    assert MovesHeld.decode(MovesHeld(3, (0, 1)).encode()) == MovesHeld(3, (0, 1))
    assert MovesHeld.decode(MovesHeld(3, ()).encode()) == MovesHeld(3, ())


ROBOT_SETS = st.lists(st.integers(0, MAX_ROBOTS - 1), unique=True, max_size=40).map(
    lambda v: tuple(sorted(v))
)


@given(round_no=st.integers(1, 2**62), timed_out=ROBOT_SETS, then_active=ROBOT_SETS)
def test_commit_round_trips_with_the_next_rounds_active_set(
    round_no: int, timed_out: tuple[int, ...], then_active: tuple[int, ...]
) -> None:
    commit = Commit(round_no, timed_out, then_active)
    assert decode_control(commit.encode()) == commit


@given(round_no=st.integers(1, 2**62), robots=ROBOT_SETS)
def test_moves_held_round_trips(round_no: int, robots: tuple[int, ...]) -> None:
    notice = MovesHeld(round_no, robots)
    assert MovesHeld.decode(notice.encode()) == notice


def test_a_commit_carries_the_begin_of_the_next_round_only_with_an_active_set() -> None:
    assert Commit(4, (1,), then_active=(0, 2)).then == Begin(5, (0, 2))
    assert Commit(4, (1,)).then is None


def test_the_largest_commit_and_moves_notice_fit_under_their_size_limits() -> None:
    everyone = tuple(range(MAX_ROBOTS))
    assert len(Commit(2**62, everyone, everyone).encode()) <= MAX_CONTROL_BYTES
    late = 1e14 + 0.123456789  # the longest msgpack floats
    delays = tuple((r, late, late) for r in everyone)
    assert len(Commit(2**62, everyone, (), delays).encode()) <= MAX_CONTROL_BYTES
    looks = tuple((r, late) for r in everyone)
    assert len(Begin(2**62, everyone, late, looks).encode()) <= MAX_CONTROL_BYTES
    reply = ControlReply(
        True,
        "x" * 200,
        MAX_ROBOTS,
        2**62,
        2**62,
        Status.RUNNING,
        2**62,
        everyone,
        late,
        looks,
        everyone,
        2**63 - 1,
        everyone,
    )
    assert len(reply.encode()) <= MAX_CONTROL_BYTES
    assert len(MovesHeld(2**62, everyone, 2**63 - 1).encode()) <= MAX_NOTICE_BYTES


def test_snapshot_round_trips_and_checks_its_size() -> None:
    view = np.array([[1.0, -2.0], [3.5, 0.25]])
    d = Snapshot.decode(Snapshot(2, 3, "uniform-circle", {"a": 4.0}, view, epoch=9).encode())
    assert np.array_equal(d.view, view)
    assert (d.round, d.n, d.algorithm, d.params, d.epoch) == (2, 3, "uniform-circle", {"a": 4.0}, 9)
    fewer = Snapshot(2, 4, "uniform-circle", {"a": 4.0}, view).encode()  # 2 of 3 seen: fine
    assert Snapshot.decode(fewer).view.shape == (2, 2)
    wrong = Snapshot(2, 2, "uniform-circle", {"a": 4.0}, view).encode()  # n = 2: 1 row at most
    with pytest.raises(ProtocolError, match="bytes"):
        Snapshot.decode(wrong)
    body = {"round": 2, "n": 4, "algorithm": "u", "params": {}, "view": b"\x00" * 24, "epoch": 0}
    with pytest.raises(ProtocolError, match="bytes"):  # not a whole number of (x, y) pairs
        Snapshot.decode(pack("snapshot", body))


def test_look_request_round_trips_and_refuses_garbage() -> None:
    move = MoveSubmitted(3, 2, Path((Line((1.0, 0.5)),))).encode()
    for request in (
        LookRequest(),
        LookRequest(epoch=2**63 - 1, after=2**62),
        LookRequest(epoch=1, after=2, move=move),
    ):
        assert LookRequest.decode(request.encode()) == request
    assert "move" not in msgpack.unpackb(LookRequest(1, 2).encode())  # none: no key at all
    good = {"v": PROTOCOL_VERSION, "t": "look", "epoch": 1, "after": 2}
    too_big = b"x" * (MAX_MOVE_BYTES + 1)
    for change in (
        {"after": -1},
        {"epoch": -1},
        {"after": "2"},
        {"t": "snapshot"},
        {"move": "text"},
        {"move": 7},
        {"move": too_big},
    ):
        with pytest.raises(ProtocolError):
            LookRequest.decode(_raw(**{**good, **change}))
    assert len(LookRequest(1, 2, b"x" * MAX_MOVE_BYTES).encode()) <= MAX_LOOK_BYTES


def _raw(**fields: object) -> bytes:
    out: bytes = msgpack.packb(fields, use_bin_type=True)
    return out


GOOD_MOVE = {"v": PROTOCOL_VERSION, "t": "move", "robot": 1, "round": 2, "path": [{"line": [1, 2]}]}


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"", "not msgpack"),
        (b"\xc1garbage", "not msgpack"),
        (b"\x93\x01\x02\x03", "must be a map"),
        (_raw(**{**GOOD_MOVE, "v": 99}), "protocol version"),
        (_raw(**{k: v for k, v in GOOD_MOVE.items() if k != "v"}), "protocol version"),
        (_raw(**{**GOOD_MOVE, "t": "state"}), "message type"),
        (_raw(**{**GOOD_MOVE, "robot": -1}), "'robot'"),
        (_raw(**{**GOOD_MOVE, "robot": True}), "'robot'"),
        (_raw(**{**GOOD_MOVE, "round": 0}), "'round'"),
        (_raw(**{**GOOD_MOVE, "round": "3"}), "'round'"),
        (_raw(**{**GOOD_MOVE, "path": [{"line": [math.nan, 0.0]}]}), "bad path"),
        (_raw(**{**GOOD_MOVE, "path": [{"line": [math.inf, 0.0]}]}), "bad path"),
        (_raw(**{**GOOD_MOVE, "path": [{"line": [1e300, 0.0]}]}), "bounded plane"),
        (_raw(**{**GOOD_MOVE, "path": [{"arc": [0.0, 0.0, 1e9]}]}), "sweep"),
        (_raw(**{**GOOD_MOVE, "path": [{"teleport": [0.0, 0.0]}]}), "bad path"),
        (_raw(**{**GOOD_MOVE, "path": [{"line": [0, 0]}] * 65}), "bad path"),
        (b"\x00" * (2 << 20), "exceeds"),
    ],
)
def test_move_decoder_refuses_garbage(data: bytes, reason: str) -> None:
    with pytest.raises(ProtocolError, match=reason):
        MoveSubmitted.decode(data)


def test_world_state_decoder_refuses_bad_shapes() -> None:
    good = msgpack.unpackb(_state().encode(), raw=False)
    for key, value in [
        ("positions", b"\x00" * 8),
        ("positions", np.full((3, 2), np.nan).tobytes()),
        ("alive", [True]),
        ("status", "exploded"),
        ("active", [0, 0]),
        ("active", [7]),
        ("n", 0),
    ]:
        with pytest.raises(ProtocolError):
            WorldState.decode(_raw(**{**good, key: value}))


def test_control_decoder_refuses_unknown_requests() -> None:
    with pytest.raises(ProtocolError, match="message type"):
        decode_control(_raw(v=PROTOCOL_VERSION, t="format-disk"))
    with pytest.raises(ProtocolError):
        decode_control(_raw(v=PROTOCOL_VERSION, t="begin", round=1, active="all"))


GOOD_COMMIT = {
    "v": PROTOCOL_VERSION,
    "t": "commit",
    "round": 2,
    "timed_out": [1],
    "then_active": [0, 1],
}


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"then_active": None}, "'then_active'"),
        ({"then_active": "all"}, "'then_active'"),
        ({"then_active": [0, 0]}, "repeats"),
        ({"then_active": [-1]}, "'then_active'"),
        ({"then_active": [MAX_ROBOTS]}, "'then_active'"),
        ({"then_active": [True]}, "'then_active'"),
        ({"then_active": [1.0]}, "'then_active'"),
        ({"then_active": list(range(MAX_ROBOTS + 1))}, "'then_active'"),
        ({"timed_out": [0, 0]}, "repeats"),
        ({"round": 0}, "'round'"),
        ({"v": PROTOCOL_VERSION - 1}, "protocol version"),
    ],
)
def test_commit_decoder_refuses_a_bad_next_active_set(
    change: dict[str, object], reason: str
) -> None:
    fields = {k: v for k, v in {**GOOD_COMMIT, **change}.items() if v is not None}
    assert decode_control(_raw(**GOOD_COMMIT)) == Commit(2, (1,), (0, 1))  # the good one passes
    with pytest.raises(ProtocolError, match=reason):
        decode_control(_raw(**fields))


GOOD_NOTICE = {"v": PROTOCOL_VERSION, "t": "moves-held", "round": 3, "robots": [0, 2]}


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"robots": None}, "'robots'"),
        ({"robots": 2}, "'robots'"),
        ({"robots": [2, 2]}, "repeats"),
        ({"robots": [-1]}, "'robots'"),
        ({"robots": [MAX_ROBOTS]}, "'robots'"),
        ({"robots": ["0"]}, "'robots'"),
        ({"round": 0}, "'round'"),
        ({"round": None}, "'round'"),
        ({"t": "move-held"}, "message type"),  # the old per-move notice
        ({"epoch": -1}, "'epoch'"),
        ({"epoch": "7"}, "'epoch'"),
        ({"v": 2}, "protocol version"),
    ],
)
def test_moves_held_decoder_refuses_garbage(change: dict[str, object], reason: str) -> None:
    fields = {k: v for k, v in {**GOOD_NOTICE, **change}.items() if v is not None}
    assert MovesHeld.decode(_raw(**GOOD_NOTICE)) == MovesHeld(3, (0, 2))  # the good one passes
    with pytest.raises(ProtocolError, match=reason):
        MovesHeld.decode(_raw(**fields))
    with pytest.raises(ProtocolError, match="not msgpack"):
        MovesHeld.decode(b"\xc1")


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, 2e9, -2e9])
def test_a_snapshot_view_with_one_non_finite_or_out_of_range_coordinate_is_refused(
    bad: float,
) -> None:
    view = np.zeros((3, 2))
    view[1, 1] = bad
    data = Snapshot(round=1, n=4, algorithm="gathering", params={}, view=np.zeros((3, 2))).encode()
    raw = msgpack.unpackb(data, raw=False)
    with pytest.raises(ProtocolError, match="non-finite or out-of-range"):
        Snapshot.decode(_raw(**{**raw, "view": view.tobytes()}))
    edge = np.full((3, 2), -1e9)  # the bound itself is inside
    assert np.array_equal(Snapshot.decode(_raw(**{**raw, "view": edge.tobytes()})).view, edge)
