"""One world and one coordinator per swarm: a second is refused at start, another swarm is not."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from netharness import Swarm, assert_one_line, assert_same_run, lockstep_record, part, run_all

from fatswarm.coordinator.protocol import alive_key as coordinator_alive_key
from fatswarm.world.protocol import alive_key as world_alive_key
from fatswarm.world.record_read import read_record

pytestmark = pytest.mark.integration

SEED = 3  # forms under ssync for n = 4 (as the lockstep run says)
OTHER_SEED = 7  # another start that forms: a swarm mixed with the first would not match its own


def _refusal(part_name: str, swarm: str) -> str:
    return (
        f"fatswarm {part_name}: swarm '{swarm}' already has a {part_name} on this router "
        "network; stop it or pick another --swarm"
    )


def test_a_second_world_coordinator_or_fatswarm_run_on_a_swarm_is_refused_in_one_line(
    tmp_path: Path, make_swarm: Callable[..., Swarm]
) -> None:
    # One swarm in use for the four refusals, side by side: a second world (a new run, and the
    # same command twice), a second coordinator, and `fatswarm run` on that swarm
    sw = make_swarm(4, SEED)
    sw.start_router()
    sw.observe()
    sw.start_world()
    sw.start_coordinator(pace=0.0)  # no agents yet: it waits for them, so both stay up
    sw.wait_for(
        "the world's and the coordinator's tokens",
        lambda: sw.live(world_alive_key(sw.swarm)) and sw.live(coordinator_alive_key(sw.swarm)),
    )
    state_before = sw.state_path.read_bytes()
    other_state = tmp_path / "second.jsonl"
    record = tmp_path / "run.jsonl"
    world_new, world_same, coordinator, run = run_all(
        part("world", *sw.world_flags(other_state)),  # a new run on the same swarm
        part("world", *sw.world_flags()),  # the same command twice (the same state file)
        part("coordinator", *sw.coordinator_flags(0.0)),
        [
            sys.executable, "-m", "fatswarm.deploy.cli", "run", "--connect", sw.endpoint,
            "--swarm", sw.swarm, "--no-dashboard", "-n", "4", "--record", str(record),
        ],
    )  # fmt: skip
    assert_one_line(world_new, _refusal("world", sw.swarm))
    assert_one_line(world_same, _refusal("world", sw.swarm))
    assert_one_line(coordinator, _refusal("coordinator", sw.swarm))
    # `fatswarm run` before anything: no seed line, no progress line of the other run, no
    # refusal of each part: this one line
    assert_one_line(run, _refusal("world", sw.swarm).replace("world", "run", 1))
    assert run.stdout == ""
    assert not record.exists()
    assert not other_state.exists()  # nothing visible: no state file created...
    assert sw.state_path.read_bytes() == state_before  # ...nor touched
    assert not sw.children.exited(), sw.logs()  # the first world and coordinator serve on
    sw.start_agents()
    end = sw.wait_done()  # and run as if nothing had happened
    assert end.status == "formed" and end.collisions_total == 0, sw.logs()
    assert_same_run(
        read_record(sw.state_path), lockstep_record(tmp_path / "lock.jsonl", sw.n, SEED)
    )


def test_a_second_swarm_on_the_same_router_runs_alongside_unmixed(
    tmp_path: Path, make_swarm: Callable[..., Swarm]
) -> None:
    first = make_swarm(4, SEED)
    first.start_all(pace=0.05, hosted=True)
    first.wait_for(
        "the first swarm's round 1", lambda: (s := first.state()) is not None and s.round >= 1
    )
    second = make_swarm(4, OTHER_SEED, endpoint=first.endpoint)
    second.start_all(pace=0.05, router=False, hosted=True)
    for sw, seed in ((first, SEED), (second, OTHER_SEED)):
        end = sw.wait_done()
        assert end.status == "formed" and end.collisions_total == 0, sw.logs()
        assert_same_run(
            read_record(sw.state_path), lockstep_record(tmp_path / f"lock-{seed}.jsonl", sw.n, seed)
        )
    assert "already has" not in first.logs() + second.logs()
