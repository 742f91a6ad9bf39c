"""The record's lines declared: the round line's fields and the result line's head, each with its
JSON Schema, from which docs/record.schema.json's round and result parts are generated together with
the run's figures (fatswarm.domain.figures). `python -m fatswarm.domain.record_lines` regenerates
the file; a test checks it is up to date."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Final

from fatswarm.domain.figures import Place, derived_figures, place


@dataclass(frozen=True, slots=True)
class LineField:
    """One field of the record's round line: its JSON Schema (`schema`, without the help)."""

    name: str
    help: str
    schema: Mapping[str, Any]
    required: bool = False


_SOME: Final = {"$ref": "#/$defs/someRobots"}
_TIME: Final = {"$ref": "#/$defs/number", "minimum": 0}

# The fields of the record's round line, in the schema's order (the writer keeps a line's own).
ROUND_FIELDS: tuple[LineField, ...] = (
    LineField("type", "", {"const": "round"}, True),
    LineField(
        "round", "Round number: 1, 2, ... consecutive.", {"type": "integer", "minimum": 1}, True
    ),
    LineField(
        "active",
        "The robots the scheduler activated.",
        {"$ref": "#/$defs/robots", "minItems": 1},
        True,
    ),
    LineField(
        "moves",
        "The applied paths (robots with a non-empty path), by robot number.",
        {"type": "array", "items": {"$ref": "#/$defs/move"}},
        True,
    ),
    LineField(
        "positions", "Every robot's position after the round.", {"$ref": "#/$defs/points"}, True
    ),
    LineField(
        "collisions",
        "Contacts that stopped a mover.",
        {"type": "array", "items": {"$ref": "#/$defs/collision"}},
        True,
    ),
    LineField(
        "timed_out",
        "Active robots whose move did not arrive in time (their agent was slow or gone; a "
        "compute that failed is `failed`).",
        _SOME,
    ),
    LineField(
        "crashed",
        "Robots that count as crashed from this round (their agent gone for 4n rounds, at "
        "least 10).",
        _SOME,
    ),
    LineField("recovered", "Crashed robots whose agent came back.", _SOME),
    LineField("cut", "--non-rigid: robots whose move the adversary stopped short.", _SOME),
    LineField(
        "crash",
        "--crash: robots the crash adversary crashes in this round, for good (async models: "
        "since the line before; `crash_at` says when).",
        _SOME,
    ),
    LineField("look", "Async models: the virtual time of the Look this cycle began with.", _TIME),
    LineField(
        "start",
        "Async models: the virtual time the move starts (robots move at unit speed from then "
        "on); the Look's time for a cycle that stays.",
        _TIME,
    ),
    LineField(
        "end",
        "Async models: the virtual time the cycle ends (its move's end, or its Look when it "
        "stays); positions are every robot's at this time.",
        _TIME,
    ),
    LineField(
        "origin",
        "Async models: where the move starts (the robot's position at its Look).",
        {"$ref": "#/$defs/point"},
    ),
    LineField(
        "crash_at",
        "Async models with --crash: the virtual time at which each robot of `crash` crashed (at "
        "its Look, which it never made), keyed by robot number as a string.",
        {
            "type": "object",
            "propertyNames": {"pattern": "^(0|[1-9][0-9]*)$"},
            "additionalProperties": _TIME,
            "minProperties": 1,
        },
    ),
    LineField(
        "lights",
        "Luminous algorithms: every robot's colour at this line (rounds: after the round's moves "
        "started; async: at end), robot i at index i (n of them).",
        {"type": "array", "items": {"$ref": "#/$defs/colour"}, "minItems": 1},
    ),
    LineField(
        "views",
        "--record-views: for each robot that Looked in the round (async: the cycle's robot), "
        "keyed by its number as a string, the robots it was shown, increasing (possibly none).",
        {
            "type": "object",
            "propertyNames": {"pattern": "^(0|[1-9][0-9]*)$"},
            "additionalProperties": {"$ref": "#/$defs/robots"},
        },
    ),
    LineField(
        "failed",
        "Active robots whose compute failed (the algorithm raised), keyed by robot number as a "
        "string: why, one line (`Type: message`); each stayed. Written only when one did.",
        {
            "type": "object",
            "propertyNames": {"pattern": "^(0|[1-9][0-9]*)$"},
            "additionalProperties": {"type": "string", "maxLength": 200},
            "minProperties": 1,
        },
    ),
)
ROBOT_LISTS: Final = ("timed_out", "crashed", "recovered", "cut", "crash")  # written if not empty
ASYNC_TIMES: Final = ("look", "start", "end", "origin")  # an async cycle's line has all four

