"""fatswarm: a swarm emulator in which every robot is its own process, talking over Eclipse Zenoh.

The packages live in the checkout's top-level folders (agent/, coordinator/, world/, deploy/) and
are installed and imported only as fatswarm.agent, fatswarm.coordinator, fatswarm.world and
fatswarm.deploy, so that no generic name is installed and nothing in a working directory can
shadow them. In the checkout, fatswarm/ links to those folders.

The Python API (fatswarm.deploy.engine.api) is here too: `fatswarm.run(...)`,
`fatswarm.read_record(path)` and `fatswarm.trajectory(record)`, loaded on first use so that `import
fatswarm` stays light.
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any

_API = ("run", "read_record", "trajectory", "moved_by_round", "summary")

try:
    __version__ = version("fatswarm")
except PackageNotFoundError:  # a checkout that was never installed
    __version__ = "0+unknown"


def __getattr__(name: str) -> Any:
    """The API's functions, imported when first asked for."""
    if name in _API:
        return getattr(import_module("fatswarm.deploy.engine.api"), name)
    raise AttributeError(f"module 'fatswarm' has no attribute {name!r}")


__all__ = ["__version__", *_API]
