"""Zenoh endpoints and errors: malformed endpoints refused up front, Zenoh's errors in one line
(what opening a real session raises is in tests/integration/test_zconf_sessions.py)."""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path

import pytest
import zenoh

from fatswarm.deploy.net.zconf import (
    ONE_WORKER_RUNTIME,
    ZenohSetupError,
    check_network,
    endpoint_problem,
    explain_zenoh_error,
    free_port,
    make_config,
    settle_runtime,
    unreachable_message,
)

# Verbatim messages of eclipse-zenoh 1.10 (Rust source paths included), and what we show instead.
RUST = "/root/.cargo/git/checkouts/zenoh-9c599d5ef3e0480e/cc83980"
ZENOH_SAYS = [
    (
        f"Unable to connect to any of [Single(tcp/127.0.0.1:1), Single(tcp/[::1]:2)]!  at "
        f"{RUST}/zenoh/src/net/runtime/orchestrator.rs:447.",
        "no Zenoh router answers at tcp/127.0.0.1:1, tcp/[::1]:2",
    ),
    (
        'Json5Err(Message { msg: "Endpoints must be of the form <protocol>/<address>[?<metadata>]'
        f'[#<config>]: garbage at {RUST}/commons/zenoh-protocol/src/core/endpoint.rs:615.", '
        f"location: Some(Location {{ line: 1, column: 2 }}) }}) at "
        f"{RUST}/zenoh/src/api/config.rs:86.",
        "'garbage' is not an endpoint: write <protocol>/<address>, e.g. tcp/127.0.0.1:7447",
    ),
    (
        f"Can not create a new TCP listener bound to tcp/127.0.0.1:7447: [127.0.0.1:7447: Address "
        f"already in use (os error 98) at {RUST}/io/zenoh-link-commons/src/tcp.rs:61.] at "
        f"{RUST}/io/zenoh-links/zenoh-link-tcp/src/unicast.rs:338.",
        "cannot listen on tcp/127.0.0.1:7447: address already in use (a router already running "
        "there? pick another port)",
    ),
    (
        f"Can not create a new TCP listener bound to tcp/10.9.9.9:7447: [10.9.9.9:7447: Cannot "
        f"assign requested address (os error 99) at "
        f"{RUST}/io/zenoh-link-commons/src/tcp.rs:61.] at "
        f"{RUST}/io/zenoh-links/zenoh-link-tcp/src/unicast.rs:338.",
        "cannot listen on tcp/10.9.9.9:7447: cannot assign requested address",
    ),
    (f"invalid port value at {RUST}/io/zenoh-link-commons/src/lib.rs:62.", "invalid port value"),
    (
        "Unicast not supported for foo protocol [zenoh-link/src/lib.rs:183]",
        "unicast not supported for foo protocol",
    ),
]


@pytest.mark.parametrize(("message", "shown"), ZENOH_SAYS)
def test_zenoh_messages_become_one_sentence_without_rust_source_paths(
    message: str, shown: str
) -> None:
    assert explain_zenoh_error(zenoh.ZError(message)) == shown


@pytest.mark.parametrize(
    ("endpoint", "problem"),
    [
        ("garbage", "write <protocol>/<address>"),
        ("tcp/notanip:x", "the port must be a whole number in 1..65535, got 'x'"),
        ("tcp/127.0.0.1", "the address must be <host>:<port>"),
        ("tcp/127.0.0.1:70000", "the port must be"),
        ("tcp/127.0.0.1:0", "the port must be"),  # nothing to connect to
        ("tcp/1.2.3:7447", "'1.2.3' is not an IPv4 address"),
        ("tcp/[::1:7447", "neither an IP address nor a host name"),
        ("tcp/a_b:7447", "neither an IP address nor a host name"),
        ("TCP/127.0.0.1:7447", "unknown protocol 'TCP'"),
        ("foo/127.0.0.1:7447", "unknown protocol 'foo'"),
    ],
)
def test_malformed_endpoints_are_refused_with_the_flag_and_what_to_fix(
    endpoint: str, problem: str
) -> None:
    found = endpoint_problem(endpoint)
    assert found is not None and problem in found
    with pytest.raises(ZenohSetupError, match=r"^bad --connect endpoint '") as info:
        make_config("client", connect=[endpoint])
    assert problem in str(info.value)


