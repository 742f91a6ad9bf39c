"""The world's message to its observers (dashboards, watchers, tests): `WorldState`, published
after each round and at a round's start, with what the world knows of each agent. Its key is
`protocol.state_key`; the codec and field checks are `fatswarm.domain.wire`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from fatswarm.domain.figures import derived_figures
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points
from fatswarm.domain.robot_model import PAPER_MODEL, ModelError, RobotModel
from fatswarm.domain.seam import ParamValue
from fatswarm.domain.wire import (
    MAX_COORD,
    MAX_ROBOTS,
    ProtocolError,
    get_bool,
    get_figures,
    get_float,
    get_int,
    get_lights,
    get_params,
    get_points,
    get_robots,
    get_str,
    pack,
    points_to_bytes,
    robot_list,
    unpack,
)
from fatswarm.world.protocol import STATUSES

MAX_OUTSIDE = 2000  # characters of the line saying a run is outside its assumptions
MAX_REFUSED_KINDS = 64  # kinds of refused messages a state may count (world.rejections)


@dataclass(frozen=True, slots=True)
class AgentInfo:
    """What the world knows of one robot's agent process."""

    alive: bool  # its liveliness token is present
    last_active: int  # last round it was active in, -1 if never
    last_path_length: float  # length of the last path it sent that was applied (0 if none)
    timeouts: int  # rounds it was active in but sent no move in time


@dataclass(frozen=True, slots=True, eq=False)  # holds arrays: compare fields
class WorldState:
    """The world after a round (or at a round's start): the observers' stream, DROP-published."""

    round: int  # last committed round (0 before the first)
    n: int
    algorithm: str  # its registered name
    params: dict[str, ParamValue]  # its parameters, every one
    figures: dict[str, float]  # the algorithm's figures for the configuration (may be empty)
    scheduler: str  # (never the seed: it would give away every robot's private frame)
    swarm: str
    positions: Points  # (n, 2) world frame
    active: tuple[int, ...]  # active set of the round being run (or just committed)
    open_round: int  # the round being run, 0 between a commit and the next round's opening
    moved: tuple[int, ...]  # robots whose move was applied in `round`
    stopped: tuple[int, ...]  # robots stopped by contact in `round`
    collisions_total: int
    status: Status
    agents: tuple[AgentInfo, ...]  # one per robot
    lights: tuple[str, ...] = ()  # each robot's colour name (a luminous algorithm's), else ()
    palette: tuple[str, ...] = ()  # the algorithm's colour names, else ()
    # the run's figures derived from the positions so far (fatswarm.domain.figures: min_gap, its
    # least over the rounds), by name; only those known (a figure without a value yet is left out)
    derived: dict[str, float] = field(default_factory=dict)
    outside: str = ""  # how the run is outside its algorithm's assumptions ('' if within)
    model: RobotModel = PAPER_MODEL  # the robot model the run enforces (sent when not the paper's)
    # messages the world refused or dropped so far, by kind (world.rejections); {} if none
    refused: dict[str, int] = field(default_factory=dict)

    @property
    def a(self) -> float:
        """The side `a` of the paper's algorithm (0 for an algorithm without one)."""
        value = self.params.get("a", 0.0)
        return float(value) if isinstance(value, (int, float)) else 0.0

    def encode(self) -> bytes:
        """msgpack bytes of this state."""
        return pack(
            "state",
            {
                "round": int(self.round),
                "n": int(self.n),
                "algorithm": self.algorithm,
                "params": dict(self.params),
                "figures": {k: float(v) for k, v in self.figures.items()},
                "scheduler": self.scheduler,
                "swarm": self.swarm,
                "positions": points_to_bytes(self.positions),
                "active": robot_list(self.active),
                "open_round": int(self.open_round),
                "moved": robot_list(self.moved),
                "stopped": robot_list(self.stopped),
                "collisions_total": int(self.collisions_total),
                "status": self.status,
                "alive": [bool(g.alive) for g in self.agents],
                "last_active": [int(g.last_active) for g in self.agents],
                "last_path_length": [float(g.last_path_length) for g in self.agents],
                "timeouts": [int(g.timeouts) for g in self.agents],
                **(
                    {"lights": list(self.lights), "palette": list(self.palette)}
                    if self.lights
                    else {}
                ),
                **({"derived": derived_wire(self.derived)} if self.derived else {}),
                **({"outside": self.outside} if self.outside else {}),
                **({} if self.model.is_paper else {"model": self.model.to_header()}),
                **(
                    {"refused": {k: int(v) for k, v in self.refused.items()}}
                    if self.refused
                    else {}
                ),
            },
        )

    @staticmethod
    def decode(data: bytes | bytearray | memoryview) -> WorldState:
        """Parse and validate; raises ProtocolError."""
        obj = unpack(data, "state")
        n = get_int(obj, "n", 1, MAX_ROBOTS)
        status = get_str(obj, "status")
        if status not in STATUSES:
            raise ProtocolError(f"'status' must be one of {STATUSES}, got {status!r}")
        alive, last_active = obj.get("alive"), obj.get("last_active")
        lengths, timeouts = obj.get("last_path_length"), obj.get("timeouts")
        for name, col in (("alive", alive), ("last_active", last_active)):
            if not isinstance(col, list) or len(col) != n:
                raise ProtocolError(f"{name!r} must be a list of {n} values")
        for name, col in (("last_path_length", lengths), ("timeouts", timeouts)):
            if not isinstance(col, list) or len(col) != n:
                raise ProtocolError(f"{name!r} must be a list of {n} values")
        assert isinstance(alive, list) and isinstance(last_active, list)
        assert isinstance(lengths, list) and isinstance(timeouts, list)
        agents = tuple(
            AgentInfo(
                alive=get_bool({"x": alive[i]}, "x"),
                last_active=get_int({"x": last_active[i]}, "x", -1, 2**62),
                last_path_length=get_float({"x": lengths[i]}, "x", 0.0, MAX_COORD),
                timeouts=get_int({"x": timeouts[i]}, "x", 0, 2**62),
            )
            for i in range(n)
        )
        return WorldState(
            round=get_int(obj, "round", 0, 2**62),
            n=n,
            algorithm=get_str(obj, "algorithm"),
            params=get_params(obj, "params"),
            figures=get_figures(obj, "figures"),
            scheduler=get_str(obj, "scheduler"),
            swarm=get_str(obj, "swarm"),
            positions=get_points(obj, "positions", n),
            active=get_robots(obj, "active", n),
            open_round=get_int(obj, "open_round", 0, 2**62),
            moved=get_robots(obj, "moved", n),
            stopped=get_robots(obj, "stopped", n),
            collisions_total=get_int(obj, "collisions_total", 0, 2**62),
            status=Status(status),
            agents=agents,
            **get_lights(obj, n),
            derived=get_derived(obj),
            outside=get_str(obj, "outside", MAX_OUTSIDE) if "outside" in obj else "",
            model=get_model(obj),
            refused=get_refused(obj),
        )


