"""A secured swarm on three hosts: three network namespaces on one bridge (made and removed by the
test, no traffic outside them), one router per host from `fatswarm secure` (mutual TLS, access
control with default deny), the world and coordinator on host A, agents on hosts B and C.

Run 1: rogue clients on B and C (a robot's and a dashboard's identity) try every refused thing
while the swarm forms, and one robot's agent starts only after they tried to stand in for it
with a fake token: the record equals the unattacked lock-step run, and nothing came back to them.
Run 2: host C's link goes down for a few seconds mid-run and comes back: the run forms.
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import pytest
from netharness import assert_same_run, lockstep_record, part

from fatswarm.deploy.net.children import Children
from fatswarm.deploy.secure.plan import Plan
from fatswarm.world.record import RecordFormatError, RunRecord
from fatswarm.world.record_read import read_record

pytestmark = [pytest.mark.integration, pytest.mark.slow]

N, SEED = 6, 3
ON_B, ON_C = (0, 1, 2), (3, 4)  # agents started at once; robot LATE (on C) after the rogues
LATE = 5
SUBNET = "10.77.{}.{}"  # only inside the namespaces
DEADLINE_S = 120.0
PARTITION_S = 4.0  # host C's link down: less than Zenoh's 10 s lease between routers
ROGUES_TRIED_S = 2.0  # how long the coordinator is given to wrongly start round 1 without LATE
ROGUE_SRC = Path(__file__).with_name("rogues.py")


def _ip(*argv: str) -> None:
    subprocess.run(["ip", *argv], check=True, capture_output=True, timeout=30)


class Hosts:
    """Network namespaces `<tag>-a|b|c` on a bridge in `<tag>-sw`, addresses 10.77.x.1-3."""

    def __init__(self, names: Sequence[str]) -> None:
        self.tag = f"fs{secrets.token_hex(3)}"
        self.net = secrets.randbelow(200) + 20
        self.names = list(names)
        self.addr = {h: SUBNET.format(self.net, i + 1) for i, h in enumerate(self.names)}
        self.made: list[str] = []

    def ns(self, host: str) -> str:
        return f"{self.tag}-{host}"

    def up(self) -> None:
        switch = self.ns("sw")
        _ip("netns", "add", switch)
        self.made.append(switch)
        _ip("-n", switch, "link", "add", "br0", "type", "bridge")
        _ip("-n", switch, "link", "set", "br0", "up")
        for h in self.names:
            ns = self.ns(h)
            _ip("netns", "add", ns)
            self.made.append(ns)
            _ip(
                "link",
                "add",
                "eth0",
                "netns",
                ns,
                "type",
                "veth",
                "peer",
                "name",
                f"p-{h}",
                "netns",
                switch,
            )
            _ip("-n", ns, "addr", "add", f"{self.addr[h]}/24", "dev", "eth0")
            _ip("-n", ns, "link", "set", "eth0", "up")
            _ip("-n", ns, "link", "set", "lo", "up")
            _ip("-n", switch, "link", "set", f"p-{h}", "master", "br0")
            _ip("-n", switch, "link", "set", f"p-{h}", "up")

    def link(self, host: str, state: str) -> None:
        _ip("-n", self.ns(host), "link", "set", "eth0", state)

    def argv(self, host: str, argv: Sequence[str]) -> list[str]:
        return ["ip", "netns", "exec", self.ns(host), *argv]

    def down(self) -> None:
        """Kill what is left in the namespaces (only processes this test started can be there),
        then remove them (their veth pairs go with them)."""
        for ns in reversed(self.made):
            pids = subprocess.run(
                ["ip", "netns", "pids", ns], capture_output=True, text=True, timeout=30, check=False
            ).stdout.split()
            for pid in pids:
                try:
                    os.kill(int(pid), 9)
                except (ProcessLookupError, ValueError):
                    continue
            subprocess.run(["ip", "netns", "del", ns], capture_output=True, timeout=30, check=False)


@contextmanager
def three_hosts() -> Iterator[Hosts]:
    if os.geteuid() != 0 or shutil.which("ip") is None:
        pytest.skip("needs root and iproute2 (ip netns)")
    hosts = Hosts(["a", "b", "c"])
    try:
        try:
            hosts.up()
        except subprocess.CalledProcessError as exc:
            pytest.skip(f"cannot make network namespaces: {exc.stderr!r}")
        yield hosts
    finally:
        hosts.down()


class Parts:
    """The swarm's processes, each in its host's namespace, logs in `tmp`."""

    def __init__(
        self, tmp: Path, hosts: Hosts, plan: Plan, folder: Path, children: Children
    ) -> None:
        self.tmp, self.hosts, self.plan, self.folder = tmp, hosts, plan, folder
        self.children = children

    def start(self, name: str, host: str, argv: list[str]) -> None:
        log = open(self.tmp / f"{name}.log", "ab")  # noqa: SIM115
        self.children.start(name, self.hosts.argv(host, argv), stdout=log, stderr=log)
        log.close()

    def fatswarm(self, name: str, host: str, role: str, identity: str, *flags: str) -> None:
        config = str(self.folder / f"{identity}.json5")
        self.start(name, host, part(role, "--config", config, *flags))

    def client(self, name: str, host: str, role: str, identity: str, *flags: str) -> None:
        self.fatswarm(
            name,
            host,
            role,
            identity,
            "--connect",
            self.plan.local_endpoint,
            "--swarm",
            self.plan.swarm,
            *flags,
        )

    def rogue(self, name: str, host: str, identity: str) -> Path:
        report = self.tmp / f"{name}.json"
        self.start(
            name,
            host,
            [
                sys.executable,
                str(ROGUE_SRC),
                "--config",
                str(self.folder / f"{identity}.json5"),
                "--connect",
                self.plan.local_endpoint,
                "--swarm",
                self.plan.swarm,
                "-n",
                str(N),
                "--victim",
                str(LATE),
                "--report",
                str(report),
            ],
        )
        return report

    def log(self, name: str) -> str:
        path = self.tmp / f"{name}.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def logs(self) -> str:
        return "\n".join(
            f"--- {p.name}\n{p.read_text(errors='replace')[-3000:]}"
            for p in sorted(self.tmp.glob("*.log"))
            if p.stat().st_size
        )

    def wait_for(self, what: str, predicate: Callable[[], bool]) -> None:
        end = time.monotonic() + DEADLINE_S
        while not predicate():
            dead = {k: v for k, v in self.children.exited().items() if v != 0}
            if time.monotonic() > end or dead:
                pytest.fail(f"waiting for {what}: {dead or 'timed out'}\n{self.logs()}")
            time.sleep(0.05)


def record(path: Path) -> RunRecord | None:
    try:
        return read_record(path, allow_torn_end=True) if path.exists() else None
    except (RecordFormatError, StopIteration):
        return None


def rounds(path: Path) -> int:
    rec = record(path)
    return len(rec.rounds) if rec is not None else 0


def ended(path: Path) -> bool:
    rec = record(path)
    return rec is not None and rec.result is not None


def test_a_secured_swarm_on_three_hosts_forms_refuses_rogues_and_survives_a_partition(
    tmp_path: Path,
) -> None:
    from fatswarm.deploy.secure.pki import write_bundle

    with three_hosts() as hosts, Children() as children:
        a, b, c = (hosts.addr[h] for h in "abc")
        plan = Plan(f"ns-{secrets.token_hex(2)}", N, (a, b, c), 7447, 1)
        folder = tmp_path / "secure"
        write_bundle(plan, folder)
        parts = Parts(tmp_path, hosts, plan, folder, children)
        for h in "abc":
            parts.fatswarm(
                f"router-{h}", h, "router", f"router-{hosts.addr[h]}", "--log-level", "info"
            )
        for h in "abc":

            def listening(h: str = h) -> bool:
                return "listening" in parts.log(f"router-{h}")

            parts.wait_for(f"router {h}", listening)

        # --- run 1: rogues on B and C while the swarm forms --------------------------------
        first = tmp_path / "run1.jsonl"
        run = ("--seed", str(SEED), "--log-level", "info")
        parts.client(
            "world",
            "a",
            "world",
            "world",
            "--state",
            str(first),
            "-n",
            str(N),
            "--scheduler",
            "ssync",
            *run,
        )
        parts.client("coordinator", "a", "coordinator", "coordinator", "--scheduler", "ssync", *run)
        dashboard = [
            sys.executable,
            "-m",
            "fatswarm.deploy.cli",
            "dashboard",
            "--config",
            str(folder / "dashboard-0.json5"),
            "--connect",
            plan.local_endpoint,
            "--swarm",
            plan.swarm,
            "--no-dashboard",
            "--exit-at-end",
            "--every",
            "1",
        ]
        parts.start("dashboard", "c", dashboard)  # reads the state through two routers
        reports = [
            parts.rogue("rogue-robot", "b", "agent-1"),
            parts.rogue("rogue-dashboard", "c", "dashboard-0"),
        ]
        for name in ("rogue-robot", "rogue-dashboard"):

            def armed(name: str = name) -> bool:
                return "armed" in parts.log(name)

            parts.wait_for(f"{name} armed", armed)
        for host, robots in (("b", ON_B), ("c", ON_C)):  # each agent its own identity
            parts.client(
                f"agents-{host}",
                host,
                "agents",
                "agent-{robot}",
                "-n",
                str(len(robots)),
                "--first",
                str(robots[0]),
                *run,
            )
        up = [f"robot {r} up" for r in (*ON_B, *ON_C)]
        parts.wait_for(
            "the first agents",
            lambda: all(line in parts.log("agents-b") + parts.log("agents-c") for line in up),
        )
        time.sleep(ROGUES_TRIED_S)  # a fake token for robot LATE would start round 1 by now
        assert rounds(first) == 0, "round 1 started without robot 5's agent: a fake token won"
        parts.client("late-agent", "c", "agent", f"agent-{LATE}", "--robot", str(LATE), *run)
        parts.wait_for("run 1 to end", lambda: ended(first))
        assert children.procs["coordinator"].wait(timeout=DEADLINE_S) == 0, parts.logs()
        net = read_record(first)
        assert net.result is not None and net.result.status == "formed"
        assert_same_run(net, lockstep_record(tmp_path / "lockstep.jsonl", N, SEED))
        assert children.procs["dashboard"].wait(timeout=DEADLINE_S) == 0, parts.log("dashboard")
        assert f"round {len(net.rounds)}" in parts.log("dashboard"), parts.log("dashboard")
        for name in ("rogue-robot", "rogue-dashboard"):
            children.stop(name)
            assert children.procs[name].wait(timeout=DEADLINE_S) == 0, parts.log(name)
        for report, allowed in zip(reports, (set(), {"state_samples"}), strict=True):
            seen = json.loads(report.read_text())
            print(report.stem, seen)
            assert seen.pop("tries") > 0, seen
            kept = {k: v for k, v in seen.items() if k not in allowed}
            assert kept == dict.fromkeys(kept, 0), (report.stem, seen)

        # --- run 2: host C partitioned mid-run, then healed --------------------------------
        children.stop("world")
        assert children.procs["world"].wait(timeout=DEADLINE_S) == 0, parts.log("world")
        second = tmp_path / "run2.jsonl"
        parts.client(
            "world2",
            "a",
            "world",
            "world",
            "--state",
            str(second),
            "-n",
            str(N),
            "--scheduler",
            "ssync",
            *run,
        )
        parts.client(
            "coordinator2",
            "a",
            "coordinator",
            "coordinator",
            "--scheduler",
            "ssync",
            "--pace",
            "0.2",
            "--move-timeout",
            "1.5",
            *run,
        )
        parts.wait_for("run 2, round 2", lambda: rounds(second) >= 2)
        hosts.link("c", "down")
        try:
            down_at = rounds(second)
            time.sleep(PARTITION_S)
        finally:
            hosts.link("c", "up")
        healed_at = rounds(second)
        parts.wait_for("run 2 to end", lambda: ended(second))
        assert children.procs["coordinator2"].wait(timeout=DEADLINE_S) == 0, parts.logs()
        healed = read_record(second)
        on_c = {*ON_C, LATE}
        assert healed.result is not None and healed.result.status == "formed", parts.logs()
        assert not any(r.collisions for r in healed.rounds)
        assert healed.result.rounds > healed_at >= down_at, (down_at, healed_at)
        cut = [r.round for r in healed.rounds if set(r.extra.get("timed_out", ())) & on_c]
        assert cut, "no robot on host C timed out: the partition changed nothing"
        assert any(r.round > cut[-1] and set(r.active) & on_c for r in healed.rounds), (
            "no robot on host C took part again after the partition healed"
        )
        print(
            f"run 1: {len(net.rounds)} rounds; run 2: partitioned at round {down_at}, healed at "
            f"{healed_at}, formed at {healed.result.rounds}"
        )
