"""Gathering that takes its time: for tests that must interrupt a sweep mid-way.

With FATSWARM_TEST_SLOW=SECONDS in the environment, building its parameters in a child process
(a sweep's worker: about once per run) sleeps that long; with FATSWARM_TEST_DIE=1 the child kills
itself there instead (a worker lost to the OOM killer, say). Otherwise it is plain gathering.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
from collections.abc import Mapping

from fatswarm.agent.gathering import Gathering, GatheringParams
from fatswarm.domain.seam import ParamValue


class SlowGathering(Gathering):
    """`gathering`, slowed down by FATSWARM_TEST_SLOW seconds per run."""

    name = "slow-gathering"

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> GatheringParams:
        if multiprocessing.parent_process() is not None:
            if os.environ.get("FATSWARM_TEST_DIE"):
                os.kill(os.getpid(), signal.SIGKILL)
            time.sleep(float(os.environ.get("FATSWARM_TEST_SLOW", "0")))
        return super().make_params(n, values)


ALGORITHM = SlowGathering()
