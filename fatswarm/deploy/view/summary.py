"""How a finished run ended and the summary every kind of run prints: text, or one JSON object."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final, TextIO

from fatswarm.domain import figures
from fatswarm.domain.outcome import ExitCode, Status, exit_code_for
from fatswarm.domain.robot_model import PAPER_WORD, ModelError, RobotModel, short_of_header
from fatswarm.domain.words import counted as counted  # the one plural (re-exported)
from fatswarm.domain.words import unit as unit  # the one word for what a run counts

WIDTH: Final = 80  # columns of a summary line, where it can be broken (the smallest terminal)

if TYPE_CHECKING:
    from fatswarm.world.record import RoundEntry


def print_outcome(
    outcome: Outcome | None,
    code: int,
    out: TextIO,
    *,
    as_json: bool,
    record: str | None,
    svg: str | None,
) -> None:
    """Print the end of a run to `out`: the text summary and the files written, or (`as_json`)
    one JSON object. `outcome` None: the run ended without a result in its record."""
    if as_json:
        print(summary_json(outcome, code, record=record, svg=svg), file=out)
        return
    if outcome is not None:
        print(summary(outcome), file=out)
    if record:
        print(f"record: {record}", file=out)
    if svg:
        print(f"svg: {svg}", file=out)


@dataclass(frozen=True, slots=True)
class Outcome:
    """How a finished run ended (lockstep result or networked record): what the summary says."""

    status: Status  # what ended the run
    rounds: int
    collisions: int  # robots stopped at contact, over the whole run
    n: int
    a: float | None  # the paper's side, None for an algorithm without one
    seed: int | None
    scheduler: str
    epochs: int | None  # None when the record does not say
    moves: int
    total_distance: float
    algorithm: str = "uniform-circle"
    params: dict[str, Any] = dataclasses.field(default_factory=dict)
    time: float | None = None  # async models: the virtual time the run ended at
    model: str | None = None  # the robot model as flags, when it is not the paper's
    model_label: str = PAPER_WORD  # the robot model in one word (`RobotModel.short`)
    assumption: str | None = None  # the record header's line: frames outside the algorithm's
    crashes: tuple[tuple[int, int], ...] = ()  # --crash: (robot, round or cycle it crashed in)
    # the run's figures that follow from the positions (fatswarm.domain.figures), by name
    derived: Mapping[str, figures.FigureValue] = dataclasses.field(default_factory=dict)

    def noted(self, header: Mapping[str, Any]) -> Outcome:
        """This outcome with the `model` and `assumption` a record header's fields give (its
        `Header.extra`, or the JSON header line): the model as its flags when it is not the
        paper's, and the header's `assumption` line."""
        model, assumption = model_notes(header)
        label = model_label(header)
        return dataclasses.replace(self, model=model, assumption=assumption, model_label=label)


def model_label(header: Mapping[str, Any]) -> str:
    """The robot model of a record header's fields in one word (`RobotModel.short`: `paper`,
    `opaque+sight5`), `unreadable` for a `model` no run writes."""
    return short_of_header(header.get("model"))


def model_notes(header: Mapping[str, Any]) -> tuple[str | None, str | None]:
    """`model` and `assumption` of an `Outcome` from a record header's fields (None: not there,
    or the paper's model)."""
    try:
        robot_model = RobotModel.from_header(header.get("model"))
    except ModelError as exc:
        model: str | None = f"unreadable ({exc})"
    else:
        model = None if robot_model.is_paper else robot_model.describe()
    line = header.get("assumption")
    assumption = " ".join(line.split()) if isinstance(line, str) else ""  # one line, whatever
    return model, assumption or None


def side_of(values: Any) -> float | None:
    """The parameter `a` (the paper's side), None for an algorithm without one."""
    a = values.get("a")
    return float(a) if isinstance(a, (int, float)) and not isinstance(a, bool) else None


def exit_code(outcome: Outcome) -> ExitCode:
    """The exit code of `fatswarm run` for this outcome (see EXIT_CODES_HELP)."""
    return exit_code_for(outcome.status, outcome.collisions)


def verdict(outcome: Outcome) -> str:
    """One line: formed or not, in how many rounds (ended cycles under an async model), and
    whether robots collided on the way; a run stopped by its cap says which cap; a run whose
    algorithm failed (computes that raised) says how often and the first failure, under every
    scheduler alike."""
    return ended(outcome) + failed_text(outcome.derived)


def failed_text(values: Mapping[str, figures.FigureValue]) -> str:
    """`; the algorithm failed 37 times, first robot 2 in round 3: ViewError: ...` from the run's
    `failures` and `first_failure` figures ("" when no compute failed)."""
    k, first = values.get("failures"), values.get("first_failure")
    if not isinstance(k, int) or k <= 0:
        return ""
    return f"; the algorithm failed {counted(k, 'time')}" + (f", first {first}" if first else "")


