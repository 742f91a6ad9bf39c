"""docs/notebook.md runs as written: its cells in order in one namespace, as Jupyter would (the
last expression of a cell is what it shows; a `text` block after a cell is that, as text), its
`!fatswarm ...` lines through the command's own entry point, in this process."""

from __future__ import annotations

import ast
import builtins
import importlib.util
import re
import shlex
import types
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.sweep import pool
from fatswarm.deploy.sweep.grid import RunSpec
from fatswarm.deploy.sweep.table import RunFigures

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "notebook.md"
FENCE = re.compile(r"^```(\w+)\n(.*?)^```", re.DOTALL | re.MULTILINE)


def cells() -> list[tuple[str, str | None]]:
    """Every python block of the page, with the text block that shows its output (the next
    block, when it is a `text` one), if any."""
    out: list[tuple[str, str | None]] = []
    for kind, body in FENCE.findall(DOC.read_text()):
        if kind == "python":
            out.append((body, None))
        elif kind == "text":
            assert out and out[-1][1] is None, "a text block shows the output of the cell before"
            out[-1] = (out[-1][0], body)
    return out


def shell(line: str) -> None:
    """A cell's `!fatswarm ARGS` line: the command, in this process; it must exit 0."""
    words = shlex.split(line)
    assert words[0] == "fatswarm", f"only !fatswarm lines run here, got {line!r}"
    assert cli.main(words[1:]) == 0, line


def as_python(code: str) -> str:
    """A cell with its `!` lines as calls of `shell`."""
    return "\n".join(
        f"__shell__({line[1:]!r})" if line.startswith("!") else line for line in code.splitlines()
    )


def run_cell(code: str, namespace: dict[str, object]) -> object:
    """Run a cell; what Jupyter would show: its last expression's value (None without one)."""
    tree = ast.parse(as_python(code))
    last = tree.body[-1] if tree.body else None
    if not isinstance(last, ast.Expr):
        exec(compile(tree, str(DOC), "exec"), namespace)
        return None
    tree.body.pop()
    exec(compile(tree, str(DOC), "exec"), namespace)
    return eval(compile(ast.Expression(last.value), str(DOC), "eval"), namespace)


def inline_run_all(
    todo: Sequence[RunSpec],
    jobs: int,
    on_done: Callable[[RunSpec, RunFigures], None],
    stop: Callable[[], bool],
) -> bool:
    """The sweep's pool, in this process (unit tests start no process)."""
    for spec in todo:
        on_done(spec, pool.run_spec(spec))
    return True


def notebook_namespace() -> dict[str, object]:
    """The cells' globals: `!` lines' `__shell__`, and `from IPython.display import Image` as
    Jupyter has it (a stand-in for these cells alone when IPython is not installed)."""
    if importlib.util.find_spec("IPython") is not None:
        return {"__shell__": shell, "__name__": "__main__"}
    display = types.ModuleType("IPython.display")
    display.Image = Path  # type: ignore[attr-defined]

    def cell_import(name: str, *args: Any, **kwargs: Any) -> Any:
        return display if name == "IPython.display" else builtins.__import__(name, *args, **kwargs)

    cell_builtins = {**vars(builtins), "__import__": cell_import}
    return {"__shell__": shell, "__name__": "__main__", "__builtins__": cell_builtins}


def test_the_page_has_every_part_of_a_session() -> None:
    code = "\n".join(c for c, _ in cells())
    for part in ("fatswarm.run(", "read_record(", "positions_at(", "to_dataframe()"):
        assert part in code, part
    assert "!fatswarm plot run.jsonl run.gif" in code and "pd.read_csv(" in code


def test_every_cell_of_the_notebook_page_runs_as_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pd = pytest.importorskip("pandas")
    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(pool, "run_all", inline_run_all)
    namespace = notebook_namespace()
    for code, shown in cells():
        value = run_cell(code, namespace)
        if shown is not None:
            assert repr(value) == shown.strip(), code
            assert hasattr(value, "_repr_svg_"), code  # Jupyter draws it
    assert (tmp_path / "run.gif").stat().st_size > 0
    assert (tmp_path / "runs.csv").exists()
    sweep = namespace["sweep"]
    assert isinstance(sweep, pd.DataFrame)
    assert len(sweep) == 12 and set(sweep["status"]) == {"formed"}
