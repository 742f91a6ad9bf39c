"""The message codec every service shares: versioned msgpack maps, validated field by field.

Every message is a msgpack map with `v` (protocol version) and `t` (message type). Decoders check
type, shape, size, finiteness and version and raise `ProtocolError` (peer sent garbage) on anything
else; services log the reason, count it and drop the message. Positions travel as little-endian
float64 bytes, never as JSON. Keys of one swarm live under `fatswarm/<swarm>/`: each service's
protocol module builds its own below `prefix`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

import msgpack
import numpy as np

from fatswarm.domain.lights import MAX_COLOURS
from fatswarm.domain.path import Arc, Path, PathFormatError, Points, from_record, vertices
from fatswarm.domain.seam import MAX_PARAMS, MAX_TEXT, ParamValue

PROTOCOL_VERSION = 5  # 3: the held Look is the activation; one moves notice a round; no seed;
# 4: async models' virtual times (Begin.at, Begin.looks, Commit.delays, ControlReply.now/looks);
# 5: a Look carries the robot's move of the round it last saw (LookRequest.move)
ROOT = "fatswarm"
MAX_ROBOTS = 4096  # bounds every list and array a peer can make us allocate
MAX_MESSAGE_BYTES = 1 << 20  # 1 MiB: a 4096-robot state is ~130 KB
MAX_COORD = 1e9  # coordinates beyond this are nonsense for unit discs and risk overflow
_SWARM_NAME = re.compile(r"[A-Za-z0-9_.-]{1,64}")


class ProtocolError(ValueError):
    """A peer sent something that is not a valid message of this protocol (never applied)."""


def check_swarm(swarm: str) -> str:
    """The swarm name, if it is a safe single key chunk; raises ValueError saying what to fix."""
    if not isinstance(swarm, str) or not _SWARM_NAME.fullmatch(swarm):
        raise ValueError(
            f"swarm name must be 1-64 characters of letters, digits, '_', '-', '.', got {swarm!r}"
        )
    return swarm


def prefix(swarm: str) -> str:
    """`fatswarm/<swarm>`: every key of one swarm lives below it, so swarms can share a router."""
    return f"{ROOT}/{check_swarm(swarm)}"


_ROBOT_IN_KEY = re.compile(r"^[^/]+/[^/]+/robot/(0|[1-9][0-9]{0,8})/[a-z]+$")


def robot_of_key(key: str) -> int | None:
    """The robot id in `fatswarm/<swarm>/robot/<id>/<leaf>`, or None if the key has no valid id."""
    m = _ROBOT_IN_KEY.match(key)
    return int(m.group(1)) if m else None


def pack(kind: str, fields: dict[str, Any]) -> bytes:
    """A versioned msgpack map of type `kind`."""
    out: bytes = msgpack.packb({"v": PROTOCOL_VERSION, "t": kind, **fields}, use_bin_type=True)
    return out


def unpack_any(
    data: bytes | bytearray | memoryview, kinds: Sequence[str]
) -> tuple[str, dict[str, Any]]:
    """The type and fields of a message whose type is one of `kinds`; raises ProtocolError."""
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise ProtocolError(f"payload must be bytes, got {type(data).__name__}")
    if len(data) > MAX_MESSAGE_BYTES:
        raise ProtocolError(f"message of {len(data)} bytes exceeds {MAX_MESSAGE_BYTES}")
    try:
        obj = msgpack.unpackb(bytes(data), raw=False, strict_map_key=True)
    except Exception as exc:  # msgpack raises several unrelated types on garbage
        raise ProtocolError(f"not msgpack: {type(exc).__name__}: {exc}") from None
    if not isinstance(obj, dict):
        raise ProtocolError(f"message must be a map, got {type(obj).__name__}")
    version = obj.get("v")
    if version != PROTOCOL_VERSION:
        raise ProtocolError(f"protocol version {version!r}, expected {PROTOCOL_VERSION}")
    kind = obj.get("t")
    if kind not in kinds:
        raise ProtocolError(f"message type {kind!r}, expected one of {tuple(kinds)}")
    return str(kind), obj


def unpack(data: bytes | bytearray | memoryview, kind: str) -> dict[str, Any]:
    """The fields of a message of type `kind`; raises ProtocolError for anything else."""
    return unpack_any(data, (kind,))[1]


def get_int(obj: dict[str, Any], key: str, lo: int, hi: int) -> int:
    """An integer field within [lo, hi]."""
    v = obj.get(key)
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise ProtocolError(f"{key!r} must be an integer in [{lo}, {hi}], got {v!r}")
    return v


def get_float(
    obj: dict[str, Any], key: str, lo: float = -MAX_COORD, hi: float = MAX_COORD
) -> float:
    """A finite number field within [lo, hi]."""
    v = obj.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ProtocolError(f"{key!r} must be a number, got {v!r}")
    f = float(v)
    if not math.isfinite(f) or not lo <= f <= hi:
        raise ProtocolError(f"{key!r} must be finite and in [{lo}, {hi}], got {v!r}")
    return f


def get_str(obj: dict[str, Any], key: str, max_len: int = 64) -> str:
    """A short string field."""
    v = obj.get(key)
    if not isinstance(v, str) or len(v) > max_len:
        raise ProtocolError(f"{key!r} must be a string of at most {max_len} characters")
    return v


def get_bool(obj: dict[str, Any], key: str) -> bool:
    """A boolean field."""
    v = obj.get(key)
    if not isinstance(v, bool):
        raise ProtocolError(f"{key!r} must be a boolean, got {v!r}")
    return v


def get_robots(obj: dict[str, Any], key: str, n: int = MAX_ROBOTS) -> tuple[int, ...]:
    """A list of distinct robot ids in [0, n), returned sorted."""
    v = obj.get(key)
    if not isinstance(v, list) or len(v) > min(n, MAX_ROBOTS):
        raise ProtocolError(f"{key!r} must be a list of at most {min(n, MAX_ROBOTS)} robot ids")
    for r in v:
        if isinstance(r, bool) or not isinstance(r, int) or not 0 <= r < n:
            raise ProtocolError(f"{key!r} holds {r!r}, not a robot id in [0, {n})")
    if len(set(v)) != len(v):
        raise ProtocolError(f"{key!r} repeats a robot id")
    return tuple(sorted(v))


def get_params(obj: dict[str, Any], key: str) -> dict[str, ParamValue]:
    """An algorithm's parameters: a short map of plain names to finite scalars or short texts."""
    v = obj.get(key)
    if not isinstance(v, dict) or len(v) > MAX_PARAMS:
        raise ProtocolError(f"{key!r} must be a map of at most {MAX_PARAMS} parameters")
    out: dict[str, ParamValue] = {}
    for name, value in v.items():
        if not isinstance(name, str) or not _SWARM_NAME.fullmatch(name):
            raise ProtocolError(f"{key!r} holds a parameter name that is not plain: {name!r}")
        if isinstance(value, float) and not math.isfinite(value):
            raise ProtocolError(f"{key!r}: parameter {name} is not finite")
        if isinstance(value, str) and len(value) > MAX_TEXT:
            raise ProtocolError(f"{key!r}: parameter {name} is longer than {MAX_TEXT} characters")
        if not isinstance(value, (bool, int, float, str)):
            raise ProtocolError(f"{key!r}: parameter {name} must be a number, bool or text")
        out[name] = value
    return out