def ended(outcome: Outcome) -> str:
    """The verdict without the algorithm's failures."""
    k, word = outcome.collisions, unit(outcome.scheduler)
    rounds = counted(outcome.rounds, word)
    collisions = counted(k, "collision")
    if outcome.status == Status.FORMED:
        if k == 0:
            return f"formed in {rounds}, collision-free"
        return (
            f"formed in {rounds}, but with {collisions}: not the collision-free "
            "formation the paper guarantees"
        )
    if outcome.status == Status.STALLED:
        head = f"not formed: stalled after {rounds}"
    elif outcome.status == Status.MAX_ROUNDS:
        head = f"not formed: stopped at the {word} limit ({rounds})"
    else:
        head = f"not formed: {outcome.status} after {rounds}"
    return head if k == 0 else f"{head}, with {collisions}"


def summary(outcome: Outcome) -> str:
    """The summary both kinds of run print at the end: the verdict, the run (its robot model in
    one word), its figures on lines of at most WIDTH columns (and the robots the crash adversary
    crashed, when it did)."""
    o = outcome
    epochs = "?" if o.epochs is None else str(o.epochs)
    values = o.params or ({"a": o.a} if o.algorithm == "uniform-circle" else {})
    shown = "".join(
        f" {k}={v:g}" if isinstance(v, float) else f" {k}={v}" for k, v in values.items()
    )
    named = "" if o.algorithm == "uniform-circle" else f" algorithm={o.algorithm}"
    return (
        f"{verdict(o)}\n"
        f"n={o.n}{named}{shown} seed={'?' if o.seed is None else o.seed} "
        f"scheduler={o.scheduler} model={o.model_label}\n"
        + broken(
            [
                f"{unit(o.scheduler)}s {o.rounds}",
                f"epochs {epochs}",
                f"moves {o.moves} ({o.moves / o.n:.2f} per robot)",
                f"total distance {o.total_distance:.3f}",
                f"collisions {o.collisions}",
                *derived_parts(o.derived),
                *([] if o.time is None else [f"virtual time {o.time:.3f}"]),
            ]
        )
        + ("" if not o.crashes else f"\n{crashes_text(o.crashes, o.scheduler)}")
        + ("" if o.model is None else f"\nmodel: {o.model}")
        + ("" if o.assumption is None else f"\n{o.assumption}")
    )


def broken(parts: Iterable[str], width: int = WIDTH) -> str:
    """`parts` two spaces apart, on as many lines of at most `width` columns as they take (a
    part longer than that alone on its line)."""
    lines: list[str] = []
    for part in parts:
        if lines and len(lines[-1]) + 2 + len(part) <= width:
            lines[-1] += "  " + part
        else:
            lines.append(part)
    return "\n".join(lines)


def derived_parts(values: Mapping[str, figures.FigureValue]) -> list[str]:
    """`min gap 0.412`: the run's derived figures shown in the summary, each with its words
    (one it does not know, or that does not apply, is left out; a text, such as the first
    failure, is the verdict's to say)."""
    return [
        f"{f.words} {figures.shown(value)}"
        for f in figures.derived_figures()
        if figures.Place.SUMMARY in f.places
        and f.type is not str
        and (value := values.get(f.name)) is not None
    ]


def crashes_text(crashes: Iterable[tuple[int, int]], scheduler: str) -> str:
    """ "crashed (--crash): robot 3 in round 5, robot 0 in round 9": who the crash adversary
    crashed, and when (under an async model, the ended cycle its crash first counts in)."""
    word = unit(scheduler)
    listed = ", ".join(
        f"robot {robot} in {word} {when}"
        for robot, when in sorted(crashes, key=lambda c: (c[1], c[0]))
    )
    return f"crashed (--crash): {listed}"


def crashes_in(rounds: Iterable[RoundEntry]) -> tuple[tuple[int, int], ...]:
    """(robot, round) of every robot a record's round lines say the crash adversary crashed
    (their `crash` key; an async record's: the first cycle line after the crash, `crash_at`
    saying when)."""
    found: list[tuple[int, int]] = []
    for entry in rounds:
        robots = entry.extra.get("crash")
        if isinstance(robots, list):
            found += [(int(r), entry.round) for r in robots]
    return tuple(found)


def summary_json(
    outcome: Outcome | None, code: int, *, record: str | None = None, svg: str | None = None
) -> str:
    """The summary as one JSON object (`--json`): the outcome's figures, verdict, exit code and
    the files written; status "unfinished" (and no figures) when the run ended without a result."""
    fields: dict[str, Any] = {"status": "unfinished"}
    if outcome is not None:
        fields = {**dataclasses.asdict(outcome), "verdict": verdict(outcome)}
        del fields["derived"]  # each at the top level, as the other figures
        fields.update(figures.summary_values(outcome.derived))
        for key in ("model", "assumption", "crashes"):  # only when there: JSON as before
            if not fields[key]:
                del fields[key]
            elif key == "crashes":
                fields[key] = [{"robot": r, unit(outcome.scheduler): k} for r, k in fields[key]]
    fields.update(exit_code=int(code), record=record or None, svg=svg or None)
    return json.dumps(fields, allow_nan=False)
