"""`fatswarm.sweep(...)`: a grid of lock-step runs from Python, on the executors of `fatswarm
sweep` (the local pool, or a Dask cluster), as a pandas DataFrame of the CLI's CSV rows.

The keywords become the CLI's flags, read by its own parser and grid (`command.build_grid`); the
runs go through `pool.run_all` into a `RunTable` (the CSV file `out`, or one in a temporary
folder), and the frame is that table's rows of the grid as `pandas.read_csv` reads them.
"""

from __future__ import annotations

import argparse
import inspect
import io
import os
import tempfile
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Final

from fatswarm.deploy.engine.api import api_words
from fatswarm.deploy.engine.config import input_errors
from fatswarm.deploy.engine.notebook import EXTRA
from fatswarm.deploy.sweep.batch_flags import jobs_of
from fatswarm.deploy.sweep.command import Shipped, add_arguments, build_grid
from fatswarm.deploy.sweep.executor import ClusterError, open_workers
from fatswarm.deploy.sweep.grid import RIGID, SweepInputError, value_text
from fatswarm.deploy.sweep.table import header_line, make_row, row_key, row_line
from fatswarm.domain.robot_model import AXES, AXIS_NAMES
from fatswarm.domain.version import __version__

if TYPE_CHECKING:
    import pandas as pd


class SweepArgumentError(SweepInputError, TypeError):
    """A keyword of `fatswarm.sweep` of the wrong type (a ValueError, as every refused input,
    and a TypeError)."""


def sweep(
    n: int | Iterable[int] | str | None = None,
    *,
    seeds: int | Iterable[int] | str | None = None,
    algorithm: str | Iterable[str] | None = None,
    params: Mapping[str, object] | None = None,
    start: str | Iterable[str] | None = None,
    scheduler: str | Iterable[str] | None = None,
    non_rigid: float | str | Iterable[float | str | None] | None = None,
    crash: int | str | Iterable[int | str | None] | None = None,
    max_rounds: int | None = None,
    jobs: int | None = None,
    cluster: object | None = None,
    out: str | os.PathLike[str] | None = None,
    **model: object,
) -> pd.DataFrame:
    """Run a grid of lock-step runs as `fatswarm sweep` does (docs/sweep.md) and return its rows
    as a DataFrame: the columns and rows of the CLI's CSV (`pandas.read_csv` of it), one row per
    run of the grid in its order (seed by seed).

    Each keyword is the flag of the same name and takes what it takes, as Python values (None:
    the flag's default): `n` and `crash` a number, a list or range of them or a range text
    (`"4..16:4"`; `n` default 4, 8, 16); `seeds` a count K (seeds 0 to K-1; default 10), a list
    or range of seeds or a range text; `algorithm`, `start`, `scheduler` a name or a list
    (`scheduler` default: every one a sweep takes); `non_rigid` a delta, None (rigid) or a list
    of them; `params` the algorithms' parameters (`{"a": 4.0}`); `**model` one keyword per axis
    of the robot model (`AXES`: `sight=[6, None]`, `frames="chirality"`...), a value or a list.
    `jobs`: local worker processes (default one per core); `cluster`: a Dask scheduler's address
    or a `distributed.Client` (left open), as `--cluster`. `out`: the CSV to append to and
    resume from, as `--out` (its rows of this grid are not run again); None: none is kept.

    Raises a ValueError (SweepInputError, or one of the run's input errors) in these keywords'
    words for what the CLI refuses, SweepArgumentError for a keyword of the wrong type,
    ClusterError when the cluster cannot be used, WorkerDiedError when a worker vanished.
    Needs pandas (`fatswarm[notebook]`).
    """
    try:
        import pandas as pd  # optional (fatswarm[notebook]): only the frame needs it
    except ImportError:
        raise ImportError(f"fatswarm.sweep needs pandas: pip install 'fatswarm[{EXTRA}]'") from None
    # the lock-step engine and multiprocessing: `fatswarm.sweep` alone needs them here
    from fatswarm.deploy.sweep.pool import RunTable, run_all

    keywords = dict(
        n=n,
        seeds=seeds,
        algorithm=algorithm,
        start=start,
        scheduler=scheduler,
        non_rigid=non_rigid,
        crash=crash,
    )
    refused: tuple[type[Exception], ...] = (SweepInputError, *input_errors())
    try:
        args = _parsed(keywords, params, max_rounds, jobs, model)
        grid = build_grid(args)
        workers_wanted = jobs_of(args.jobs)
    except refused as exc:
        exc.args = (_keyword_words(str(exc)), *exc.args[1:])
        raise exc.with_traceback(None) from None
    with tempfile.TemporaryDirectory(prefix="fatswarm-sweep-") as folder:
        path = os.fspath(out) if out is not None else os.path.join(folder, "runs.csv")
        table = RunTable.open(path, models=grid.has_models)
        try:
            runs = grid.runs()
            present = table.keys()
            todo = [spec for spec in runs if spec.key() not in present]
            shipped = Shipped(todo)
            with open_workers(
                max(1, min(workers_wanted, len(todo))), cluster if todo else None
            ) as workers:
                run_all(
                    shipped.runs,
                    workers,
                    lambda spec, figures: table.append(
                        make_row(shipped.given(spec), figures, __version__)
                    ),
                    lambda: False,
                )
            by_key = {row_key(row): row for row in table.rows}
            text = header_line(table.columns) + "".join(
                row_line(by_key[spec.key()], table.columns) for spec in runs
            )
        finally:
            table.close()
    return pd.read_csv(io.StringIO(text))


