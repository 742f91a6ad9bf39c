"""The one place that builds Zenoh configurations, opens client sessions and words Zenoh's errors.

Defaults changed between Zenoh releases, so every setting the services rely on is explicit here.
Zenoh reports a bad endpoint or a missing router as a Rust error with source paths; every part
checks endpoints here first and shows what is left as one short sentence (`explain_zenoh_error`).
"""

from __future__ import annotations

import argparse
import errno
import ipaddress
import json
import os
import re
import socket
import threading
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import zenoh

DEFAULT_SWARM = "default"
# Agents announce a short lease so a hung (SIGSTOPped) agent is declared gone within ~2 s; a killed
# one is seen at once through its closed TCP link (see shared zenoh notes: 1.7 s at 2000 ms).
AGENT_LEASE_MS = 2000
ROUTER_ENDPOINT_HELP = "Zenoh endpoint, e.g. tcp/127.0.0.1:7447"
# A client's `zenoh.open` fails at once when no router listens; the world, the coordinator and
# `fatswarm run --connect` retry this long (a router started a moment later is fine), then give up.
CONNECT_DEADLINE_S = 5.0
CONNECT_RETRY_S = 0.2
# One world and one coordinator per swarm: each asks for its role's liveliness token before it
# declares its own (`token_held`). The routers answer such a get at once (< 1 ms on loopback);
# the timeout only bounds a router that went silent.
TOKEN_QUERY_S = 1.0
# A token can outlive its process for a moment: a killed process's token goes when its router sees
# the link close (about 1 ms on loopback), then crosses the other routers. A world or coordinator
# restarted right after the one it replaces must not be refused for it, so a token counts only if
# every look over about 2 s still finds it. (One whose host vanished, or that hangs, holds its
# token until its lease runs out, 10 s by default: it is refused meanwhile, as for a live one.)
TOKEN_LOOKS = 4
TOKEN_LOOK_EVERY_S = 0.6
# The link protocols of the eclipse-zenoh 1.10 wheel; the first five take <host>:<port>.
PROTOCOLS = ("tcp", "udp", "tls", "quic", "ws", "unixsock-stream")
_HOST_PORT_PROTOCOLS = frozenset(PROTOCOLS[:5])
_HOSTNAME = re.compile(
    r"(?=.{1,253}$)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
    r"(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?"
)


class ZenohSetupError(ValueError):
    """An endpoint is malformed, no router answers, or a router cannot listen (one line to show)."""


# --- Zenoh's errors in one sentence ----------------------------------------------------------

_RUST_AT = re.compile(r"\s*\bat\s+\S+\.rs:\d+(:\d+)?\.?")  # " at /root/.cargo/.../x.rs:447."
_RUST_BRACKET = re.compile(r"\s*\[[^\[\]\s]*\.rs:\d+(:\d+)?\]")  # "[zenoh/src/x.rs:447]"
_JSON5 = re.compile(r'Json5Err\(Message \{ msg: "(?P<msg>.*?)", location: .*\}\)', re.DOTALL)
_UNREACHABLE = re.compile(r"Unable to connect to any of \[(?P<eps>.*)\]!?")
_LISTENER = re.compile(r"Can not create a new \w+ listener bound to (?P<ep>\S+?): \[(?P<why>.*)\]")
_OS_ERROR = re.compile(r"\s*\(os error \d+\)")
_FORM = "Endpoints must be of the form <protocol>/<address>[?<metadata>][#<config>]: "


def explain_zenoh_error(exc: BaseException) -> str:
    """Zenoh's error message as one short sentence, without Rust source locations."""
    text = _RUST_BRACKET.sub("", _RUST_AT.sub("", str(exc)))
    if m := _JSON5.search(text):
        text = m["msg"].replace('\\"', '"')
    if text.startswith(_FORM):
        bad = text[len(_FORM) :]
        text = f"{bad!r} is not an endpoint: write <protocol>/<address>, e.g. tcp/127.0.0.1:7447"
    if m := _UNREACHABLE.search(text):
        endpoints = re.findall(r"Single\(([^()]*)\)", m["eps"]) or [m["eps"]]
        text = f"no Zenoh router answers at {', '.join(endpoints)}"
    if m := _LISTENER.search(text):
        why = m["why"].rpartition(": ")[2] or m["why"]
        text = f"cannot listen on {m['ep']}: {_lower_first(why)}"
    text = " ".join(_OS_ERROR.sub("", text).split()).rstrip(" .!")
    if "already in use" in text.lower():
        text += " (a router already running there? pick another port)"
    return _lower_first(text) or f"Zenoh failed ({type(exc).__name__})"


