"""The flags and checks every command shares: which flags were given, the algorithm's flags, and the
refusal of a file or a duration that cannot be used (one line, RunInputError)."""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable
from typing import Any, Final

from fatswarm.deploy.engine.config import (
    RunInputError,
)
from fatswarm.domain.registry import DEFAULT
from fatswarm.domain.robot_model import AXES, AXIS_NAMES, Axis, ModelError, Value, axis_named


class Terminated(BaseException):
    """SIGTERM arrived: unwind like Ctrl-C (closing files, stopping children), then exit 143.

    A BaseException, as KeyboardInterrupt is, so that no `except Exception` swallows it.
    """


GIVEN: Final = "_given"  # the namespace attribute listing the flags given (`StoreGiven`)
ONCE: Final = "_once"  # the namespace attribute holding each single flag's first value (`Once`)

# flags whose default is not None, or whose value may be None when given (`--sight unlimited`)
TRACKED: Final = ("scheduler", "start", "algorithm", *AXIS_NAMES)


class StoreGiven(argparse.Action):
    """Store the value and note that the flag was given: --resume refuses a given flag that
    contradicts the record, while a default one never does (its default may be the record's)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        setattr(namespace, GIVEN, (*getattr(namespace, GIVEN, ()), self.dest))


class Once(argparse.Action):
    """A flag that takes one value: given again with another value, it is refused (one line
    naming the flag and both values) rather than the last one taken silently; the same value
    twice is fine. `refuse_repeats` makes every single-valued flag of a parser one."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        seen: dict[str, tuple[str | None, Any]] = dict(getattr(namespace, ONCE, {}))
        if self.dest in seen and seen[self.dest][1] != values:
            flag, first = seen[self.dest]
            said = f"{flag} {_shown(self.dest, first)}, then {option_string} "
            said += _shown(self.dest, values)
            raise argparse.ArgumentError(self, f"given twice ({said}): give it once")
        seen[self.dest] = (option_string, values)
        setattr(namespace, ONCE, seen)
        super().__call__(parser, namespace, values, option_string)  # the flag's own action


