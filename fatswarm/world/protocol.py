"""The world's wire protocol: its key expressions and every message to or from it (no zenoh).

The agents are the world's clients: their moves and liveliness tokens are defined here too. A view
and a move travel in the robot's private frame: the path starts at the robot's centre (origin), in
the axes the world drew for it (docs/model.md, "Frames"), so the agent never needs and never learns
a global coordinate nor its frame; the world brings the path to world axes and translates it.
The coordinator's control messages (`Hello`, `Begin`, `Commit`) live here as well: it is the
world's client too.
The codec and field checks are `fatswarm.domain.wire`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from fatswarm.domain.lights import MAX_COLOURS
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import (
    Path,
    Points,
    to_record,
)
from fatswarm.domain.quick import quick_init
from fatswarm.domain.seam import MAX_FAILURE, ParamValue
from fatswarm.domain.wire import (
    MAX_ROBOTS,
    MAX_TIME,
    ProtocolError,
    checked_path,
    get_bool,
    get_float,
    get_int,
    get_params,
    get_points,
    get_robots,
    get_str,
    get_times,
    pack,
    points_to_bytes,
    prefix,
    robot_list,
    unpack,
    unpack_any,
)

MAX_CONTROL_BYTES = 160 << 10  # a Commit with 4096 robots' async delays is ~100 KB, a Begin with
# their first Looks ~65 KB, a reply with their next Looks ~77 KB: larger is dropped unread
MAX_MOVE_BYTES = 16 << 10  # a move of MAX_SEGMENTS segments is ~3 KB: larger is dropped unread
MAX_LOOK_BYTES = MAX_MOVE_BYTES + 256  # two integers and a move: larger is refused unread
MAX_NOTICE_BYTES = 64 << 10  # a MovesHeld naming 4096 robots is ~12 KB: larger is dropped unread
STATUSES = tuple(Status)


# --- key expressions (all under fatswarm/<swarm>/) -------------------------------------------


def state_key(swarm: str) -> str:
    """World -> observers: `WorldState` after every change (DROP congestion control)."""
    return f"{prefix(swarm)}/world/state"


def control_key(swarm: str) -> str:
    """Coordinator -> world: queryable taking `Hello`, `Begin`, `Commit`; replies `ControlReply`."""
    return f"{prefix(swarm)}/world/control"


def moves_held_key(swarm: str) -> str:
    """World -> coordinator: `MovesHeld` once every live active robot's move is held."""
    return f"{prefix(swarm)}/world/moves"


def alive_key(swarm: str) -> str:
    """The world's liveliness token, declared once it serves (a second world is refused)."""
    return f"{prefix(swarm)}/alive/world"


def snapshot_key(swarm: str, robot: int) -> str:
    """Agent asks, world answers with a `Snapshot` when the robot is active in an open round and
    has not moved in it yet; until then the world holds the query: its answer is the activation."""
    return f"{prefix(swarm)}/robot/{robot}/snapshot"


def snapshot_any_key(swarm: str) -> str:
    """The world's one queryable for every robot's snapshot."""
    return f"{prefix(swarm)}/robot/*/snapshot"


# --- field checks shared by every protocol module ---------------------------------------------


# --- an agent: its move and its liveliness token ----------------------------------------------


def move_key(swarm: str, robot: int) -> str:
    """Any client -> world: `MoveSubmitted` (BLOCK, express). Our agents send their moves inside
    their next Look instead (`LookRequest.move`): one message a round less."""
    return f"{prefix(swarm)}/robot/{robot}/move"


def move_any_key(swarm: str) -> str:
    """The world's one subscriber for every robot's moves."""
    return f"{prefix(swarm)}/robot/*/move"


def agent_alive_key(swarm: str, robot: int) -> str:
    """The agent's liveliness token: present while its process (session) lives."""
    return f"{prefix(swarm)}/alive/agent/{robot}"


def agent_alive_any_key(swarm: str) -> str:
    """Every agent's liveliness token (coordinator and world subscribe with history)."""
    return f"{prefix(swarm)}/alive/agent/*"


_ALIVE = re.compile(r"^[^/]+/[^/]+/alive/agent/(0|[1-9][0-9]{0,8})$")


def robot_of_alive_key(key: str) -> int | None:
    """The robot id of an agent liveliness key, or None."""
    m = _ALIVE.match(key)
    return int(m.group(1)) if m else None