def _lower_first(text: str) -> str:
    """'Address already in use' -> 'address already in use'; 'TCP ...' stays."""
    if len(text) > 1 and text[0].isupper() and not text[1].isupper():
        return text[0].lower() + text[1:]
    return text


# --- endpoints -------------------------------------------------------------------------------


def endpoint_problem(endpoint: str, listening: bool = False) -> str | None:
    """What is wrong with `endpoint` as Zenoh would read it, or None (no name is resolved)."""
    protocol, slash, rest = endpoint.partition("/")
    if not slash or not protocol or not rest:
        return "write <protocol>/<address>, e.g. tcp/127.0.0.1:7447"
    if protocol not in PROTOCOLS:
        return f"unknown protocol {protocol!r} (use one of {', '.join(PROTOCOLS)})"
    if protocol not in _HOST_PORT_PROTOCOLS:
        return None
    address = re.split(r"[?#]", rest, maxsplit=1)[0]
    host, colon, port = address.rpartition(":")
    if not colon or not host:
        return f"the address must be <host>:<port>, e.g. {protocol}/127.0.0.1:7447"
    least = 0 if listening else 1
    if not port.isdigit() or not least <= int(port) <= 65535:
        return f"the port must be a whole number in {least}..65535, got {port!r}"
    return _host_problem(host)


def _host_problem(host: str) -> str | None:
    """What is wrong with the host of a <host>:<port> address, or None (no name is resolved)."""
    if host.startswith("[") and host.endswith("]"):
        return None if _is_ip(host[1:-1], 6) else f"{host} is not an IPv6 address"
    if re.fullmatch(r"[0-9.]+", host):
        return None if _is_ip(host, 4) else f"{host!r} is not an IPv4 address"
    if not _HOSTNAME.fullmatch(host):
        return f"{host!r} is neither an IP address nor a host name"
    return None


def _is_ip(text: str, version: int) -> bool:
    try:
        return ipaddress.ip_address(text).version == version
    except ValueError:
        return False


def check_endpoints(endpoints: Sequence[str], flag: str) -> None:
    """Raise ZenohSetupError naming `flag` (`--connect`, `--listen`) and the first bad endpoint."""
    for endpoint in endpoints:
        problem = endpoint_problem(endpoint, listening=flag == "--listen")
        if problem is not None:
            raise ZenohSetupError(f"bad {flag} endpoint {endpoint!r}: {problem}")


def _host_port(endpoint: str) -> tuple[str, int] | None:
    """(host, port) of a <protocol>/<host>:<port> endpoint, brackets of IPv6 removed; else None."""
    protocol, _, rest = endpoint.partition("/")
    if protocol not in _HOST_PORT_PROTOCOLS:
        return None
    host, _, port = re.split(r"[?#]", rest, maxsplit=1)[0].rpartition(":")
    return host.strip("[]"), int(port)


# The largest message a router passes on (and a session takes in): larger ones are dropped where
# they are reassembled, before any part holds them. A 4096-robot state is ~200 KB.
MAX_MESSAGE_IN = 512 << 10


RETRY_INIT_MS = 50  # a lost router is tried again after this, then twice as long each time...
RETRY_MAX_MS = 500  # ...up to this
# Zenoh's open of a router session waits `scouting/delay` (500 ms by default) for peers to appear,
# even with scouting off. A router linked to no other router has nobody to wait for: it opens at
# once (a restarted world that hosts the router is back 0.5 s sooner). One with --connect links
# keeps the wait, so that its world finds another world on the network before it starts.
LONE_ROUTER_DELAY_MS = 0


# An agent exchanges two small messages a round, the world a few per robot: one Zenoh worker
# thread for every runtime of the process instead of 8 (rx, tx, net, acc handed over to it).
# Measured at n = 64, fsync, 2 cores: a fifth less CPU per Look in the agents (an earlier round
# of work), a quarter less in the world hosting the router (0.22 -> 0.16 ms; docs/results.md).
ONE_WORKER_RUNTIME = (
    "(app: (worker_threads: 1), rx: (handover: app), tx: (handover: app), "
    "net: (handover: app), acc: (handover: app))"
)


def settle_runtime() -> None:
    """One Zenoh worker thread for this process (ONE_WORKER_RUNTIME), unless the user set
    ZENOH_RUNTIME. Zenoh reads it when the process opens its first session: call it before."""
    os.environ.setdefault("ZENOH_RUNTIME", ONE_WORKER_RUNTIME)


