"""fatswarm: a swarm emulator in which every robot is its own process, talking over Eclipse Zenoh.

The packages live in the checkout's top-level folders (agent/, coordinator/, world/, deploy/) and
are installed and imported only as fatswarm.agent, fatswarm.coordinator, fatswarm.world and
fatswarm.deploy, so that no generic name is installed and nothing in a working directory can
shadow them. In the checkout, fatswarm/ links to those folders.

The Python API (fatswarm.deploy.engine.api) is here too: `fatswarm.run(...)`,
`fatswarm.read_record(path)`, `fatswarm.positions_at(record, t)`, `fatswarm.summary(...)`,
`fatswarm.trajectory(record)`, `fatswarm.Swarm(...)` (a run to step through), loaded on first
use so that `import fatswarm` stays light (`dir(fatswarm)` lists them all the same).
docs/notebook.md shows them in a notebook.
"""

import importlib as _importlib
import typing as _typing

from fatswarm.domain.version import __version__

if _typing.TYPE_CHECKING:  # the API's types for type checkers and editors; loaded lazily below
    from fatswarm.deploy.engine.api import (
        RunRecord,
        RunResult,
        moved_by_round,
        positions_at,
        read_record,
        run,
        summary,
        trajectory,
    )
    from fatswarm.deploy.engine.swarm import Swarm
    from fatswarm.deploy.sweep.api import sweep

__all__ = [
    "RunRecord",
    "RunResult",
    "Swarm",
    "__version__",
    "moved_by_round",
    "positions_at",
    "read_record",
    "run",
    "summary",
    "sweep",
    "trajectory",
]
_API = frozenset(__all__) - {"__version__"}  # names of fatswarm.deploy.engine.api, but:
_ELSEWHERE = {  # the API's names in modules of their own
    "Swarm": "fatswarm.deploy.engine.swarm",
    "sweep": "fatswarm.deploy.sweep.api",
}


def __getattr__(name: str) -> _typing.Any:
    """The API's functions, imported when first asked for."""
    if name in _API:
        module = _ELSEWHERE.get(name, "fatswarm.deploy.engine.api")
        return getattr(_importlib.import_module(module), name)
    raise AttributeError(f"module 'fatswarm' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The module's names and the API's, which load on first use (for completion in notebooks)."""
    return sorted({*globals(), *_API, *_ELSEWHERE})  # private imports and helpers start with "_"