@dataclass(frozen=True, slots=True)
class MoveSubmitted:
    """Robot `robot` wants to follow `path` in round `round` (relative to itself, in its private
    frame: the world brings it to world axes) and, for a luminous algorithm, to show `colour`
    (an index in its palette) from the start of the move.

    `failed`: its compute raised (`Type: message`, one line, fatswarm.domain.seam.failure_text):
    it stays (an empty path, no colour), and the world books why at once instead of waiting out
    the move timeout. Optional on the wire: a world that does not know it takes a move that stays.
    """

    robot: int
    round: int
    path: Path
    colour: int | None = None
    failed: str | None = None

    def encode(self) -> bytes:
        """msgpack bytes."""
        body: dict[str, Any] = {
            "robot": int(self.robot),
            "round": int(self.round),
            "path": to_record(self.path),
        }
        if self.colour is not None:
            body["colour"] = int(self.colour)
        if self.failed is not None:
            body["failed"] = self.failed[:MAX_FAILURE]
        return pack("move", body)

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> MoveSubmitted:
        """Parse and validate (finite, bounded coordinates); raises ProtocolError."""
        obj = unpack(data, "move")
        path = checked_path(obj.get("path"))
        failed = None if "failed" not in obj else get_str(obj, "failed", MAX_FAILURE)
        if failed is not None and (path or "colour" in obj):
            raise ProtocolError("a move that 'failed' stays: no path, no colour")
        return MoveSubmitted(
            robot=get_int(obj, "robot", 0, MAX_ROBOTS - 1),
            round=get_int(obj, "round", 1, 2**62),
            path=path,
            colour=None if "colour" not in obj else get_int(obj, "colour", 0, MAX_COLOURS - 1),
            failed=failed,
        )

    @staticmethod
    def of(robot: int, round_no: int, path: Path, colour: int | None = None) -> MoveSubmitted:
        """The move as the world receives it from an agent, without the bytes: its path through
        the same record form and the same checks as `decode`; raises ProtocolError."""
        if colour is not None and not 0 <= colour < MAX_COLOURS:
            raise ProtocolError(f"'colour' must be an integer in [0, {MAX_COLOURS - 1}]")
        return MoveSubmitted(robot, round_no, checked_path(to_record(path)), colour)

    @staticmethod
    def failing(robot: int, round_no: int, failed: str) -> MoveSubmitted:
        """The move of a robot whose compute raised (`failed`: why, one line): it stays."""
        return MoveSubmitted(robot, round_no, Path(), None, failed[:MAX_FAILURE])


# --- world -> agent: the snapshot -------------------------------------------------------------


@dataclass(frozen=True, slots=True, eq=False)  # holds arrays: compare fields
class Snapshot:
    """What one Look shows: the positions of the robots the asker sees, relative to it in its
    private frame (shuffled, no ids, nothing of the robots it does not see, not even how many),
    their colours and its own as the lights model lets it read them, and the run's n, algorithm
    and parameters (what the algorithm is configured with).

    Never holds global coordinates: the asker learns where others are from itself, not where it is.
    """

    round: int
    n: int
    algorithm: str  # the name of the algorithm the run is for: an agent running another stays
    params: dict[str, ParamValue]
    view: Points  # (k, 2), k <= n - 1: other centre minus asker's centre, the asker's frame
    epoch: int = 0  # the world process that answered (see LookRequest)
    colours: tuple[int, ...] | None = None  # palette indices lined up with `view`, if shown
    own: int | None = None  # the asker's own colour, if shown

    def encode(self) -> bytes:
        """msgpack bytes."""
        body: dict[str, Any] = {
            "round": int(self.round),
            "n": int(self.n),
            "algorithm": self.algorithm,
            "params": dict(self.params),
            "view": points_to_bytes(self.view),
            "epoch": int(self.epoch),
        }
        if self.colours is not None:
            body["colours"] = bytes(self.colours)
        if self.own is not None:
            body["own"] = int(self.own)
        return pack("snapshot", body)

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> Snapshot:
        """Parse and validate; raises ProtocolError."""
        obj = unpack(data, "snapshot")
        n = get_int(obj, "n", 1, MAX_ROBOTS)
        raw = obj.get("view")
        rows = len(raw) // 16 if isinstance(raw, bytes) and len(raw) <= (n - 1) * 16 else n - 1
        view = get_points(obj, "view", rows)
        colours = obj.get("colours")
        if colours is not None and (
            not isinstance(colours, bytes)
            or len(colours) != rows
            or any(c >= MAX_COLOURS for c in colours)
        ):
            raise ProtocolError(f"'colours' must be {rows} palette indices below {MAX_COLOURS}")
        return Snapshot(
            round=get_int(obj, "round", 1, 2**62),
            n=n,
            algorithm=get_str(obj, "algorithm"),
            params=get_params(obj, "params"),
            view=view,
            epoch=get_int(obj, "epoch", 0, 2**63 - 1),
            colours=None if colours is None else tuple(colours),
            own=None if "own" not in obj else get_int(obj, "own", 0, MAX_COLOURS - 1),
        )


