"""The agent's wire protocol: its move and its liveliness token (versioned msgpack).

A move travels in the robot's translation-only frame: the path starts at the robot's centre
(origin), axes are the world's (the private mirroring is already undone), so the agent never needs
and never learns a global coordinate; the world translates it by the robot's position.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from fatswarm.agent.path import Arc, Path, PathFormatError, from_record, to_record, vertices
from fatswarm.world.protocol import (
    MAX_CARRIED_MOVE_BYTES,
    MAX_COORD,
    MAX_ROBOTS,
    ProtocolError,
    get_int,
    pack,
    prefix,
    unpack,
)

MAX_SWEEP = 8 * math.pi  # an arc never needs more than a few turns; bounds physics work
MAX_MOVE_BYTES = MAX_CARRIED_MOVE_BYTES  # a move of MAX_SEGMENTS segments is ~3 KB: larger is
# dropped unread


def move_key(swarm: str, robot: int) -> str:
    """Any client -> world: `MoveSubmitted` (BLOCK, express). Our agents send their moves inside
    their next Look instead (`LookRequest.move`): one message a round less."""
    return f"{prefix(swarm)}/robot/{robot}/move"


def move_any_key(swarm: str) -> str:
    """The world's one subscriber for every robot's moves."""
    return f"{prefix(swarm)}/robot/*/move"


def alive_key(swarm: str, robot: int) -> str:
    """The agent's liveliness token: present while its process (session) lives."""
    return f"{prefix(swarm)}/alive/agent/{robot}"


def alive_any_key(swarm: str) -> str:
    """Every agent's liveliness token (coordinator and world subscribe with history)."""
    return f"{prefix(swarm)}/alive/agent/*"


_ALIVE = re.compile(r"^[^/]+/[^/]+/alive/agent/(0|[1-9][0-9]{0,8})$")


def robot_of_alive_key(key: str) -> int | None:
    """The robot id of an agent liveliness key, or None."""
    m = _ALIVE.match(key)
    return int(m.group(1)) if m else None


@dataclass(frozen=True, slots=True)
class MoveSubmitted:
    """Robot `robot` wants to follow `path` in round `round` (relative to itself, world axes)."""

    robot: int
    round: int
    path: Path

    def encode(self) -> bytes:
        """msgpack bytes."""
        return pack(
            "move",
            {"robot": int(self.robot), "round": int(self.round), "path": to_record(self.path)},
        )

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> MoveSubmitted:
        """Parse and validate (finite, bounded coordinates); raises ProtocolError."""
        obj = unpack(data, "move")
        try:
            path = from_record(obj.get("path"))
        except PathFormatError as exc:
            raise ProtocolError(f"bad path: {exc}") from None
        for x, y in vertices((0.0, 0.0), path):
            if not (abs(x) <= MAX_COORD and abs(y) <= MAX_COORD):
                raise ProtocolError("path leaves the bounded plane")
        for seg in path.segments:
            if isinstance(seg, Arc) and not (
                abs(seg.center[0]) <= MAX_COORD
                and abs(seg.center[1]) <= MAX_COORD
                and abs(seg.sweep) <= MAX_SWEEP
            ):
                raise ProtocolError("arc centre or sweep out of range")
        return MoveSubmitted(
            robot=get_int(obj, "robot", 0, MAX_ROBOTS - 1),
            round=get_int(obj, "round", 1, 2**62),
            path=path,
        )