def make_config(
    mode: str,
    connect: Sequence[str] = (),
    listen: Sequence[str] = (),
    lease_ms: int | None = None,
    shared_memory: bool = True,
    max_message_in: int = MAX_MESSAGE_IN,
    config_file: str | None = None,
    default_listen: Sequence[str] = (),
) -> zenoh.Config:
    """A Zenoh config with multicast (and gossip) scouting off and the given (checked) endpoints.

    `config_file` (`--config`): Zenoh's own configuration file to start from (see
    `load_config_file`). Applied on top of it: the mode, multicast scouting off, the message size
    limit, the lease and shared memory as given here, and the endpoints given here; the file's
    endpoints stay where none are given (`default_listen` where neither gives any). The file wins
    for everything else (TLS, access control, authentication, timeouts...).

    Raises ZenohSetupError for a malformed endpoint, a bad file or an endpoint the file's
    `transport/link/protocols` does not allow; ValueError for an unknown mode.
    """
    import zenoh  # lazily: what only checks endpoints or adds flags never loads zenoh

    if mode not in ("client", "peer", "router"):
        raise ValueError(f"mode must be client, peer or router, got {mode!r}")
    check_endpoints(connect, "--connect")
    check_endpoints(listen, "--listen")
    conf = zenoh.Config() if config_file is None else load_config_file(config_file)
    conf.insert_json5("mode", json.dumps(mode))
    conf.insert_json5("scouting/multicast/enabled", "false")
    try:
        for key, given, default in (
            ("connect/endpoints", connect, ()),
            ("listen/endpoints", listen, default_listen),
        ):
            if given or config_file is None or not _endpoints_in(conf, key):
                conf.insert_json5(key, json.dumps(list(given or default)))
    except zenoh.ZError as exc:  # something endpoint_problem let through
        raise ZenohSetupError(explain_zenoh_error(exc)) from None
    if config_file is not None:
        _check_protocols(conf, config_file)
    conf.insert_json5("transport/link/rx/max_message_size", str(int(max_message_in)))
    if not shared_memory:
        # Agents send and receive small messages only; no 16 MB SHM pool per process.
        conf.insert_json5("transport/shared_memory/enabled", "false")
    if lease_ms is not None:
        conf.insert_json5("transport/link/tx/lease", str(int(lease_ms)))
    _set_reconnection(conf, mode, config_file)
    return conf


def _set_reconnection(conf: zenoh.Config, mode: str, config_file: str | None) -> None:
    """The reconnection pace and, for a router linked to no other router, no scouting delay:
    defaults a `config_file` may override (docs/security.md), so set only where it does not."""
    if (
        mode == "router"
        and not connect_endpoints(conf)
        and (config_file is None or json.loads(conf.get_json("scouting/delay")) is None)
    ):
        conf.insert_json5("scouting/delay", str(LONE_ROUTER_DELAY_MS))
    if config_file is None or json.loads(conf.get_json("connect/retry")) is None:
        # A restarted router is found again within RETRY_MAX_MS (Zenoh's default backs off to 4 s)
        conf.insert_json5(
            "connect/retry",
            json.dumps(
                {
                    "period_init_ms": RETRY_INIT_MS,
                    "period_max_ms": RETRY_MAX_MS,
                    "period_increase_factor": 2,
                }
            ),
        )


def connect_endpoints(conf: zenoh.Config) -> list[str]:
    """The `connect/endpoints` of a config (what a waiting client reports)."""
    return _endpoints_in(conf, "connect/endpoints") or []


def listen_endpoints(conf: zenoh.Config) -> list[str]:
    """The `listen/endpoints` of a config."""
    return _endpoints_in(conf, "listen/endpoints") or []


def _endpoints_in(conf: zenoh.Config, key: str) -> list[str] | None:
    """The endpoint list at `key`, or None where the config holds Zenoh's per-mode default."""
    endpoints: Any = json.loads(conf.get_json(key))
    return [str(e) for e in endpoints] if isinstance(endpoints, list) else None


# --- `--config FILE` -------------------------------------------------------------------------

# The paths a Zenoh configuration names (relative ones are taken from the file's folder).
CONFIG_PATHS = (
    "transport/link/tls/root_ca_certificate",
    "transport/link/tls/listen_private_key",
    "transport/link/tls/listen_certificate",
    "transport/link/tls/connect_private_key",
    "transport/link/tls/connect_certificate",
    "transport/auth/usrpwd/dictionary_file",
)
CONFIG_SUFFIXES = (".json5", ".json", ".yaml")
_PEST_AT = re.compile(r"^\s*-->\s*(?P<line>\d+):(?P<col>\d+).*?=\s*(?P<msg>[^\n]*)", re.DOTALL)
_SERDE_AT = re.compile(
    r'msg: "(?P<msg>.*?)", location: Some\(Location \{ line: (?P<line>\d+), '
    r"column: (?P<col>\d+) \}\)",
    re.DOTALL,
)