def get_model(obj: dict[str, Any]) -> RobotModel:
    """A state's robot model (the paper's for a world that sends none); ProtocolError for one
    that is not a record header's `model` object."""
    try:
        return RobotModel.from_header(obj.get("model"))
    except ModelError as exc:
        raise ProtocolError(f"'model': {exc}") from None


def get_refused(obj: dict[str, Any]) -> dict[str, int]:
    """A state's counts of refused messages by kind ({} for a world that sends none)."""
    refused = obj.get("refused", {})
    if not isinstance(refused, dict) or len(refused) > MAX_REFUSED_KINDS:
        raise ProtocolError(f"'refused' must be a map of at most {MAX_REFUSED_KINDS} counts")
    return {
        get_str({"kind": k}, "kind", 80): get_int({"count": v}, "count", 0, 2**62)
        for k, v in refused.items()
    }


def derived_wire(values: dict[str, float]) -> dict[str, float]:
    """The run's derived figures as the state carries them: the declared ones, as numbers."""
    known = {f.name for f in derived_figures()}
    return {k: float(v) for k, v in values.items() if k in known}


def get_derived(obj: dict[str, Any]) -> dict[str, float]:
    """A state's derived figures ({} for a world that sends none); those this fatswarm does not
    declare are left out (a newer world's)."""
    if "derived" not in obj:
        return {}
    known = {f.name for f in derived_figures()}
    return {k: v for k, v in get_figures(obj, "derived").items() if k in known}
