"""Flood a running swarm's world with rogue messages it must refuse and print what it cost: the
world's memory before and after each batch, the lines its log grew by, and how long it took.

    python bench/bench_flood.py                       # 100,000 messages in batches of 20,000
    python bench/bench_flood.py --count 20000 --batch 5000

The messages are tests/integration/floods.py's, half `flood` (every rejection the world names)
and half `burst` (Looks on one robot's key, fired without waiting), from a client that is no part
of the swarm, without access control so that they reach the world.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "integration"))

from floods import burst, flood, rss_kb, wait_answered
from netharness import Swarm

from fatswarm.deploy.net.zconf import make_config
from fatswarm.world.rejections import SAY_EVERY_S


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--count", type=int, default=100_000, help="rogue messages in all")
    p.add_argument("--batch", type=int, default=20_000, help="messages between two measures")
    p.add_argument("-n", type=int, default=4, help="robots of the swarm flooded")
    args = p.parse_args()
    import zenoh

    with tempfile.TemporaryDirectory() as tmp:
        sw = Swarm(Path(tmp), args.n, 1)
        try:
            sw.start_all(pace=0.2)
            sw.wait_for("round 2", lambda: (s := sw.state()) is not None and s.round >= 2)
            world = sw.children.procs["world"].pid
            rogue = zenoh.open(make_config("client", [sw.endpoint], shared_memory=False))
            with rogue:
                wait_answered(rogue, sw.swarm)
                before = rss_kb(world)
                lines0 = sw.log("world").count("\n")
                print(f"{'sent':>8} {'world kB':>9} {'growth':>7} {'log lines':>9} {'s':>6}")
                print(f"{0:>8} {before:>9} {0:>6.1f}% {0:>9} {0:>6.1f}", flush=True)
                sent, t0 = 0, time.monotonic()
                while sent < args.count:
                    batch = min(args.batch, args.count - sent)
                    flood(rogue, sw.swarm, args.n, batch // 2)
                    burst(rogue, sw.swarm, args.n - 1, batch - batch // 2)
                    sent += batch
                    now = rss_kb(world)
                    lines = sw.log("world").count("\n") - lines0
                    print(
                        f"{sent:>8} {now:>9} {100 * (now / before - 1):>6.1f}% {lines:>9} "
                        f"{time.monotonic() - t0:>6.1f}",
                        flush=True,
                    )
                time.sleep(2 * SAY_EVERY_S)  # the world gives back what a flood took, then
                now = rss_kb(world)
                print(f"after {2 * SAY_EVERY_S:g} s: {now} kB ({100 * (now / before - 1):.1f}%)")
            print(f"world alive: {sw.children.procs['world'].poll() is None}")
            tail = sw.log("world").splitlines()[-8:]
            print("last log lines:", *tail, sep="\n  ")
        finally:
            sw.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