def load_config_file(path: str) -> zenoh.Config:
    """Zenoh's own configuration file (`--config`: JSON5, JSON or YAML, as `zenoh.Config.from_file`
    reads it), with every relative certificate, key or password-file path taken from the file's
    folder (Zenoh alone reads them from the working directory), so a folder made by
    `fatswarm secure` works from anywhere.

    Raises ZenohSetupError in one line: a missing or unreadable file, one Zenoh cannot parse (with
    line and column), or a file it names that is not there.
    """
    import zenoh  # lazily: what only checks endpoints or adds flags never loads zenoh

    where = f"--config {path}"
    if not os.path.isfile(path):
        why = "is a folder" if os.path.isdir(path) else "no such file"
        raise ZenohSetupError(f"{where}: {why}")
    if not path.lower().endswith(CONFIG_SUFFIXES):
        raise ZenohSetupError(f"{where}: Zenoh reads only {', '.join(CONFIG_SUFFIXES)} files")
    try:
        conf = zenoh.Config.from_file(path)
    except zenoh.ZError as exc:
        raise ZenohSetupError(f"{where}: {explain_config_error(exc)}") from None
    folder = os.path.dirname(os.path.abspath(path))
    for key in CONFIG_PATHS:
        named: Any = json.loads(conf.get_json(key))
        if not isinstance(named, str) or not named:
            continue
        full = named if os.path.isabs(named) else os.path.join(folder, named)
        if not os.path.isfile(full):
            raise ZenohSetupError(f"{where}: {key.rpartition('/')[2]} {full}: no such file")
        conf.insert_json5(key, json.dumps(full))
    return conf


def explain_config_error(exc: BaseException) -> str:
    """Zenoh's complaint about a configuration file in one line, with line and column."""
    text = str(exc)
    for pattern in (_SERDE_AT, _PEST_AT):
        if m := pattern.search(text):
            msg = " ".join(_RUST_AT.sub("", m["msg"].replace('\\"', '"')).split()).rstrip(" .")
            return f"line {m['line']}, column {m['col']}: {_lower_first(msg)}"
    return explain_zenoh_error(exc)


def _check_protocols(conf: zenoh.Config, path: str) -> None:
    """Refuse an endpoint whose protocol the file's `transport/link/protocols` leaves out (Zenoh
    would fail on it with no word of why)."""
    allowed: Any = json.loads(conf.get_json("transport/link/protocols"))
    if not isinstance(allowed, list):
        return
    for key in ("connect/endpoints", "listen/endpoints"):
        for endpoint in _endpoints_in(conf, key) or []:
            if endpoint.partition("/")[0] not in allowed:
                raise ZenohSetupError(
                    f"endpoint {endpoint} uses a protocol --config {path} does not allow "
                    f"(transport/link/protocols: {', '.join(map(str, allowed))})"
                )


# --- opening sessions ------------------------------------------------------------------------


def open_client(
    conf: zenoh.Config,
    stop: threading.Event | None = None,
    deadline_s: float = CONNECT_DEADLINE_S,
) -> Any:
    """An open client zenoh.Session, retried until a router answers; None if `stop` is set first.

    Raises ZenohSetupError after `deadline_s` without a router, or at once for any other refusal.
    """
    import zenoh  # lazily: what only checks endpoints or adds flags never loads zenoh

    stop = stop or threading.Event()
    deadline = time.monotonic() + deadline_s
    while True:
        try:
            return zenoh.open(conf)
        except zenoh.ZError as exc:
            if not _UNREACHABLE.search(str(exc)):
                why = explain_zenoh_error(exc)
                raise ZenohSetupError(f"cannot open a Zenoh session: {why}") from None
        if time.monotonic() >= deadline:
            raise ZenohSetupError(unreachable_message(connect_endpoints(conf), deadline_s))
        if stop.wait(CONNECT_RETRY_S):
            return None


