"""A router made by `fatswarm secure` (mutual TLS, access control with default deny) on loopback:
each part does its own job through it, and every rogue try of another part is refused by the
router: what it sends reaches nobody, what it asks gets no answer, what it declares is not seen.

Rogues are real parts' identities (a robot, a dashboard, the coordinator); witnesses are the
sessions of the parts that would have received the message. Every check of "nothing came"
follows a positive control on the same path that did come.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from netharness import assert_one_line, part, run_all
from rogues import Rogue

from fatswarm.deploy.net.children import Children
from fatswarm.deploy.net.zconf import free_port, make_config
from fatswarm.deploy.secure.plan import Plan
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Path as MovePath
from fatswarm.world.protocol import (
    Begin,
    ControlReply,
    LookRequest,
    MovesHeld,
    MoveSubmitted,
    Snapshot,
    agent_alive_any_key,
    agent_alive_key,
    control_key,
    move_any_key,
    move_key,
    moves_held_key,
    snapshot_any_key,
    snapshot_key,
    state_key,
)

pytestmark = pytest.mark.integration

N = 3
DEADLINE_S = 30.0
SETTLE_S = 0.3  # after the positive control arrived, how long a refused message could still lag
ASK_S = 2.0  # the timeout of a get; a refused one returns at once


@dataclass
class Net:
    out: Path
    plan: Plan
    endpoint: str
    sessions: list[Any] = field(default_factory=list)

    def client(self, name: str, config: Path | None = None) -> Any:
        """An open client session with identity `name` (its file of the folder)."""
        import zenoh

        conf = make_config(
            "client", [self.endpoint], config_file=str(config or self.out / f"{name}.json5")
        )
        session = zenoh.open(conf)
        self.sessions.append(session)
        return session


@pytest.fixture(scope="module")
def router(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Net]:
    """A secured router (its own process, `fatswarm router --config`) on a free loopback port."""
    import zenoh

    from fatswarm.deploy.secure.pki import write_bundle

    tmp = tmp_path_factory.mktemp("secure")
    plan = Plan("sec", N, ("127.0.0.1",), free_port(), 1)
    write_bundle(plan, tmp / "bundle")
    probe = Net(tmp / "bundle", plan, plan.endpoint("127.0.0.1"))
    log = open(tmp / "router.log", "wb")  # noqa: SIM115
    with Children() as children:
        children.start(
            "router",
            part("router", "--config", str(probe.out / "router-127.0.0.1.json5")),
            stdout=log,
            stderr=log,
        )
        log.close()
        deadline = time.monotonic() + DEADLINE_S
        while True:
            try:
                probe.client("dashboard-0").close()
                break
            except zenoh.ZError:
                if time.monotonic() > deadline or children.exited():
                    pytest.fail(
                        f"secured router did not come up: {(tmp / 'router.log').read_text()}"
                    )
                time.sleep(0.1)
        yield probe


@pytest.fixture
def net(router: Net) -> Iterator[Net]:
    """The secured router, with sessions of this test only (closed after it)."""
    net = Net(router.out, router.plan, router.endpoint)
    try:
        yield net
    finally:
        for session in net.sessions:
            session.close()


class Inbox:
    """Samples (key, payload) a witness received, thread-safe."""

    def __init__(self) -> None:
        self.items: list[tuple[str, bytes]] = []
        self._lock = threading.Lock()

    def __call__(self, sample: Any) -> None:
        with self._lock:
            self.items.append((str(sample.key_expr), sample.payload.to_bytes()))

    def payloads(self) -> list[bytes]:
        with self._lock:
            return [p for _, p in self.items]


def wait_for(what: str, predicate: Callable[[], bool]) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not predicate():
        if time.monotonic() > deadline:
            pytest.fail(f"timed out waiting for {what}")
        time.sleep(0.01)


def replies(session: Any, key: str, payload: bytes | None = None) -> list[bytes]:
    """The payloads of the OK replies to one get (a refused get returns at once, empty)."""
    got = session.get(key, payload=payload, timeout=ASK_S)
    return [r.ok.payload.to_bytes() for r in got if r.ok is not None]


def answering(payload: bytes, asked: list[str]) -> Callable[[Any], None]:
    """A queryable callback that notes the key asked and replies `payload`."""

    def answer(query: Any) -> None:
        asked.append(str(query.key_expr))
        with query:
            query.reply(query.key_expr, payload)

    return answer


def move(robot: int, round_no: int = 1) -> bytes:
    return MoveSubmitted(robot=robot, round=round_no, path=MovePath()).encode()


def deliver(what: str, send: Callable[[], None], arrived: Callable[[], bool]) -> None:
    """Send until it arrived: a message sent before the router knows of its receiver is lost."""
    deadline = time.monotonic() + DEADLINE_S
    while True:
        send()
        again = time.monotonic() + 0.2
        while time.monotonic() < again:
            if arrived():
                return
            time.sleep(0.01)
        if time.monotonic() > deadline:
            pytest.fail(f"timed out delivering {what}")


def synced(net: Net, session: Any, name: str) -> None:
    """Return once the router has taken in everything `session` (identity `name`) sent so far:
    a message it may send, sent now, has come through (one link keeps the order)."""
    swarm = net.plan.swarm
    if name.startswith("agent-"):
        key = agent_alive_key(swarm, int(name.removeprefix("agent-")))
        token = session.liveliness().declare_token(key)
        watcher = net.client("dashboard-0")
        wait_for(
            f"{name}'s token",
            lambda: any(r.ok is not None for r in watcher.liveliness().get(key, timeout=ASK_S)),
        )
        token.undeclare()
    elif name.startswith("dashboard-"):
        states = Inbox()
        session.declare_subscriber(state_key(swarm), states)
        publisher = net.client("world").declare_publisher(state_key(swarm))
        deliver("a state", lambda: publisher.put(b"sync"), lambda: bool(states.items))
    else:
        raise ValueError(name)


# --- the rogue list ----------------------------------------------------------------------------


def test_a_move_reaches_the_world_only_in_its_own_robots_look(net: Net) -> None:
    swarm = net.plan.swarm
    looks: list[tuple[str, bytes]] = []
    world_session = net.client("world")

    def hold(query: Any) -> None:
        with query:
            looks.append((str(query.key_expr), LookRequest.decode(query.payload.to_bytes()).move))
            query.reply(query.key_expr, b"view")

    world_session.declare_queryable(snapshot_any_key(swarm), hold)
    puts = Inbox()
    world_session.declare_subscriber(move_any_key(swarm), puts)  # as the world listens
    owner, rogue = net.client("agent-2"), net.client("agent-1")
    dashboard = net.client("dashboard-0")

    def look(session: Any, robot: int, carried: bytes) -> list[bytes]:
        return replies(session, snapshot_key(swarm, robot), LookRequest(move=carried).encode())

    wait_for("robot 2's own Look", lambda: look(owner, 2, move(2, 1)) != [])
    rogue.put(move_key(swarm, 2), move(2, 7))  # a move for another robot
    rogue.put(move_key(swarm, 1), move(1, 7))  # its own, but outside its Look
    dashboard.put(move_key(swarm, 2), move(2, 8))
    assert look(rogue, 2, move(2, 6)) == [] and look(dashboard, 2, move(2, 5)) == []
    assert look(owner, 2, move(2, 9)) == [b"view"]
    time.sleep(SETTLE_S)
    assert {m for k, m in looks} == {move(2, 1), move(2, 9)}
    assert {k for k, m in looks} == {snapshot_key(swarm, 2)}
    assert puts.payloads() == []


def test_only_the_coordinator_opens_and_commits_rounds(net: Net) -> None:
    swarm = net.plan.swarm
    asked: list[str] = []
    net.client("world").declare_queryable(control_key(swarm), answering(b"ok", asked))
    begin = Begin(1, (0, 1, 2)).encode()
    coordinator = net.client("coordinator")
    wait_for("the world to answer", lambda: replies(coordinator, control_key(swarm), begin) != [])
    asked.clear()
    for rogue in ("agent-1", "dashboard-0"):
        assert replies(net.client(rogue), control_key(swarm), begin) == [], rogue
    assert asked == []
    assert replies(coordinator, control_key(swarm), begin) == [b"ok"]
    assert asked == [control_key(swarm)]


def test_a_robot_gets_only_its_own_snapshot(net: Net) -> None:
    swarm = net.plan.swarm
    asked: list[str] = []
    net.client("world").declare_queryable(snapshot_any_key(swarm), answering(b"view", asked))
    rogue = net.client("agent-1")
    wait_for("the world to answer", lambda: replies(rogue, snapshot_key(swarm, 1)) != [])
    asked.clear()
    assert replies(rogue, snapshot_key(swarm, 2)) == []
    assert replies(net.client("dashboard-0"), snapshot_key(swarm, 2)) == []
    assert asked == []
    assert replies(rogue, snapshot_key(swarm, 1)) == [b"view"]  # its own: answered
    assert asked == [snapshot_key(swarm, 1)]


def test_a_fake_agent_token_is_not_seen(net: Net) -> None:
    swarm = net.plan.swarm
    seen = Inbox()
    coordinator = net.client("coordinator")
    coordinator.liveliness().declare_subscriber(agent_alive_any_key(swarm), seen, history=True)
    rogue, dashboard = net.client("agent-1"), net.client("dashboard-0")
    fakes = [
        rogue.liveliness().declare_token(agent_alive_key(swarm, 2)),  # robot 2 has no agent
        rogue.liveliness().declare_token(agent_alive_key(swarm, 9)),
        dashboard.liveliness().declare_token(agent_alive_key(swarm, 0)),
    ]
    own = rogue.liveliness().declare_token(agent_alive_key(swarm, 1))  # after its fakes
    wait_for("robot 1's own token", lambda: len(seen.items) >= 1)
    synced(net, dashboard, "dashboard-0")  # (its get would see its own token, in the session)
    live = net.client("dashboard-0").liveliness().get(agent_alive_any_key(swarm), timeout=ASK_S)
    time.sleep(SETTLE_S)
    assert [k for k, _ in seen.items] == [agent_alive_key(swarm, 1)]
    assert [str(r.ok.key_expr) for r in live if r.ok is not None] == [agent_alive_key(swarm, 1)]
    for token in (*fakes, own):
        token.undeclare()


def test_a_fake_world_answers_no_snapshot(net: Net) -> None:
    swarm = net.plan.swarm
    view = np.zeros((N - 1, 2))
    fake = Snapshot(round=1, n=N, algorithm="uniform-circle", params={"a": 4.0}, view=view)
    fake_asked: list[str] = []
    rogue, dashboard = net.client("agent-1"), net.client("dashboard-0")
    rogue.declare_queryable(snapshot_any_key(swarm), answering(fake.encode(), fake_asked))
    rogue.declare_queryable(snapshot_key(swarm, 2), answering(fake.encode(), fake_asked))
    dashboard.declare_queryable(snapshot_any_key(swarm), answering(fake.encode(), fake_asked))
    synced(net, rogue, "agent-1")
    synced(net, dashboard, "dashboard-0")
    agent = net.client("agent-2")
    assert replies(agent, snapshot_key(swarm, 2)) == []  # no world: nobody answers
    asked: list[str] = []
    net.client("world").declare_queryable(snapshot_any_key(swarm), answering(b"real", asked))
    querier = agent.declare_querier(snapshot_key(swarm, 2), timeout=ASK_S)  # as an agent asks
    wait_for("the world to answer", lambda: any(r.ok is not None for r in querier.get()))
    asked.clear()
    for _ in range(3):
        assert [r.ok.payload.to_bytes() for r in querier.get() if r.ok is not None] == [b"real"]
    assert fake_asked == [] and len(asked) == 3


def test_fake_moves_held_notices_reach_no_coordinator(net: Net) -> None:
    swarm = net.plan.swarm
    coordinator = Inbox()
    net.client("coordinator").declare_subscriber(moves_held_key(swarm), coordinator)
    world = net.client("world").declare_publisher(moves_held_key(swarm))
    first, last = (MovesHeld(round=r, robots=(0,)).encode() for r in (1, 2))
    deliver("the world's notice", lambda: world.put(first), lambda: first in coordinator.payloads())
    fake = MovesHeld(round=2, robots=(0, 1, 2)).encode()
    for rogue in ("agent-1", "dashboard-0"):
        net.client(rogue).put(moves_held_key(swarm), fake)
    world.put(last)
    wait_for("the world's next notice", lambda: last in coordinator.payloads())
    time.sleep(SETTLE_S)
    assert set(coordinator.payloads()) == {first, last}


def test_a_fake_control_reply_reaches_no_coordinator(net: Net) -> None:
    swarm = net.plan.swarm
    formed = ControlReply(
        ok=True, reason="", n=N, committed=5, open_round=0, status=Status.FORMED
    ).encode()
    fake_asked: list[str] = []
    for name in ("agent-1", "dashboard-0"):
        rogue = net.client(name)
        rogue.declare_queryable(control_key(swarm), answering(formed, fake_asked))
        synced(net, rogue, name)
    coordinator = net.client("coordinator")
    begin = Begin(1, (0,)).encode()
    assert replies(coordinator, control_key(swarm), begin) == []  # no world: no answer
    running = ControlReply(
        ok=True, reason="", n=N, committed=0, open_round=1, status=Status.RUNNING
    ).encode()
    net.client("world").declare_queryable(control_key(swarm), answering(running, []))
    wait_for("the world to answer", lambda: replies(coordinator, control_key(swarm), begin) != [])
    for _ in range(3):
        assert replies(coordinator, control_key(swarm), begin) == [running]
    assert fake_asked == []


def test_dashboards_and_agents_read_the_state_only_as_allowed(net: Net) -> None:
    swarm = net.plan.swarm
    dashboard, agent, others, everything = Inbox(), Inbox(), Inbox(), Inbox()
    watcher = net.client("dashboard-0")
    watcher.declare_subscriber(state_key(swarm), dashboard)
    watcher.declare_subscriber(moves_held_key(swarm), others)
    watcher.declare_subscriber(f"fatswarm/{swarm}/**", everything)  # gets what it may: the state
    reader = net.client("agent-1")
    reader.declare_subscriber(state_key(swarm), agent)  # positions: not an agent's to read
    synced(net, reader, "agent-1")
    net.client("dashboard-0").put(state_key(swarm), b"fake state")
    world = net.client("world")
    world.put(moves_held_key(swarm), MovesHeld(round=1, robots=(0,)).encode())
    states = world.declare_publisher(state_key(swarm))
    deliver(
        "the world's state", lambda: states.put(b"state"), lambda: b"state" in dashboard.payloads()
    )
    time.sleep(SETTLE_S)
    assert set(dashboard.payloads()) == {b"state"} == set(everything.payloads())
    assert agent.payloads() == [] and others.payloads() == []


def test_the_rogue_of_the_networked_test_sees_nothing_come_back(net: Net) -> None:
    """The same `Rogue` the network-namespace test runs on another host, here at once."""
    swarm = net.plan.swarm
    world = net.client("world")
    world.declare_queryable(snapshot_any_key(swarm), answering(b"view", []))
    world.declare_queryable(control_key(swarm), answering(b"ok", []))
    world.declare_publisher(state_key(swarm))
    for name in ("agent-1", "dashboard-0", "coordinator"):
        rogue = Rogue(net.client(name), net.client(name), swarm, N, victim=2)
        rogue.arm()
        for round_no in (1, 2):
            rogue.strike(round_no)
        seen = rogue.report()
        if name == "coordinator":  # its own job: control answered, notices it may read
            assert seen["control_replies"] == 6, seen
            seen["control_replies"] = 0
        assert seen == {**dict.fromkeys(seen, 0), "tries": 2}, (name, seen)


# --- no certificate of the swarm: no link at all -----------------------------------------------


def test_a_client_without_the_swarms_certificate_cannot_connect(net: Net, tmp_path: Path) -> None:
    import zenoh

    from fatswarm.deploy.secure.pki import write_bundle

    tcp = make_config("client", [net.endpoint.replace("tls/", "tcp/")])
    with pytest.raises(zenoh.ZError):  # a TLS port: plain TCP never gets a session
        zenoh.open(tcp)
    no_cert = tmp_path / "no-cert.json5"
    no_cert.write_text(
        f'{{ transport: {{ link: {{ tls: {{ root_ca_certificate: "{net.out / "ca.pem"}" }} }} }} }}'
    )
    with pytest.raises(zenoh.ZError):  # the server's CA, but no client certificate
        net.client("anyone", no_cert)
    other = tmp_path / "other"  # the same names, signed by another authority
    write_bundle(Plan(net.plan.swarm, N, ("127.0.0.1",), net.plan.port), other)
    with pytest.raises(zenoh.ZError):
        net.client("world", other / "world.json5")


def test_parts_refuse_a_plain_endpoint_or_a_bad_file_in_one_line(net: Net, tmp_path: Path) -> None:
    bad = tmp_path / "bad.json5"
    bad.write_text("{ mode: ")
    acl = tmp_path / "acl.json5"  # well formed, but a policy names a rule that is not there
    acl.write_text(
        f'{{ listen: {{ endpoints: ["tcp/127.0.0.1:{free_port()}"] }}, access_control: '
        '{ enabled: true, default_permission: "deny", rules: [{ id: "r", permission: '
        '"allow", flows: ["ingress"], messages: ["put"], key_exprs: ["a"] }], '
        'subjects: [{ id: "s", cert_common_names: ["x"] }], policies: [{ id: "p", '
        'rules: ["r2"], subjects: ["s"] }] } }'
    )
    plain = net.endpoint.replace("tls/", "tcp/")
    agent, router, agents, dashboard, acl_router = run_all(
        part(
            "agent", "--robot", "0", "--config", str(net.out / "agent-0.json5"), "--connect", plain
        ),
        part("router", "--config", str(bad)),
        part(
            "agents",
            "-n",
            "2",
            "--config",
            str(net.out / "agent-{robot}.json5"),
            "--first",
            "2",
            "--connect",
            net.endpoint,
        ),  # agent-3 has no file
        [
            sys.executable,
            "-m",
            "fatswarm.deploy.cli",
            "dashboard",
            "--config",
            str(bad),
            "--connect",
            net.endpoint,
        ],
        part("router", "--config", str(acl)),
    )
    assert_one_line(
        agent,
        f"fatswarm agent: endpoint {plain} uses a protocol --config "
        f"{net.out / 'agent-0.json5'} does not allow (transport/link/protocols: tls)",
    )
    assert_one_line(router, f"fatswarm router: --config {bad}: line 1, column 9: expected")
    assert_one_line(agents, f"fatswarm agents: --config {net.out / 'agent-3.json5'}: no such file")
    assert_one_line(dashboard, f"fatswarm dashboard: --config {bad}: line 1, column 9")
    assert_one_line(
        acl_router,
        f"fatswarm router: --config {acl}: access control not enabled "
        "due to: Rule 'r2' in policy #0 does not exist in rules list",
    )


@pytest.mark.parametrize("spawn", ["fork", "exec"])
def test_an_agents_host_gives_each_agent_its_own_identity(
    net: Net, tmp_path: Path, spawn: str
) -> None:
    """`{robot}` in --config: each agent's token is taken, which only its own identity may do."""
    swarm = net.plan.swarm
    dashboard = net.client("dashboard-0")  # may ask who is alive (world and coordinator subscribe)

    def tokens() -> list[str]:
        live = dashboard.liveliness().get(agent_alive_any_key(swarm), timeout=ASK_S)
        return sorted(str(r.ok.key_expr) for r in live if r.ok is not None)

    log = open(tmp_path / "agents.log", "wb")  # noqa: SIM115
    with Children() as children:
        children.start(
            "agents",
            part(
                "agents",
                "-n",
                "2",
                "--first",
                "1",
                "--spawn",
                spawn,
                "--config",
                str(net.out / "agent-{robot}.json5"),
                "--connect",
                net.endpoint,
                "--swarm",
                swarm,
            ),
            stdout=log,
            stderr=log,
        )
        log.close()
        wanted = [agent_alive_key(swarm, 1), agent_alive_key(swarm, 2)]
        wait_for("both agents' tokens", lambda: tokens() == wanted or bool(children.exited()))
        assert not children.exited(), (tmp_path / "agents.log").read_text()
