"""What a hunt's failure is saved as: its `--init` and `--schedule` files, the `fatswarm run`
command line that replays it and summary.json, and the names of its folder and its kinds.
"""

from __future__ import annotations

import os
import shlex
from collections.abc import Mapping
from typing import Any

from fatswarm.deploy.hunt.search import KINDS, Candidate, Case, Failure, Hunt, configure
from fatswarm.deploy.hunt.shrink import Shrunk, case_decimals
from fatswarm.deploy.sweep.executor import absolute_ref
from fatswarm.deploy.sweep.grid import model_argv
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.version import __version__


def start_data(hunt: Hunt, case: Case) -> dict[str, Any]:
    """The `--init` file of a case: `{"positions": [[x, y], ...]}`, with the side `a` when the
    algorithm has one (what `world.starts.load_init` reads)."""
    data: dict[str, Any] = {"positions": [[x, y] for x, y in case.positions]}
    a = configure(hunt, case.n).values.get("a")
    if a is not None:
        data["a"] = a
    return data


def schedule_data(case: Case) -> dict[str, Any] | None:
    """The `--schedule` file of a case (what `coordinator.schedule.load_script` reads); None for
    a case replayed under its own model."""
    if case.rounds is None:
        return None
    return {"rounds": [list(r) for r in case.rounds], "after": case.after}


def replay_argv(
    hunt: Hunt, case: Case, folder: str = ".", record: str = "replay.jsonl"
) -> list[str]:
    """`fatswarm run --lockstep` repeating the case from the files in `folder`: the same seed
    (it fixes the private frames too), cap, adversary and robot model (its axes that are not the
    paper's), and `--record-views` if the hunt has it. A file algorithm is named absolutely."""

    def inside(name: str) -> str:
        return name if folder == "." else os.path.join(folder, name)

    argv = ["fatswarm", "run", "--lockstep", "--init", inside("start.json")]
    if case.rounds is None:
        argv += ["--scheduler", case.model]
    else:
        argv += ["--scheduler", "scripted", "--schedule", inside("schedule.json")]
    argv += ["--seed", str(case.seed), "--max-rounds", str(case.max_rounds)]
    if hunt.algorithm != DEFAULT_ALGORITHM:
        argv += ["--algorithm", absolute_ref(hunt.algorithm)]
    for name, text in hunt.params:
        argv += ["--param", f"{name}={text}"]
    if hunt.non_rigid is not None:
        argv += ["--non-rigid", repr(hunt.non_rigid)]
    if hunt.crash is not None:
        argv += ["--crash", str(hunt.crash)]
    argv += model_argv(case.robot_model)
    if hunt.record_views:
        argv.append("--record-views")
    return [*argv, "--no-dashboard", "--record", inside(record), "--force"]


def replay_command(hunt: Hunt, case: Case) -> str:
    """The shell line that replays a saved case from inside its folder."""
    return shlex.join(replay_argv(hunt, case))


def summary_data(
    hunt: Hunt,
    hunt_seed: int,
    candidate: Candidate,
    found: Failure,
    shrunk: Shrunk,
    original: Case,
    replayed: Failure | None,
) -> dict[str, Any]:
    """summary.json: what failed, where the hunt drew it (its robot model as a record's header
    says it, when not the paper's), how it was shrunk and how to replay."""
    model = {} if candidate.robot_model.is_paper else {"model": candidate.robot_model.to_header()}
    views = {"record_views": True} if hunt.record_views else {}
    return {
        "kind": shrunk.failure.kind,
        "detail": shrunk.failure.detail,
        "round": shrunk.failure.round,
        "replayed": None
        if replayed is None
        else {"kind": replayed.kind, "detail": replayed.detail},
        "reproduced": shrunk.reproduced,
        "found": {
            "index": candidate.index,
            "family": candidate.family,
            "n": candidate.n,
            "scheduler": candidate.model,
            **model,
            "seed": candidate.seed,
            "kind": found.kind,
            "detail": found.detail,
            "round": found.round,
            "script_rounds": _length(original),
            "decimals": case_decimals(original),
        },
        "shrunk": {
            "n": shrunk.case.n,
            "script_rounds": _length(shrunk.case),
            "after": shrunk.case.after,
            "seed": shrunk.case.seed,
            "max_rounds": shrunk.case.max_rounds,
            "decimals": case_decimals(shrunk.case),
            "runs": shrunk.runs,
            "steps": shrunk.steps,
        },
        "hunt": {
            "seed": hunt_seed,
            "algorithm": hunt.algorithm,
            "params": dict(hunt.params),
            "non_rigid": hunt.non_rigid,
            "crash": hunt.crash,
            **views,
        },
        "command": replay_command(hunt, shrunk.case),
        "fatswarm_version": __version__,
    }


def _length(case: Case) -> int | None:
    return None if case.rounds is None else len(case.rounds)


def folder_name(candidate: Candidate, kind: str) -> str:
    """A failure's subfolder: the candidate's index (the hunt's order) and the kind."""
    return f"{candidate.index:06d}-{kind}"


def kind_counts(kinds: Mapping[str, int]) -> str:
    """`collision 3  stalled 1`, kinds in KINDS order, the ones never seen left out."""
    return "  ".join(f"{kind} {kinds[kind]}" for kind in KINDS if kinds.get(kind))


__all__ = [
    "absolute_ref",
    "folder_name",
    "kind_counts",
    "replay_argv",
    "replay_command",
    "schedule_data",
    "start_data",
    "summary_data",
]