def _shown(dest: str, value: Any) -> str:
    """A flag's value as a user types it (a number axis's None: its word, `unlimited`)."""
    if dest in AXIS_NAMES:
        return axis_named(dest).label(value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def refuse_repeats(parser: argparse.ArgumentParser) -> None:
    """Make every flag of `parser` that stores one value (`store`, `StoreGiven`) a `Once`: the
    one place that refuses a flag repeated with two values (`--visibility opaque --visibility
    transparent`). Flags that gather (`append`) or count are left as they are."""
    for action in parser._actions:
        kind = type(action)
        if action.option_strings and kind in (argparse._StoreAction, StoreGiven):
            action.__class__ = type(f"Once{kind.__name__}", (Once, kind), {})


def flag_given(args: argparse.Namespace, dest: str) -> bool:
    """Whether the user gave the flag of `dest`: listed by `StoreGiven` for the TRACKED ones,
    else not None (their default)."""
    if dest in TRACKED:
        return dest in getattr(args, GIVEN, ())
    return getattr(args, dest, None) is not None


def given_flags(args: argparse.Namespace) -> dict[str, Any]:
    """The flags the user gave, by dest, with their values (`flag_given`: the TRACKED ones as
    `StoreGiven` listed them, the others not None, a `store_true` one when set): what --resume
    holds against the record's settings."""
    skip = {GIVEN, ONCE, "_argv", "_networked_flags"}
    return {
        dest: value
        for dest, value in vars(args).items()
        if dest not in skip and value is not False and value != [] and flag_given(args, dest)
    }


def check_start_flags(args: argparse.Namespace) -> None:
    """Refuse `--start` beside `--init` rather than ignore it: the file is the start
    (RunInputError)."""
    if getattr(args, "init", None) is not None and flag_given(args, "start"):
        raise RunInputError(
            f"--start {args.start} draws a random start, --init {args.init} gives one: "
            "pass one of them"
        )


def add_algorithm_arguments(p: argparse.ArgumentParser, *, params: bool = True) -> None:
    """`--algorithm` (and `--param`): which algorithm the robots run, with what parameters."""
    p.add_argument(
        "--algorithm",
        default=DEFAULT,
        metavar="NAME",
        action=StoreGiven,
        help=f"the algorithm every robot runs: a registered name (`fatswarm "
        f"algorithms` lists them; default {DEFAULT}) or module:attribute or "
        "path/to/file.py:attribute of your own (docs/algorithms.md)",
    )
    if params:
        p.add_argument(
            "--param",
            action="append",
            default=[],
            metavar="NAME=VALUE",
            help="set one of the algorithm's parameters (repeat for more; "
            "`fatswarm algorithms` lists them)",
        )


def add_robot_model_arguments(p: argparse.ArgumentParser, *, lists: bool = False) -> None:
    """The robot model's flags (docs/model.md), one per axis of `AXES`, unset by default (the
    paper's model), each value read by its axis (`Axis.parse`: `--sight unlimited` alike in run,
    sweep and hunt) and each help saying its default. With `lists` (sweep, hunt) each takes a
    comma-separated list of values: an axis of the grid (no empty item: `comma_list`)."""
    group = p.add_argument_group("robot model (docs/model.md; default: the paper's)")
    for axis in AXES:
        if lists:
            shown = ",".join(axis.words) if axis.words else f"{axis.metavar},..."
            default = f"'{axis.unset}' is no limit" if axis.unset else "default the first"
            if not axis.words and not axis.unset:
                default = f"default {axis.default:g}" if isinstance(axis.default, float) else ""
            group.add_argument(
                axis.flag,
                action="append",
                type=comma_list(axis.flag),
                default=None,
                metavar="LIST",
                help=f"{axis.help}; a comma-separated list is an axis ({shown}; {default})",
            )
        elif axis.words:
            group.add_argument(
                axis.flag,
                choices=axis.words,
                default=None,
                action=StoreGiven,
                help=with_default(axis),
            )
        else:
            group.add_argument(
                axis.flag,
                type=axis_value(axis),
                default=None,
                action=StoreGiven,
                metavar=axis.metavar,
                help=with_default(axis),
            )
    group.add_argument(
        "--record-views",
        action="store_true",
        help="each round line of the record names the robots each robot that Looked saw",
    )


def with_default(axis: Axis) -> str:
    """An axis's help, ending with its default as its flag takes it (unless it says it)."""
    if "(default" in axis.help or "; default" in axis.help:  # it says it: sight, noise
        return axis.help
    return f"{axis.help} (default {axis.text(axis.default)})"


def axis_value(axis: Axis) -> Callable[[str], Value]:
    """The `type=` of a number axis's flag: its text read by the axis (`Axis.parse`: `unlimited`
    is None for --sight), a refusal naming what it takes."""

    def parse(text: str) -> Value:
        try:
            return axis.parse(text)
        except ModelError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix(axis.flag + " ")) from None

    parse.__name__ = axis.name  # argparse's word for the value, were it to use it
    return parse


def comma_list(flag: str) -> Callable[[str], str]:
    """The `type=` of a flag that takes a comma-separated list: the text as given, refused when
    it is empty or has an empty item (`--frames ''`, `--frames y-axis,,`), which would otherwise
    run as if the flag were not there."""

    def check(text: str) -> str:
        if not text.strip():
            raise argparse.ArgumentTypeError("an empty list: give one value or more")
        if any(not item.strip() for item in text.split(",")):
            raise argparse.ArgumentTypeError(
                f"an empty item in {text!r}: give values separated by single commas"
            )
        return text

    check.__name__ = flag
    return check


def check_writable(flag: str, path: str) -> None:
    """Refuse `path` for `flag` if it is a directory or its directory is missing or read-only."""
    if os.path.isdir(path):
        raise RunInputError(f"{flag} {path} is a directory; name a file")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise RunInputError(
            f"{flag} {path}: the directory {folder} does not exist; create it first"
        )
    if not os.access(folder, os.W_OK | os.X_OK):
        raise RunInputError(f"{flag} {path}: cannot write in {folder}")


def check_seconds(flag: str, value: float, *, zero_ok: bool) -> None:
    """Refuse a duration flag that is not finite, or not > 0 (>= 0 if `zero_ok`)."""
    if not math.isfinite(value) or value < 0 or (value == 0 and not zero_ok):
        bound = ">= 0" if zero_ok else "> 0"
        raise RunInputError(f"{flag} must be a finite number of seconds {bound}, got {value:g}")