@dataclass(frozen=True, slots=True)
class LookRequest:
    """An agent's Look (the query's payload): the snapshot of a round after `after`, the last
    round it moved in at the world process `epoch`. The world holds the query until then, so a
    Look that overtakes the agent's own move is not answered twice; a new world process (another
    epoch) may reopen a round it lost, so it ignores `after` from another epoch.

    `move`: the robot's encoded `MoveSubmitted` for round `after`, if it has one to send: the
    Move and the next Look travel as one message (b"": none; the world decodes it as a move
    that came from the robot of the query's key). The agent sends it with every Look until one
    is answered, so a Look lost with a router does not lose the move; the world takes it once."""

    epoch: int = 0
    after: int = 0
    move: bytes = b""

    def encode(self) -> bytes:
        """msgpack bytes."""
        fields: dict[str, Any] = {"epoch": int(self.epoch), "after": int(self.after)}
        if self.move:
            fields["move"] = bytes(self.move)
        return pack("look", fields)

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> LookRequest:
        """Parse and validate; raises ProtocolError."""
        obj = unpack(data, "look")
        move = obj.get("move", b"")
        if not isinstance(move, bytes) or len(move) > MAX_MOVE_BYTES:
            raise ProtocolError(f"'move' must be at most {MAX_MOVE_BYTES} bytes")
        return LookRequest(
            epoch=get_int(obj, "epoch", 0, 2**63 - 1),
            after=get_int(obj, "after", 0, 2**62),
            move=move,
        )


# --- coordinator <-> world: control queries ---------------------------------------------------


@dataclass(frozen=True, slots=True)
class Hello:
    """Coordinator asks where the run stands (at start and after a restart)."""

    def encode(self) -> bytes:
        """msgpack bytes."""
        return pack("hello", {})


def _times(pairs: Sequence[tuple[int, float]]) -> list[list[float]]:
    return [[int(r), float(t)] for r, t in pairs]


@quick_init
@dataclass(frozen=True, slots=True)
class Begin:
    """Coordinator opens round `round` with active set `active` (before activating the agents).

    Async models: the round is the instant `at` (virtual time) at which `active` Look; `looks`
    gives robots their first Look's time (the adversary's choice, fatswarm/domain/adversary.py).
    """

    round: int
    active: tuple[int, ...]
    at: float | None = None
    looks: tuple[tuple[int, float], ...] = ()

    def encode(self) -> bytes:
        """msgpack bytes."""
        fields: dict[str, Any] = {"round": int(self.round), "active": robot_list(self.active)}
        if self.at is not None:
            fields["at"] = float(self.at)
        if self.looks:
            fields["looks"] = _times(self.looks)
        return pack("begin", fields)


@quick_init
@dataclass(frozen=True, slots=True)
class Commit:
    """Coordinator closes round `round`: the world applies the moves it holds, through physics;
    with `then_active`, it then opens round `round + 1` with that active set, as a `Begin` would
    (one request instead of two on the round's critical path)."""

    round: int
    timed_out: tuple[int, ...] = ()  # active robots the coordinator heard no move from (the
    # world records its own: see ControlReply.timed_out)
    then_active: tuple[int, ...] = ()  # the next round's active set; () opens nothing
    delays: tuple[tuple[int, float, float], ...] = ()  # async: (robot, compute, wait) for each
    # active robot: the adversary's delays of the cycle it began in this round

    def encode(self) -> bytes:
        """msgpack bytes."""
        fields: dict[str, Any] = {
            "round": int(self.round),
            "timed_out": robot_list(self.timed_out),
            "then_active": robot_list(self.then_active),
        }
        if self.delays:
            fields["delays"] = [[int(r), float(c), float(w)] for r, c, w in self.delays]
        return pack("commit", fields)

    @property
    def then(self) -> Begin | None:
        """The Begin this commit carries, if any."""
        return Begin(self.round + 1, self.then_active) if self.then_active else None


ControlRequest = Hello | Begin | Commit


def decode_control(data: bytes | bytearray | memoryview) -> ControlRequest:
    """Parse a control request of any kind; raises ProtocolError."""
    kind, obj = unpack_any(data, ("hello", "begin", "commit"))
    if kind == "hello":
        return Hello()
    if kind == "begin":
        at = obj.get("at")
        return Begin(
            round=get_int(obj, "round", 1, 2**62),
            active=get_robots(obj, "active"),
            at=None if at is None else get_float(obj, "at", 0.0, MAX_TIME),
            looks=get_times(obj, "looks"),
        )
    return Commit(
        round=get_int(obj, "round", 1, 2**62),
        timed_out=get_robots(obj, "timed_out"),
        then_active=get_robots(obj, "then_active"),
        delays=get_times(obj, "delays", 3),
    )


