"""The coordinator's wire protocol: the round announcement agents act on (versioned msgpack)."""

from __future__ import annotations

from dataclasses import dataclass

from fatswarm.world.protocol import MAX_ROBOTS, get_int, get_robots, pack, prefix, unpack

MAX_ROUND_START_BYTES = 64 << 10  # naming 4096 active robots is ~20 KB: larger is dropped unread


def round_key(swarm: str) -> str:
    """Coordinator -> agents (and observers): `RoundStart` once the world has opened the round."""
    return f"{prefix(swarm)}/coordinator/round"


def alive_key(swarm: str) -> str:
    """The coordinator's liveliness token (a second coordinator on the swarm is refused)."""
    return f"{prefix(swarm)}/alive/coordinator"


@dataclass(frozen=True, slots=True)
class RoundStart:
    """Round `round` is open; robots in `active` Look, Compute and Move within `timeout_ms`."""

    round: int
    active: tuple[int, ...]
    timeout_ms: int

    def encode(self) -> bytes:
        """msgpack bytes."""
        return pack(
            "round-start",
            {
                "round": int(self.round),
                "active": [int(r) for r in self.active],
                "timeout_ms": int(self.timeout_ms),
            },
        )

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> RoundStart:
        """Parse and validate; raises world.protocol.ProtocolError."""
        obj = unpack(data, "round-start")
        return RoundStart(
            round=get_int(obj, "round", 1, 2**62),
            active=get_robots(obj, "active", MAX_ROBOTS),
            timeout_ms=get_int(obj, "timeout_ms", 0, 3_600_000),
        )
