"""Zenoh sessions that cannot open: what zenoh.open really raises reads as one line, and a client
gives up after its deadline (or when stopped) naming the endpoint and the fix."""

from __future__ import annotations

import threading

import pytest
import zenoh

from fatswarm.deploy.net.zconf import (
    ZenohSetupError,
    explain_zenoh_error,
    free_port,
    make_config,
    open_client,
)

pytestmark = pytest.mark.integration


def _raised_by(action: object) -> zenoh.ZError:
    with pytest.raises(zenoh.ZError) as info:
        action()  # type: ignore[operator]
    return info.value


def test_what_zenoh_really_raises_reads_as_one_line_without_paths(busy_port: int) -> None:
    dead = f"tcp/127.0.0.1:{free_port()}"
    router = zenoh.Config()
    router.insert_json5("mode", '"router"')
    router.insert_json5("scouting/multicast/enabled", "false")
    router.insert_json5("listen/endpoints", f'["tcp/127.0.0.1:{busy_port}"]')
    raised = [
        _raised_by(lambda: zenoh.open(make_config("client", [dead]))),
        _raised_by(lambda: zenoh.Config().insert_json5("connect/endpoints", '["garbage"]')),
        _raised_by(lambda: zenoh.open(router)),
    ]
    shown = [explain_zenoh_error(exc) for exc in raised]
    assert shown[0] == f"no Zenoh router answers at {dead}"
    assert shown[1].startswith("'garbage' is not an endpoint")
    assert shown[2].startswith(f"cannot listen on tcp/127.0.0.1:{busy_port}: address already")
    for text in shown:
        assert ".rs" not in text and "/root" not in text and "\n" not in text, text


def test_a_client_gives_up_after_its_deadline_naming_the_endpoint_and_the_fix() -> None:
    dead = f"tcp/127.0.0.1:{free_port()}"
    with pytest.raises(ZenohSetupError) as info:
        open_client(make_config("client", [dead]), deadline_s=0.3)
    assert str(info.value) == (
        f"no Zenoh router answers at {dead} (tried for 0.3 s): start one there "
        f"(fatswarm router --listen {dead}) or fix --connect"
    )


def test_a_client_stopped_while_it_waits_returns_none() -> None:
    stop = threading.Event()
    stop.set()
    conf = make_config("client", [f"tcp/127.0.0.1:{free_port()}"])
    assert open_client(conf, stop, deadline_s=60.0) is None