@pytest.mark.parametrize(
    "endpoint",
    [
        "tcp/127.0.0.1:7447",
        "tcp/localhost:7447",
        "tcp/[::1]:7447",
        "udp/10.0.0.1:7447",
        "tcp/0.0.0.0:7447?iface=lo",
        "ws/router.lab:80",
        "unixsock-stream//tmp/zenoh.sock",
    ],
)
def test_well_formed_endpoints_pass(endpoint: str) -> None:
    assert endpoint_problem(endpoint) is None
    assert endpoint_problem(endpoint, listening=True) is None


def test_port_0_is_a_listening_endpoint_only() -> None:
    assert endpoint_problem("tcp/127.0.0.1:0", listening=True) is None
    assert endpoint_problem("tcp/127.0.0.1:0") is not None


def test_an_unknown_host_is_named_when_no_router_answers(monkeypatch: pytest.MonkeyPatch) -> None:
    def unknown(*args: object, **kwargs: object) -> None:
        raise socket.gaierror(socket.EAI_NONAME, "Name or service not known")

    monkeypatch.setattr(socket, "getaddrinfo", unknown)  # no name service is asked
    assert unreachable_message(["tcp/127.0.0.1:9", "tcp/router.lab:7447"], 5.0) == (
        "host 'router.lab' of --connect tcp/router.lab:7447 is not known: fix --connect"
    )


def test_the_run_refuses_a_listen_port_in_use_or_malformed_and_accepts_a_free_one(
    busy_port: int,
) -> None:
    with pytest.raises(
        ZenohSetupError,
        match=rf"^cannot listen on tcp/127.0.0.1:{busy_port}: "
        "address already in use",
    ):
        check_network([], [f"tcp/127.0.0.1:{busy_port}"])
    with pytest.raises(ZenohSetupError, match=r"^bad --listen endpoint 'garbage'"):
        check_network([], ["garbage"])
    with pytest.raises(ZenohSetupError, match=r"^bad --connect endpoint 'tcp/notanip:x'"):
        check_network(["tcp/notanip:x"], [])
    check_network([], [f"tcp/127.0.0.1:{free_port()}"])
    check_network([], [])  # the launcher picks a free loopback port itself


def _delay(conf: zenoh.Config) -> object:
    return json.loads(conf.get_json("scouting/delay"))


def test_a_router_linked_to_no_other_opens_without_zenohs_scouting_wait(tmp_path: Path) -> None:
    lone = make_config("router", listen=["tcp/127.0.0.1:7447"])
    linked = make_config("router", connect=["tcp/127.0.0.1:7448"], listen=["tcp/127.0.0.1:7447"])
    client = make_config("client", connect=["tcp/127.0.0.1:7447"])
    own = tmp_path / "zenoh.json5"
    own.write_text("{ scouting: { delay: 250 } }")
    assert (_delay(lone), _delay(linked), _delay(client)) == (0, None, None)
    assert _delay(make_config("router", listen=["tcp/127.0.0.1:7447"], config_file=str(own))) == 250


def test_settle_runtime_gives_one_zenoh_worker_unless_the_user_chose(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("ZENOH_RUNTIME", raising=False)
    settle_runtime()
    assert os.environ["ZENOH_RUNTIME"] == ONE_WORKER_RUNTIME
    monkeypatch.setenv("ZENOH_RUNTIME", "(app: (worker_threads: 3))")
    settle_runtime()
    assert os.environ["ZENOH_RUNTIME"] == "(app: (worker_threads: 3))"
