"""Garbage on every key a swarm listens on: nothing crashes, nothing changes, memory stays put."""

from __future__ import annotations

import random
from collections.abc import Callable
from pathlib import Path

import msgpack
import pytest
from netharness import Swarm, assert_same_run, lockstep_record

from fatswarm.deploy.net.zconf import make_config
from fatswarm.domain.wire import PROTOCOL_VERSION
from fatswarm.world.protocol import Hello
from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration
SEED = 11
KINDS = (
    "move",
    "state",
    "round-start",
    "move-held",
    "snapshot",
    "hello",
    "begin",
    "commit",
    "control-reply",
)


def _rss_kb(pid: int) -> int:
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise AssertionError(f"no VmRSS for {pid}")


def _garbage(rng: random.Random) -> bytes:
    """Random bytes, a msgpack map of the right type with wrong fields, or a huge payload."""
    pick = rng.random()
    if pick < 0.01:
        return rng.randbytes(rng.randint(1, 3) << 20)  # megabytes
    if pick < 0.5:
        return rng.randbytes(rng.randint(0, 600))
    junk: object = rng.choice(
        [
            None,
            True,
            -1,
            2**40,
            1e308,
            "x" * rng.randint(0, 900),
            [1] * 50,
            {"a": 1},
            b"\x00" * rng.randint(0, 400),
        ]
    )
    fields = {"v": rng.choice([PROTOCOL_VERSION, 1, "2"]), "t": rng.choice(KINDS)}
    for key in rng.sample(
        [
            "robot",
            "round",
            "path",
            "active",
            "view",
            "n",
            "params",
            "held",
            "status",
            "positions",
            "algorithm",
            "timed_out",
        ],
        4,
    ):
        fields[key] = junk
    out: bytes = msgpack.packb(fields, use_bin_type=True)
    return out


def fuzz(sw: Swarm, count: int, seed: int) -> None:
    """`count` messages of garbage on every key of the swarm, from a client that is no part (and
    shares no memory with the parts, as a client on another host)."""
    import zenoh

    rng = random.Random(seed)
    rogue = zenoh.open(make_config("client", [sw.endpoint], shared_memory=False))
    root = f"fatswarm/{sw.swarm}"
    subscribed = [
        f"{root}/robot/{rng.randint(0, 9)}/move",
        f"{root}/coordinator/round",
        f"{root}/world/moves",
        f"{root}/world/state",
        f"{root}/robot/x/move",
    ]
    queried = [f"{root}/world/control", f"{root}/robot/3/snapshot", f"{root}/robot/77/snapshot"]

    def answered() -> bool:
        replies = rogue.get(f"{root}/world/control", payload=Hello().encode(), timeout=1.0)
        return any(r.ok is not None for r in replies)

    with rogue:
        sw.wait_for("the rogue to reach the world", answered)
        for k in range(count):
            payload = _garbage(rng)
            if k % 20 == 0:
                list(rogue.get(rng.choice(queried), payload=payload, timeout=1.0))
            else:
                rogue.put(rng.choice(subscribed), payload)
        sw.wait_for("the world to have taken all in", answered)  # behind them on the link


def _fuzzed_run(
    tmp_path: Path, make_swarm: Callable[..., Swarm], count: int, in_world: bool = False
) -> None:
    sw = make_swarm(6, SEED)
    sw.start_all(pace=0.05, in_world=in_world, hosted=True, apart=0)  # agent 0 logs alone
    sw.wait_for("round 2", lambda: (s := sw.state()) is not None and s.round >= 2)
    world = sw.children.procs["world"].pid
    # Two floods of `count` each: the world may not grow by 20 % from where it started (with
    # Zenoh's shared memory on, the first large message mapped 20 MB into it for good).
    before = _rss_kb(world)
    fuzz(sw, count, seed=count)
    fuzz(sw, count, seed=count + 1)
    after = _rss_kb(world)
    end = sw.wait_done()
    assert end.status == "formed", sw.logs()
    coordinator = sw.children.procs["coordinator"]
    sw.wait_for("the coordinator to end with the run", lambda: coordinator.poll() is not None)
    ended = {name: p.poll() for name, p in sw.children.procs.items() if p.poll() is not None}
    assert ended == {"coordinator": 0}, ended  # nothing else ends, nor crashes
    assert_same_run(read_record(sw.state_path), lockstep_record(tmp_path / "lock.jsonl", 6, SEED))
    assert after <= before * 1.2, f"the floods grew the world from {before} kB to {after} kB"
    longest = max(
        len(line)
        for name in ("world", "coordinator", "agent 0")
        for line in sw.log(name).splitlines()
    )
    assert longest < 600, f"a log line of {longest} characters"


@pytest.mark.parametrize("in_world", [False, True], ids=["router-apart", "router-in-world"])
def test_two_thousand_garbage_messages_change_nothing_and_crash_nothing(
    tmp_path: Path, make_swarm: Callable[..., Swarm], in_world: bool
) -> None:
    _fuzzed_run(tmp_path, make_swarm, 1_000, in_world)


@pytest.mark.slow
def test_twenty_thousand_garbage_messages_change_nothing_and_crash_nothing(
    tmp_path: Path, make_swarm: Callable[..., Swarm]
) -> None:
    _fuzzed_run(tmp_path, make_swarm, 10_000)
