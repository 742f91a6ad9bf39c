"""One import name is installed: fatswarm (its parts are fatswarm.agent, .world, ...); the checks
that ask a fresh interpreter are in tests/integration/test_namespace_installed.py."""

from __future__ import annotations

import sys

GENERIC = ("agent", "world", "coordinator", "deploy")


def test_importing_every_part_loads_no_generic_top_level_module() -> None:
    import fatswarm.deploy.cli
    import fatswarm.deploy.net.launcher
    import fatswarm.deploy.net.parts  # noqa: F401

    assert not [name for name in sys.modules if name.split(".")[0] in GENERIC]
