"""A secured swarm on paper: its identities, Zenoh's access control (default deny) and each part's
Zenoh configuration, as plain data built from the swarm's name, n and its routers' hosts.

Pure: no file, no certificate, no zenoh. `deploy/secure/pki.py` issues the certificates and writes
the files. Every key expression comes from the protocol modules' functions, so a key renamed there
is renamed here; docs/security.md shows the resulting matrix.
"""

from __future__ import annotations

import ipaddress
import json
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from fatswarm.coordinator import protocol as coordinator_wire
from fatswarm.domain import wire
from fatswarm.world import protocol as world_wire

DEFAULT_PORT = 7447
LOOPBACK = "127.0.0.1"  # every router also listens here: its host's parts connect to it there
MAX_DASHBOARDS = 64
# Zenoh 1.10's ACL message kinds (zenoh-config AclMessage), in its own spelling.
MESSAGES = (
    "put",
    "delete",
    "declare_subscriber",
    "query",
    "declare_queryable",
    "reply",
    "liveliness_token",
    "declare_liveliness_subscriber",
    "liveliness_query",
)
# ingress: what the part sends its router; egress: what its router hands it.
FLOWS = ("ingress", "egress")
ROLES = ("router", "world", "coordinator", "agent", "dashboard")
_HOSTNAME = re.compile(
    r"(?=.{1,253}$)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
    r"(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*"
)


@dataclass(frozen=True, slots=True)
class Identity:
    """One part of the swarm with a certificate of its own: `name` is the certificate's common
    name (what the routers' ACL matches) and the stem of its files."""

    name: str  # "world", "coordinator", "agent-3", "dashboard-0", "router-10.0.0.1"
    role: str  # one of ROLES
    robot: int | None = None  # agents only
    host: str | None = None  # routers only: the address (IP or DNS name) it listens on


@dataclass(frozen=True, slots=True)
class Grant:
    """One thing the routers let an identity do: `message` on `key`, in `flow`."""

    flow: str  # "ingress": the part sends it; "egress": the router delivers it to the part
    message: str  # one of MESSAGES
    key: str  # a key expression; a message is let through if its key is included in this one


@dataclass(frozen=True, slots=True)
class Plan:
    """What `fatswarm secure` makes for one swarm."""

    swarm: str
    n: int
    hosts: tuple[str, ...]  # one router per host, by the address the others reach it at
    port: int = DEFAULT_PORT
    dashboards: int = 1

    def __post_init__(self) -> None:
        wire.check_swarm(self.swarm)
        if isinstance(self.n, bool) or not 1 <= self.n <= wire.MAX_ROBOTS:
            raise ValueError(f"-n must be in 1..{wire.MAX_ROBOTS}, got {self.n}")
        if not self.hosts:
            raise ValueError("give at least one router host (--hosts ADDRESS,...)")
        for host in self.hosts:
            problem = host_problem(host)
            if problem is not None:
                raise ValueError(f"bad --hosts entry {host!r}: {problem}")
        if len(set(self.hosts)) != len(self.hosts):
            raise ValueError("--hosts names a host twice")
        if not 1 <= self.port <= 65535:
            raise ValueError(f"--port must be in 1..65535, got {self.port}")
        if not 0 <= self.dashboards <= MAX_DASHBOARDS:
            raise ValueError(f"--dashboards must be in 0..{MAX_DASHBOARDS}, got {self.dashboards}")

    @property
    def routers(self) -> tuple[Identity, ...]:
        return tuple(Identity(f"router-{h}", "router", host=h) for h in self.hosts)

    @property
    def identities(self) -> tuple[Identity, ...]:
        """Every identity: the routers, the world, the coordinator, the agents, the dashboards."""
        return (
            *self.routers,
            Identity("world", "world"),
            Identity("coordinator", "coordinator"),
            *(Identity(f"agent-{i}", "agent", robot=i) for i in range(self.n)),
            *(Identity(f"dashboard-{k}", "dashboard") for k in range(self.dashboards)),
        )

    def endpoint(self, host: str) -> str:
        """The TLS endpoint of the router on `host`, as other hosts reach it."""
        return f"tls/{_bracketed(host)}:{self.port}"

    @property
    def local_endpoint(self) -> str:
        """Where the parts on a router's own host reach it (loopback: a link that goes down on
        the host does not cut them off their router)."""
        return self.endpoint(LOOPBACK)

    def listen(self, host: str) -> list[str]:
        """The endpoints the router on `host` listens on: its address and loopback (only its
        address if that is a loopback one: routers tried out on one machine)."""
        if is_loopback(host):
            return [self.endpoint(host)]
        return [self.endpoint(host), self.local_endpoint]


def host_problem(host: str) -> str | None:
    """What is wrong with `host` as a router's address in a certificate, or None."""
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        if re.fullmatch(r"[0-9.]+", host):
            return "not an IPv4 address"
        if not _HOSTNAME.fullmatch(host):
            return "neither an IP address nor a host name"
        return None
    if address.is_unspecified:
        return "a wildcard address: give the address the other hosts reach this one at"
    return None