def _parsed(
    keywords: Mapping[str, object],
    params: Mapping[str, object] | None,
    max_rounds: object,
    jobs: object,
    model: Mapping[str, object],
) -> argparse.Namespace:
    """The flags of `fatswarm sweep` the keywords say, read by its own parser."""
    argv: list[str] = []
    for name, value in keywords.items():
        if value is not None:
            argv += [_flag(name), _list(name, value)]
    if params is not None:
        if not isinstance(params, Mapping) or not all(isinstance(k, str) for k in params):
            raise SweepArgumentError(f"params must be a dict of names to values, got {params!r}")
        for key, value in params.items():
            argv += ["--param", f"{key}={_param_text(key, value)}"]
    for name, value in (("max_rounds", max_rounds), ("jobs", jobs)):
        if value is not None:
            if isinstance(value, bool) or not isinstance(value, int):
                raise SweepArgumentError(f"{name} must be an int or None, got {value!r}")
            argv += [_flag(name), str(value)]
    unknown = sorted(set(model) - set(AXIS_NAMES))
    if unknown:
        raise SweepArgumentError(f"sweep() got an unexpected keyword argument {unknown[0]!r}")
    for axis in AXES:
        if model.get(axis.name) is not None:  # None: the flag's default (sight's: unlimited)
            values = _values(model[axis.name])
            argv += [axis.flag, ",".join(_axis_text(axis.name, v) for v in values)]
    parser = argparse.ArgumentParser(prog="fatswarm.sweep", exit_on_error=False)
    add_arguments(parser)
    try:
        return parser.parse_args(argv)
    except argparse.ArgumentError as exc:  # a value of a type the flag does not take
        raise SweepArgumentError(str(exc)) from None


def _flag(name: str) -> str:
    return "-n" if name == "n" else "--" + name.replace("_", "-")


def _values(value: object) -> list[object]:
    """A keyword's values: a list, tuple or range as its items, anything else as one value."""
    return list(value) if isinstance(value, (list, tuple, range)) else [value]


def _list(name: str, value: object) -> str:
    """A list keyword as its flag's comma list (`seeds=[5]` is the seed 5, not a count)."""
    if name == "seeds" and isinstance(value, int) and not isinstance(value, bool):
        return str(value)  # a count, as `--seeds 10`
    texts = []
    for item in _values(value):
        if item is None and name == "non_rigid":
            texts.append(RIGID)
        elif item is None and name == "crash":
            texts.append("none")
        elif isinstance(item, bool) or not isinstance(item, (str, int, float)):
            raise SweepArgumentError(
                f"{name} takes a value or a list of them, got {type(item).__name__}"
            )
        elif name == "seeds" and isinstance(item, int):
            texts.append(f"{item}..{item}")
        else:
            texts.append(value_text(item))
    return ",".join(texts)


def _param_text(name: str, value: object) -> str:
    if not isinstance(value, (str, int, float, bool)):
        raise SweepArgumentError(
            f"params[{name!r}] must be a number, a bool or a str, got {value!r}"
        )
    return value_text(value)


def _axis_text(name: str, value: object) -> str:
    """An axis's value as its flag takes it (`Axis.text`; None: the word for no limit)."""
    axis = AXES[AXIS_NAMES.index(name)]
    if value is None and axis.unset:
        return axis.unset
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise SweepArgumentError(f"{name} takes a value or a list of them, got {value!r}")
    return str(value) if isinstance(value, str) else value_text(float(value))


def _keyword_words(message: str) -> str:
    """A refusal worded for the CLI's flags, worded for the keywords (`--max-rounds` is
    max_rounds); `fatswarm.run`'s rewording (`api_words`) with this function's keywords."""
    return api_words(message, KEYWORDS)


def _signature() -> inspect.Signature:
    """`sweep`'s signature with one keyword per axis of the robot model (`AXES`) in place of
    `**model` (default None: the flag's default), as `help(fatswarm.sweep)` and editors show."""
    shown = inspect.signature(sweep)
    kept = [p for p in shown.parameters.values() if p.kind is not p.VAR_KEYWORD]
    axes = [
        inspect.Parameter(a.name, inspect.Parameter.KEYWORD_ONLY, default=None, annotation="object")
        for a in AXES
    ]
    return shown.replace(parameters=[*kept, *axes])


sweep.__signature__ = _signature()  # type: ignore[attr-defined]
KEYWORDS: Final = frozenset(inspect.signature(sweep).parameters)  # the flags' words here

__all__ = ["KEYWORDS", "ClusterError", "SweepArgumentError", "sweep"]
