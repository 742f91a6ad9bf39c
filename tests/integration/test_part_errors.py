"""The parts alone, when the network is not as given: one line and exit 2, or a periodic notice."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from netharness import assert_one_line, descendants_of, part, run_all, running

from fatswarm.deploy.net.children import Children
from fatswarm.deploy.net.zconf import (
    CONNECT_DEADLINE_S,
    ZenohSetupError,
    check_network,
    free_port,
    loopback_endpoint,
)

pytestmark = pytest.mark.integration

DEADLINE_S = 60.0  # generous: the machine is shared; waits are on predicates


def test_the_help_of_world_and_coordinator_says_how_long_they_wait_for_a_router() -> None:
    for name in ("world", "coordinator"):
        done = subprocess.run(
            part(name, "--help"), capture_output=True, text=True, timeout=DEADLINE_S, check=False
        )
        assert re.search(rf"within\s+{CONNECT_DEADLINE_S:g}\s+s", done.stdout), done.stdout


@pytest.mark.parametrize(
    ("name", "flags", "said"),
    [
        (
            "world",
            ["--connect", "garbage", "--state", "unused.jsonl"],
            "bad --connect endpoint 'garbage': write <protocol>/<address>",
        ),
        (
            "world",
            ["--connect", "tcp/notanip:x", "--state", "unused.jsonl"],
            "bad --connect endpoint 'tcp/notanip:x': the port must be a whole number",
        ),
        ("coordinator", ["--connect", "garbage"], "bad --connect endpoint 'garbage'"),
        ("coordinator", ["--connect", "tcp/notanip:x"], "bad --connect endpoint 'tcp/notanip:x'"),
        ("router", ["--listen", "garbage"], "bad --listen endpoint 'garbage'"),
        ("router", ["--listen", "tcp/notanip:x"], "bad --listen endpoint 'tcp/notanip:x'"),
        ("agent", ["--robot", "0", "--connect", "garbage"], "bad --connect endpoint 'garbage'"),
        ("agents", ["-n", "2", "--connect", "tcp/notanip:x"], "bad --connect endpoint"),
    ],
)
def test_a_malformed_endpoint_exits_2_in_one_line(
    tmp_path: Path, name: str, flags: list[str], said: str
) -> None:
    (done,) = run_all(
        part(name, *[str(tmp_path / f) if f.endswith(".jsonl") else f for f in flags])
    )
    assert_one_line(done, f"fatswarm {name}: {said}")
    assert not (tmp_path / "unused.jsonl").exists()


def test_a_router_on_a_port_in_use_exits_2_in_one_line(busy_port: int) -> None:
    (done,) = run_all(part("router", "--listen", f"tcp/127.0.0.1:{busy_port}"))
    assert_one_line(
        done, f"fatswarm router: cannot listen on tcp/127.0.0.1:{busy_port}: address already in use"
    )


def test_a_world_hosting_the_router_on_a_port_in_use_exits_2_in_one_line(
    tmp_path: Path, busy_port: int
) -> None:
    state = tmp_path / "state.jsonl"
    (done,) = run_all(
        part(
            "world",
            "--router",
            "--listen",
            f"tcp/127.0.0.1:{busy_port}",
            "--state",
            str(state),
            "-n",
            "4",
        )
    )
    assert_one_line(
        done, f"fatswarm world: cannot listen on tcp/127.0.0.1:{busy_port}: address already in use"
    )
    assert not state.exists()  # no run record for a world that never served


def test_a_world_hosting_the_router_refuses_a_config_file_in_one_line(tmp_path: Path) -> None:
    config = tmp_path / "world.json5"
    config.write_text("{}\n")
    (done,) = run_all(
        part(
            "world", "--router", "--config", str(config), "--state", str(tmp_path / "unused.jsonl")
        )
    )
    assert_one_line(done, "fatswarm world: --router hosts a router without access control")
    assert not (tmp_path / "unused.jsonl").exists()


def _wait_for(what: str, predicate: Callable[[], bool], logs: Callable[[], str]) -> None:
    end = time.monotonic() + DEADLINE_S
    while not predicate():
        if time.monotonic() > end:
            pytest.fail(f"timed out waiting for {what}\n{logs()}")
        time.sleep(0.05)


GivingUp = tuple[
    str, list[subprocess.Popen[str]], threading.Thread, list[tuple[float, BaseException | None]]
]


def _start_on_dead_routers(tmp_path: Path) -> GivingUp:
    """A world and a coordinator started on a dead router, and `fatswarm run --connect`'s check
    of another one in a thread of this process: each waits CONNECT_DEADLINE_S, side by side."""
    dead, dead_for_the_run = (f"tcp/127.0.0.1:{free_port()}" for _ in range(2))
    the_run: list[tuple[float, BaseException | None]] = []

    def check_the_run() -> None:
        started = time.monotonic()
        try:
            check_network([dead_for_the_run], [])
        except ZenohSetupError as exc:
            the_run.append((time.monotonic() - started, exc))
        else:
            the_run.append((time.monotonic() - started, None))

    thread = threading.Thread(target=check_the_run, daemon=True, name=dead_for_the_run)
    thread.start()
    state = tmp_path / "state.jsonl"
    procs = [
        subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
        )
        for argv in (
            part("world", "--connect", dead, "--state", str(state), "-n", "4"),
            part("coordinator", "--connect", dead),
        )
    ]
    return dead, procs, thread, the_run


def _gave_up(tmp_path: Path, giving_up: GivingUp) -> None:
    """World, coordinator and the run gave up on their dead routers, each in one line."""
    dead, procs, thread, the_run = giving_up
    try:
        done = []
        for proc in procs:
            out, err = proc.communicate(timeout=DEADLINE_S)
            done.append(subprocess.CompletedProcess(proc.args, proc.returncode, out, err))
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    thread.join(DEADLINE_S)
    world, coordinator = done
    said = f"no Zenoh router answers at {dead} (tried for {CONNECT_DEADLINE_S:g} s)"
    assert_one_line(world, f"fatswarm world: {said}")
    assert_one_line(coordinator, f"fatswarm coordinator: {said}")
    assert not (tmp_path / "state.jsonl").exists()  # no run record for a world that never served
    # the run (`fatswarm run --connect`): it waited for a late router, then one line
    ((waited, exc),) = the_run
    assert isinstance(exc, ZenohSetupError), exc
    assert re.match(r"^no Zenoh router answers at ", str(exc)), exc
    assert waited >= CONNECT_DEADLINE_S  # it did wait for a late router
    assert thread.name in str(exc) and "\n" not in str(exc)


def test_world_coordinator_and_the_run_give_up_on_a_dead_router_while_agent_hosts_say_they_wait(
    tmp_path: Path,
) -> None:
    # Two waits side by side, one in the suite's time: world, coordinator and the run (each for
    # a dead router of its own) give up after CONNECT_DEADLINE_S, in one line each, while every
    # agent host says, after WAIT_NOTICE_S, that its robots wait for a router and where, then
    # connects once one is up. Each host's first notice, over a real Zenoh; that the notice
    # comes again every WAIT_NOTICE_S, how long so far, is pinned on a clock of its own (a second
    # notice here would cost another WAIT_NOTICE_S of waiting): test_agent_router_wait.py.
    giving_up = _start_on_dead_routers(tmp_path)
    try:
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        net = ["--connect", endpoint, "--swarm", "waiting"]
        hosts = {  # name -> (argv, who the notice names)
            "agent": (part("agent", *net, "--robot", "7"), "robot 7"),
            "agents": (part("agents", *net, "-n", "3", "--first", "0"), "robots 0..2"),
            "agents-exec": (
                part("agents", *net, "-n", "2", "--first", "3", "--spawn", "exec"),
                "robots 3..4",
            ),
        }

        def log(name: str) -> str:
            path = tmp_path / f"{name}.log"
            return path.read_text(errors="replace") if path.exists() else ""

        def logs() -> str:
            return "\n".join(f"--- {name}\n{log(name)}" for name in hosts)

        with Children() as children:
            for name, (argv, _) in hosts.items():
                with open(tmp_path / f"{name}.log", "wb") as out:
                    children.start(name, argv, stdout=out, stderr=out)
            for name, (_, who) in hosts.items():
                notice = f"{who}: still waiting for a Zenoh router at {endpoint} ("

                def noticed(notice: str = notice, name: str = name) -> bool:
                    return notice in log(name)

                _wait_for(f"{name}'s notice", noticed, logs)
            assert not children.exited(), logs()  # waiting, by design: not giving up
            with open(tmp_path / "router.log", "wb") as out:
                children.start(
                    "router", part("router", "--listen", endpoint), stdout=out, stderr=out
                )
            for name, (_, who) in hosts.items():
                answered = f"{who}: the router at {endpoint} answered after"

                def connected(answered: str = answered, name: str = name) -> bool:
                    return answered in log(name)

                _wait_for(f"{name} to connect", connected, logs)
        for name, (_, who) in hosts.items():
            lines = log(name).splitlines()
            # one speaks per host
            assert all(f"] WARNING {who}: " in line for line in lines), logs()
            waiting = [line for line in lines if "still waiting" in line]
            assert waiting and all(re.search(r"\(\d+ s so far\)", w) for w in waiting)
        _gave_up(tmp_path, giving_up)
    finally:  # nothing left running, whatever failed
        for proc in giving_up[1]:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


@pytest.mark.parametrize("spawn", ["fork", "exec"])
def test_a_killed_agents_host_leaves_no_agent_behind(spawn: str) -> None:
    argv = [
        sys.executable,
        "-m",
        "fatswarm.deploy.net.parts",
        "agents",
        "-n",
        "3",
        "--spawn",
        spawn,
        "--connect",
        loopback_endpoint(),
        "--seed",
        "1",
    ]  # no router: they wait for one
    host = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    agents: list[int] = []
    try:
        deadline = time.monotonic() + 60
        while len(agents) < 3 and time.monotonic() < deadline:
            agents = [p for p in descendants_of(host.pid) if running(p)]
            time.sleep(0.1)
        assert len(agents) == 3, agents
        host.kill()  # SIGKILL: no chance to stop its agents itself
        host.wait()
        deadline = time.monotonic() + 30
        while any(running(p) for p in agents) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not [p for p in agents if running(p)]
    finally:
        for pid in [host.pid, *agents]:
            if running(pid):
                os.kill(pid, signal.SIGKILL)