def _bracketed(host: str) -> str:
    try:
        return f"[{host}]" if ipaddress.ip_address(host).version == 6 else host
    except ValueError:
        return host


def is_loopback(host: str) -> bool:
    """Whether `host` is this machine's loopback (127.x, ::1, localhost)."""
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return host.lower().rstrip(".") == "localhost"


def is_ip(host: str) -> bool:
    """Whether `host` is an IP address (its certificate names it as an IP, not a DNS name)."""
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return False
    return True


# --- who may do what -------------------------------------------------------------------------


def _both(flow_in: Iterable[tuple[str, str]], flow_out: Iterable[tuple[str, str]]) -> list[Grant]:
    return [Grant("ingress", m, k) for m, k in flow_in] + [
        Grant("egress", m, k) for m, k in flow_out
    ]


def grants(swarm: str, who: Identity) -> tuple[Grant, ...]:
    """Everything the routers let `who` do on `swarm`; anything else is denied.

    A publisher or querier also receives the declarations of the subscribers or queryables that
    match its keys, as they were declared (an agent's own snapshot key matches the world's
    queryable on every robot's snapshots): a client sends a put or a query only while it knows of
    a receiver, so without them its messages would silently not be sent.

    A robot's move travels only inside its own Look (`LookRequest.move`): the `robot/<i>/move`
    route, open to any client of an unsecured swarm, is granted to nobody here.
    """
    keys = _Keys.of(swarm)
    role_grants = _ROLE_GRANTS.get(who.role)
    if role_grants is None:
        raise ValueError(f"unknown role {who.role!r}")
    return tuple(role_grants(keys, who))


@dataclass(frozen=True, slots=True)
class _Keys:
    """The key expressions of one swarm that the grants name (from the protocol modules)."""

    swarm: str
    state: str
    control: str
    held: str
    snapshots: str
    agents_alive: str
    world_alive: str
    coordinator_alive: str

    @staticmethod
    def of(swarm: str) -> _Keys:
        return _Keys(
            swarm,
            state=world_wire.state_key(swarm),
            control=world_wire.control_key(swarm),
            held=world_wire.moves_held_key(swarm),
            snapshots=world_wire.snapshot_any_key(swarm),
            agents_alive=world_wire.agent_alive_any_key(swarm),
            world_alive=world_wire.alive_key(swarm),
            coordinator_alive=coordinator_wire.alive_key(swarm),
        )

    @property
    def presence(self) -> tuple[str, str, str]:
        """The liveliness keys of the agents, the world and the coordinator."""
        return (self.agents_alive, self.world_alive, self.coordinator_alive)


def _agent_grants(k: _Keys, who: Identity) -> list[Grant]:
    if who.robot is None:
        raise ValueError(f"agent identity {who.name} has no robot")
    look = world_wire.snapshot_key(k.swarm, who.robot)
    return _both(
        [
            ("query", look),
            ("liveliness_token", world_wire.agent_alive_key(k.swarm, who.robot)),
            ("declare_liveliness_subscriber", k.world_alive),
        ],
        # the world's queryable, as declared: no data, only that it exists; and the world's
        # token (an agent asks again when a world comes up)
        [
            ("reply", look),
            ("declare_queryable", k.snapshots),
            ("liveliness_token", k.world_alive),
        ],
    )


def _world_grants(k: _Keys, who: Identity) -> list[Grant]:
    return _both(
        [
            ("declare_queryable", k.snapshots),
            ("declare_queryable", k.control),
            ("reply", k.snapshots),
            ("reply", k.control),
            ("put", k.state),
            ("put", k.held),
            ("declare_liveliness_subscriber", k.agents_alive),
            ("liveliness_token", k.world_alive),
            ("liveliness_query", k.world_alive),
        ],
        [
            ("query", k.snapshots),
            ("query", k.control),
            ("liveliness_token", k.agents_alive),
            ("liveliness_token", k.world_alive),
            ("declare_subscriber", k.state),
            ("declare_subscriber", k.held),
        ],
    )


def _coordinator_grants(k: _Keys, who: Identity) -> list[Grant]:
    return _both(
        [
            ("query", k.control),
            ("declare_subscriber", k.held),
            ("declare_liveliness_subscriber", k.agents_alive),
            ("declare_liveliness_subscriber", k.world_alive),
            ("liveliness_token", k.coordinator_alive),
            ("liveliness_query", k.world_alive),
            ("liveliness_query", k.coordinator_alive),
        ],
        [
            ("reply", k.control),
            ("put", k.held),
            ("declare_queryable", k.control),
            ("liveliness_token", k.agents_alive),
            ("liveliness_token", k.world_alive),
            ("liveliness_token", k.coordinator_alive),
        ],
    )


def _dashboard_grants(k: _Keys, who: Identity) -> list[Grant]:
    return _both(
        [
            ("declare_subscriber", k.state),
            *(("declare_liveliness_subscriber", key) for key in k.presence),
            *(("liveliness_query", key) for key in k.presence),
        ],
        [("put", k.state), *(("liveliness_token", key) for key in k.presence)],
    )