def get_figures(obj: dict[str, Any], key: str) -> dict[str, float]:
    """A short map of labels to finite numbers (an algorithm's figures for the dashboard)."""
    v = obj.get(key)
    if not isinstance(v, dict) or len(v) > MAX_PARAMS:
        raise ProtocolError(f"{key!r} must be a map of at most {MAX_PARAMS} figures")
    out: dict[str, float] = {}
    for label, value in v.items():
        if not isinstance(label, str) or len(label) > 64:
            raise ProtocolError(f"{key!r} holds a label that is not a short text")
        out[label] = get_float({"x": value}, "x", -MAX_COORD, MAX_COORD)
    return out


def points_to_bytes(points: Points) -> bytes:
    """(k, 2) float64 positions as little-endian bytes."""
    return np.ascontiguousarray(points, dtype="<f8").tobytes()


def get_points(obj: dict[str, Any], key: str, rows: int) -> Points:
    """A (rows, 2) array of finite, bounded float64 coordinates sent as bytes."""
    v = obj.get(key)
    if not isinstance(v, bytes) or len(v) != rows * 16:
        raise ProtocolError(f"{key!r} must be {rows * 16} bytes of (x, y) float64 pairs")
    arr = np.frombuffer(v, dtype="<f8").astype(np.float64).reshape(rows, 2)
    # one reduction checks both: a NaN's or an infinity's maximum is not <= MAX_COORD (the
    # agent decodes a view every Look: two numpy calls fewer there)
    if rows and not float(np.abs(arr).max()) <= MAX_COORD:
        raise ProtocolError(f"{key!r} holds a non-finite or out-of-range coordinate")
    return arr


def robot_list(values: Sequence[int]) -> list[int]:
    return [int(r) for r in values]


MAX_TIME = 1e15  # virtual times (async models) are finite and below this
MAX_SWEEP = 8 * math.pi  # an arc never needs more than a few turns; bounds physics work


def checked_path(record: Any) -> Path:
    """A move's path from its record form (`to_record`), checked as the world checks every move:
    well formed, inside the bounded plane, arcs of bounded sweep; raises ProtocolError."""
    try:
        path = from_record(record)
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
    return path


def get_times(obj: dict[str, Any], key: str, width: int = 2) -> tuple[tuple[Any, ...], ...]:
    """An optional list of [robot, t, ...] rows (robot an int, then `width` - 1 finite times in
    [0, MAX_TIME]); () when absent."""
    rows = obj.get(key, [])
    if not isinstance(rows, list) or len(rows) > MAX_ROBOTS:
        raise ProtocolError(f"{key!r} must be a list of at most {MAX_ROBOTS} rows")
    out = []
    for row in rows:
        if not isinstance(row, list) or len(row) != width:
            raise ProtocolError(f"{key!r} rows must be [robot, {width - 1} times], got {row!r}")
        cells = {"robot": row[0], **{f"t{k}": v for k, v in enumerate(row[1:])}}
        robot = get_int(cells, "robot", 0, MAX_ROBOTS - 1)
        out.append((robot, *(get_float(cells, f"t{k}", 0.0, MAX_TIME) for k in range(width - 1))))
    return tuple(out)


def get_lights(obj: dict[str, Any], n: int) -> dict[str, tuple[str, ...]]:
    """An observers' state's `lights` (n colour names) and `palette` (at most MAX_COLOURS), if
    it has them ({} if not)."""
    if "lights" not in obj:
        return {}
    lights, palette = obj.get("lights"), obj.get("palette")
    if (
        not isinstance(palette, list)
        or len(palette) > MAX_COLOURS
        or not all(isinstance(c, str) and len(c) <= 32 for c in palette)
        or not isinstance(lights, list)
        or len(lights) != n
        or not all(c in palette for c in lights)
    ):
        raise ProtocolError(f"'lights' must be {n} names of a palette of at most {MAX_COLOURS}")
    return {"lights": tuple(lights), "palette": tuple(palette)}