@quick_init
@dataclass(frozen=True, slots=True)
class ControlReply:
    """The world's answer to a control request: accepted or not (with why) and where it stands."""

    ok: bool
    reason: str  # empty when ok
    n: int
    committed: int  # last committed (durable) round, 0 before the first
    open_round: int  # the round open for moves, 0 if none
    status: Status
    collisions: int = 0  # robots stopped at contact so far (a formation with any is not clean)
    held: tuple[int, ...] = ()  # robots whose moves it holds for `open_round` (a restarted
    # coordinator need not wait for their notices again)
    now: float = 0.0  # async: the world's virtual time
    looks: tuple[tuple[int, float], ...] = ()  # async: each waiting live robot's next Look
    unset: tuple[int, ...] = ()  # async: waiting live robots with no Look time yet (first Looks)
    epoch: int = 0  # the world process that answers (MovesHeld.epoch)
    timed_out: tuple[int, ...] = ()  # the reply to a Commit: the robots of the round it committed
    # that sent no move in time, as the world records them (the coordinator hears of moves only
    # through the round's one notice, so it cannot tell them itself at a deadline)
    cycles: tuple[tuple[int, int], ...] = ()  # async, an instant open: each of its robots and the
    # cycle it began there (the adversary's delays are drawn for that cycle: a coordinator that
    # restarted counts on from the world's, not from its own)

    def encode(self) -> bytes:
        """msgpack bytes."""
        return pack(
            "control-reply",
            {
                "ok": self.ok,
                "reason": self.reason[:200],
                "n": int(self.n),
                "committed": int(self.committed),
                "open_round": int(self.open_round),
                "status": self.status,
                "collisions": int(self.collisions),
                "held": robot_list(self.held),
                "epoch": int(self.epoch),
                **(
                    {}
                    if not (self.now or self.looks or self.unset)
                    else {
                        "now": float(self.now),
                        "looks": _times(self.looks),
                        "unset": robot_list(self.unset),
                    }
                ),
                **({"timed_out": robot_list(self.timed_out)} if self.timed_out else {}),
                **({"cycles": _times(self.cycles)} if self.cycles else {}),
            },
        )

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> ControlReply:
        """Parse and validate; raises ProtocolError."""
        obj = unpack(data, "control-reply")
        status = get_str(obj, "status")
        if status not in STATUSES:
            raise ProtocolError(f"'status' must be one of {STATUSES}, got {status!r}")
        return ControlReply(
            ok=get_bool(obj, "ok"),
            reason=get_str(obj, "reason", 200),
            n=get_int(obj, "n", 1, MAX_ROBOTS),
            committed=get_int(obj, "committed", 0, 2**62),
            open_round=get_int(obj, "open_round", 0, 2**62),
            status=Status(status),
            collisions=get_int(obj, "collisions", 0, 2**62),
            held=get_robots(obj, "held"),
            now=get_float(obj, "now", 0.0, MAX_TIME) if "now" in obj else 0.0,
            looks=get_times(obj, "looks"),
            unset=get_robots(obj, "unset") if "unset" in obj else (),
            epoch=get_int(obj, "epoch", 0, 2**63 - 1) if "epoch" in obj else 0,
            timed_out=get_robots(obj, "timed_out") if "timed_out" in obj else (),
            cycles=tuple((int(r), int(c)) for r, c in get_times(obj, "cycles")),
        )


# --- world -> coordinator: moves held ---------------------------------------------------------


@quick_init
@dataclass(frozen=True, slots=True)
class MovesHeld:
    """The world holds the moves of `robots` for round `round`, and every active robot whose agent
    is alive is among them: the round can be committed (BLOCK, so none is lost). Sent once a round,
    again only if a late robot's move joins them. `epoch`: the world process that holds them (a
    notice of a world that has since been restarted is not about the round open now)."""

    round: int
    robots: tuple[int, ...]
    epoch: int = 0

    def encode(self) -> bytes:
        """msgpack bytes."""
        return pack(
            "moves-held",
            {"round": int(self.round), "robots": robot_list(self.robots), "epoch": int(self.epoch)},
        )

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> MovesHeld:
        """Parse and validate; raises ProtocolError."""
        obj = unpack(data, "moves-held")
        return MovesHeld(
            round=get_int(obj, "round", 1, 2**62),
            robots=get_robots(obj, "robots"),
            epoch=get_int(obj, "epoch", 0, 2**63 - 1) if "epoch" in obj else 0,
        )
