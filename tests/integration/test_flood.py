"""A flood of rogue messages costs the world a few log lines, not one each; the counts reach the
end of `fatswarm run`; the world's memory stays put (100,000 messages, slow)."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from floods import REASONS, burst, flood, rss_kb, wait_answered
from netharness import Swarm

from fatswarm.deploy.net.zconf import free_port, make_config
from fatswarm.domain.wire import ProtocolError
from fatswarm.world.observers import WorldState
from fatswarm.world.protocol import state_key
from fatswarm.world.rejections import SAY_EVERY_S

pytestmark = pytest.mark.integration

ALWAYS_RIGHT = Path(__file__).resolve().parents[1] / "data" / "always_right.py"
DEADLINE_S = 120.0


def _refused_total(latest: list[WorldState]) -> int:
    return sum(latest[-1].refused.values()) if latest else 0


def test_five_thousand_rogue_messages_cost_a_few_log_lines_and_are_counted_at_the_end(
    tmp_path: Path,
) -> None:
    endpoint, swarm, count = f"tcp/127.0.0.1:{free_port()}", "flooded", 5_000
    # a run that goes on until stopped (its robots never stay), paced: the flood meets it running
    argv = [sys.executable, "-m", "fatswarm.deploy.cli", "run", "-n", "4", "--seed", "1"]
    argv += ["--algorithm", f"{ALWAYS_RIGHT}:ALGORITHM", "--param", "step=0.0001"]
    argv += ["--start", "spread", "--max-rounds", "100000", "--pace", "0.2", "--no-dashboard"]
    argv += ["--listen", endpoint, "--swarm", swarm, "--record", str(tmp_path / "r.jsonl")]
    launcher = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    try:
        import zenoh

        rogue = None
        end = time.monotonic() + DEADLINE_S
        while rogue is None:  # the world hosts the router: up once the world is
            try:
                rogue = zenoh.open(make_config("client", [endpoint], shared_memory=False))
            except zenoh.ZError:
                assert time.monotonic() < end and launcher.poll() is None, "no router came up"
                time.sleep(0.1)
        latest: list[WorldState] = []

        def keep(sample: zenoh.Sample) -> None:
            try:
                latest.append(WorldState.decode(sample.payload.to_bytes()))
            except ProtocolError:
                return

        with rogue:
            rogue.declare_subscriber(state_key(swarm), keep)
            wait_answered(rogue, swarm)
            began = time.monotonic()
            flood(rogue, swarm, 4, count)
            took = time.monotonic() - began
            while _refused_total(latest) < count * 0.9:  # what the launcher's display sees too
                assert time.monotonic() < end, f"the state counts {_refused_total(latest)}"
                time.sleep(0.05)
        launcher.send_signal(signal.SIGINT)
        _out, err = launcher.communicate(timeout=DEADLINE_S)
    finally:
        if launcher.poll() is None:
            launcher.kill()
            launcher.wait()
    assert launcher.returncode == 130, err
    said = [line for line in err.splitlines() if line.startswith("fatswarm world: rejected (")]
    for reason in REASONS:
        assert any(f"rejected ({reason})" in line for line in said), (reason, err[-3000:])
    # each kind at once, then at most once every SAY_EVERY_S with its count, and once at the end
    bound = len(REASONS) * (3 + took / SAY_EVERY_S)
    assert len(said) <= bound, f"{len(said)} lines for {count} messages (bound {bound:.0f})"
    assert any(re.search(r"\[[\d,]+ since it was last said, [\d,]+ in all\]", s) for s in said)
    last = err.rstrip("\n").splitlines()[-1]  # below the line of how to go on
    match = re.fullmatch(r"refused: ([\d,]+) messages \((.*)\)", last)
    assert match is not None, err[-2000:]
    assert count * 0.9 <= int(match[1].replace(",", "")) <= count, last
    assert all(reason in match[2] for reason in REASONS), last
    assert "interrupted after round" in err


@pytest.mark.slow
def test_a_hundred_thousand_rogue_messages_leave_the_worlds_memory_within_a_fifth(
    tmp_path: Path, make_swarm: Callable[..., Swarm]
) -> None:
    import zenoh

    sw = make_swarm(4, 1)
    sw.start_all(pace=0.2)
    sw.wait_for("round 2", lambda: (s := sw.state()) is not None and s.round >= 2)
    world = sw.children.procs["world"].pid
    with zenoh.open(make_config("client", [sw.endpoint], shared_memory=False)) as rogue:
        wait_answered(rogue, sw.swarm)
        before = rss_kb(world)
        for _ in range(5):
            flood(rogue, sw.swarm, 4, 10_000)
            burst(rogue, sw.swarm, 3, 10_000)
    # it gives back what the flood took once it is over (and says what it refused): in seconds
    end = time.monotonic() + DEADLINE_S
    while (after := rss_kb(world)) > before * 1.2 and time.monotonic() < end:
        time.sleep(0.2)
    assert sw.children.procs["world"].poll() is None, sw.logs()
    assert after <= before * 1.2, f"100,000 messages grew the world from {before} to {after} kB"
    said = [line for line in sw.log("world").splitlines() if "rejected (" in line]
    assert len(said) < 1_000, f"{len(said)} log lines for 100,000 messages"


def test_two_agents_acting_for_one_robot_are_said_once(
    tmp_path: Path, make_swarm: Callable[..., Swarm]
) -> None:
    sw = make_swarm(4, 1)
    sw.start_all(pace=0.1, hosted=True)
    sw.start_agent(3, "agent 3 twin")  # the same key twice: the documented "key = identity" limit
    end = sw.wait_done()
    assert end.status == "formed", sw.logs()
    said = [line for line in sw.log("world").splitlines() if "look-two-sessions" in line]
    assert len(said) == 1 and "robot 3's Looks come from two sessions" in said[0], sw.log("world")