def _router_grants(k: _Keys, who: Identity) -> list[Grant]:
    # a router passes on what the other routers let in: all the swarm's
    everything = f"{wire.prefix(k.swarm)}/**"
    return [Grant(flow, m, everything) for flow in FLOWS for m in MESSAGES]


_ROLE_GRANTS: dict[str, Callable[[_Keys, Identity], list[Grant]]] = {
    "agent": _agent_grants,
    "world": _world_grants,
    "coordinator": _coordinator_grants,
    "dashboard": _dashboard_grants,
    "router": _router_grants,
}


def access_control(plan: Plan) -> dict[str, Any]:
    """Zenoh's `access_control` block: default deny, one subject (certificate common name) and
    one policy per identity, one rule per (identity, flow, message) listing its keys."""
    rules: list[dict[str, Any]] = []
    subjects: list[dict[str, Any]] = []
    policies: list[dict[str, Any]] = []
    for who in plan.identities:
        by_kind: dict[tuple[str, str], list[str]] = {}
        for g in grants(plan.swarm, who):
            keys = by_kind.setdefault((g.flow, g.message), [])
            if g.key not in keys:
                keys.append(g.key)
        ids = []
        for (flow, message), keys in by_kind.items():
            rule_id = f"{who.name} {flow} {message}"
            rules.append(
                {
                    "id": rule_id,
                    "permission": "allow",
                    "flows": [flow],
                    "messages": [message],
                    "key_exprs": keys,
                }
            )
            ids.append(rule_id)
        subjects.append({"id": who.name, "cert_common_names": [who.name]})
        policies.append({"id": who.name, "rules": ids, "subjects": [who.name]})
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


# --- each part's Zenoh configuration ----------------------------------------------------------


def files_of(who: Identity) -> tuple[str, str]:
    """The names of `who`'s private key and certificate files."""
    return f"{who.name}.key", f"{who.name}.pem"


CA_FILE = "ca.pem"


def _tls(who: Identity) -> dict[str, Any]:
    key, cert = files_of(who)
    tls: dict[str, Any] = {
        "root_ca_certificate": CA_FILE,
        "enable_mtls": True,
        "verify_name_on_connect": True,
        "connect_private_key": key,
        "connect_certificate": cert,
    }
    if who.role == "router":
        tls.update(listen_private_key=key, listen_certificate=cert)
    return {"protocols": ["tls"], "tls": tls}


def part_config(plan: Plan, who: Identity) -> dict[str, Any]:
    """The Zenoh configuration of `who` (file paths relative to the configuration file).

    A router listens on its host's TLS endpoint and on loopback, connects to the routers listed
    before it (one link per pair, each retried by one side), and holds the access control; a
    client holds only its credentials: it gets its router with --connect.
    """
    conf: dict[str, Any] = {
        "mode": "router" if who.role == "router" else "client",
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": {"link": _tls(who)},
    }
    if who.role == "router":
        assert who.host is not None
        earlier = plan.hosts[: plan.hosts.index(who.host)]
        conf["listen"] = {"endpoints": plan.listen(who.host)}
        conf["connect"] = {"endpoints": [plan.endpoint(h) for h in earlier]}
        conf["access_control"] = access_control(plan)
    return conf


def config_text(plan: Plan, who: Identity) -> str:
    """`who`'s configuration as a JSON5 file (JSON with a comment saying what it is)."""
    head = (
        f"// fatswarm secure: swarm {plan.swarm!r}, identity {who.name!r} ({who.role}).\n"
        "// Certificate and key paths are relative to this file's folder (fatswarm reads\n"
        "// them so; plain Zenoh reads them relative to its working directory).\n"
    )
    return head + json.dumps(part_config(plan, who), indent=2) + "\n"


def config_name(who: Identity) -> str:
    return f"{who.name}.json5"


def matrix() -> list[tuple[str, str, str, str]]:
    """The access-control matrix as docs/security.md shows it: (who, flow, message, key) with keys
    relative to `fatswarm/<swarm>/`, robot i's keys written with `<i>`, one row per grant of one
    identity of each role (robot i standing for every agent, `dashboard-k` for every dashboard)."""
    who = {
        "router": Identity("router-<host>", "router", host="h"),
        "world": Identity("world", "world"),
        "coordinator": Identity("coordinator", "coordinator"),
        "agent": Identity("agent-<i>", "agent", robot=0),
        "dashboard": Identity("dashboard-<k>", "dashboard"),
    }
    swarm = "S"
    root = f"{wire.prefix(swarm)}/"
    rows = []
    for role in ROLES:
        for g in grants(swarm, who[role]):
            key = g.key.removeprefix(root)
            if role == "agent":
                key = re.sub(r"(^|/)0(/|$)", r"\1<i>\2", key)
            rows.append((who[role].name, g.flow, g.message, key))
    return rows