def token_held(session: Any, key: str, stop: threading.Event | None = None) -> bool:
    """Whether a liveliness token on `key` is live on the router network and stays so.

    True only if each of TOKEN_LOOKS liveliness gets, TOKEN_LOOK_EVERY_S apart, finds one (see
    TOKEN_LOOKS for why); False at the first look that finds none, or if `stop` is set meanwhile.
    """
    import zenoh  # lazily: what only checks endpoints or adds flags never loads zenoh

    stop = stop or threading.Event()
    for look in range(TOKEN_LOOKS):
        if look and stop.wait(TOKEN_LOOK_EVERY_S):
            return False
        try:
            replies = session.liveliness().get(key, timeout=TOKEN_QUERY_S)
            if not any(reply.ok is not None for reply in replies):
                return False
        except zenoh.ZError:  # the router went away: nobody to ask, start as before this check
            return False
    return True


def unreachable_message(endpoints: Sequence[str], waited_s: float) -> str:
    """Why nothing answered at `endpoints` after `waited_s`, and what to do, in one line."""
    for endpoint in endpoints:
        host_port = _host_port(endpoint)
        if host_port is not None and not _resolves(*host_port):
            return f"host {host_port[0]!r} of --connect {endpoint} is not known: fix --connect"
    where = ", ".join(endpoints)
    first = endpoints[0] if endpoints else "ENDPOINT"
    if any(e.startswith("tls/") for e in endpoints):  # a refused handshake looks the same
        return (
            f"no Zenoh router answers at {where} (tried for {waited_s:g} s), or it refused "
            "this part's certificate: start one there, or check that both --config files "
            "come from the same `fatswarm secure` folder and that its certificate names this "
            "address"
        )
    return (
        f"no Zenoh router answers at {where} (tried for {waited_s:g} s): start one there "
        f"(fatswarm router --listen {first}) or fix --connect"
    )


def _resolves(host: str, port: int) -> bool:
    """Whether `host` is an IP address or a name the resolver knows."""
    if _is_ip(host, 4) or _is_ip(host, 6):
        return True
    try:
        socket.getaddrinfo(host, port)
    except (OSError, UnicodeError):
        return False
    return True


def check_network(connect: Sequence[str], listen: Sequence[str]) -> None:
    """For `fatswarm run`: raise ZenohSetupError unless the run can use its endpoints.

    With `connect`, a router must answer there within CONNECT_DEADLINE_S; otherwise the `listen`
    endpoints of the router to start must be well formed and free (a TCP/UDP bind, at once).
    """
    if connect:
        session = open_client(make_config("client", connect=connect))
        if session is not None:
            session.close()
        return
    check_endpoints(listen, "--listen")
    for endpoint in listen:
        problem = _bind_problem(endpoint)
        if problem is not None:
            raise ZenohSetupError(f"cannot listen on {endpoint}: {problem}")


def _bind_problem(endpoint: str) -> str | None:
    """Why a router could not listen on a host:port endpoint (tried with a socket), or None."""
    host_port = _host_port(endpoint)
    if host_port is None:
        return None
    kind = socket.SOCK_DGRAM if endpoint.startswith(("udp/", "quic/")) else socket.SOCK_STREAM
    try:
        infos = socket.getaddrinfo(host_port[0], host_port[1], type=kind)
    except (OSError, UnicodeError):
        return f"host {host_port[0]!r} is not known"
    family, _, _, _, address = infos[0]
    try:
        with socket.socket(family, kind) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as Zenoh's listener
            probe.bind(address)
    except OSError as exc:
        reason = (exc.strerror or str(exc)).lower()
        if exc.errno == errno.EADDRINUSE:
            reason += " (a router already running there? pick another port)"
        return reason
    return None


# --- flags -----------------------------------------------------------------------------------


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port that was free a moment ago on `host` (the OS picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        port: int = s.getsockname()[1]
        return port


def loopback_endpoint() -> str:
    """`tcp/127.0.0.1:<free port>`."""
    return f"tcp/127.0.0.1:{free_port()}"


def add_zenoh_arguments(
    p: argparse.ArgumentParser,
    listen_default: Sequence[str] = (),
    connect_note: str = "",
    *,
    swarm: bool = True,
) -> None:
    """`--connect`, `--listen` (repeatable) and `--swarm`, shared by every networked command
    (`swarm` False: a router, which routes every swarm, takes no --swarm)."""
    p.add_argument(
        "--connect",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help=f"router to connect to (repeatable); {ROUTER_ENDPOINT_HELP}{connect_note}",
    )
    p.add_argument(
        "--listen",
        action="append",
        default=list(listen_default),
        metavar="ENDPOINT",
        help="endpoint to listen on (repeatable)",
    )
    if swarm:
        p.add_argument(
            "--swarm",
            default=DEFAULT_SWARM,
            help=f"swarm name: all keys live under fatswarm/<swarm>/ (default {DEFAULT_SWARM!r})",
        )
