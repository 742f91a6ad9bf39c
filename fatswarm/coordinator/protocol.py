"""The coordinator's wire protocol: its liveliness token.

It has no message of its own: it opens and commits rounds through the world's control queryable
(`world.protocol`), and an agent learns it is active from the world's answer to its held Look.
"""

from __future__ import annotations

from fatswarm.domain.wire import prefix


def alive_key(swarm: str) -> str:
    """The coordinator's liveliness token (a second coordinator on the swarm is refused)."""
    return f"{prefix(swarm)}/alive/coordinator"
