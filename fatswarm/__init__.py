"""fatswarm: a swarm emulator in which every robot is its own process, talking over Eclipse Zenoh.

The packages live in the checkout's top-level folders (agent/, coordinator/, world/, deploy/) and
are installed and imported only as fatswarm.agent, fatswarm.coordinator, fatswarm.world and
fatswarm.deploy, so that no generic name is installed and nothing in a working directory can
shadow them. In the checkout, fatswarm/ links to those folders.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("fatswarm")
except PackageNotFoundError:  # a checkout that was never installed
    __version__ = "0+unknown"