# The result line: the fields before its figures, each with its schema.
RESULT_HEAD: tuple[LineField, ...] = (
    LineField("type", "", {"const": "result"}, True),
    LineField("status", "", {"enum": ["formed", "stalled", "max_rounds"]}, True),
    LineField("rounds", "Rounds committed.", {"type": "integer", "minimum": 0}, True),
    LineField("positions", "Final positions.", {"$ref": "#/$defs/points"}, True),
)


def _property(help_text: str, schema: Mapping[str, Any]) -> dict[str, Any]:
    return {"description": help_text, **schema} if help_text else dict(schema)


def record_schema(template: Mapping[str, Any]) -> dict[str, Any]:
    """docs/record.schema.json: `template` (the file as it is) with the round and result lines'
    properties and required keys generated from ROUND_FIELDS, RESULT_HEAD and FIGURES."""
    schema: dict[str, Any] = json_copy(template)
    line = schema["$defs"]["round"]
    line["properties"] = {f.name: _property(f.help, f.schema) for f in ROUND_FIELDS}
    line["required"] = [f.name for f in ROUND_FIELDS if f.required]
    line["dependentRequired"] = {
        key: [other for other in ASYNC_TIMES if other != key] for key in ASYNC_TIMES
    }
    result = schema["$defs"]["result"]
    head = {f.name: _property(f.help, f.schema) for f in RESULT_HEAD}
    result["properties"] = head | {
        f.name: _property(f.help, f.schema) for f in place(Place.RESULT_LINE) if f.name not in head
    }
    result["required"] = [f.name for f in RESULT_HEAD if f.required]
    derived_help = ", ".join(f.name for f in derived_figures())
    result["description"] = (
        "The last line: how the run ended (absent while it runs, or if it never ended). "
        f"Figures that follow from the round lines ({derived_help or 'none'}) are not written: "
        "readers derive them (fatswarm.domain.figures)."
    )
    return schema


def json_copy(obj: Any) -> Any:
    """A deep copy of JSON-like data (dicts and lists copied, keeping key order)."""
    if isinstance(obj, Mapping):
        return {k: json_copy(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_copy(v) for v in obj]
    return obj


def schema_text(schema: Mapping[str, Any]) -> str:
    """The schema file's text: two-space JSON, one trailing newline."""
    return json.dumps(schema, indent=2, ensure_ascii=False) + "\n"


def write_record_schema(path: str) -> bool:
    """Regenerate the schema file at `path` from the declaration (its other parts kept); True if
    it changed. A file that already says what the declaration generates (as JSON: its layout is
    free, so hand edits of the header's part stay as they are written) is left alone; one that
    does not is written again, two-space JSON. `python -m fatswarm.domain.record_lines` runs it."""
    with open(path, encoding="utf-8") as fh:
        old = json.loads(fh.read())
    new = record_schema(old)
    if new == old:
        return False
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(schema_text(new))
    return True


__all__ = [
    "ASYNC_TIMES",
    "RESULT_HEAD",
    "ROBOT_LISTS",
    "ROUND_FIELDS",
    "LineField",
    "json_copy",
    "record_schema",
    "schema_text",
    "write_record_schema",
]


if __name__ == "__main__":
    import sys

    for target in sys.argv[1:] or ["docs/record.schema.json"]:
        print(f"{target}: {'regenerated' if write_record_schema(target) else 'up to date'}")
