"""The house imports one way: every import-linter contract in pyproject.toml holds. Checked in this
process (no cache written), on the fatswarm this interpreter finds: the checkout's or an installed
copy, the same code. Two rules import-linter cannot say are checked here: the shared layer's
imports as an allow-list, and that every module of the world is named a core or a shell."""

from __future__ import annotations

import ast
import pkgutil
import sys
import tomllib
from pathlib import Path

from importlinter import api  # importing it configures import-linter (its readers of config)
from importlinter.application import use_cases
from importlinter.application.output import console

import fatswarm.domain
import fatswarm.world

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"
# What the shared layer may import: the standard library, numpy, msgpack and itself.
DOMAIN_MAY_IMPORT = frozenset(sys.stdlib_module_names) | {"numpy", "msgpack"}
# The world's shells (I/O): the Zenoh process, the durable log, the record's writer and reader,
# the FIFO from Zenoh's callbacks; every other world module is a core one, without I/O.
WORLD_SHELLS = frozenset({"service", "journal", "record", "record_read", "inbox"})
CORE_CONTRACT = "The world's core modules do no I/O"


def test_every_import_contract_in_pyproject_holds() -> None:
    assert api.read_configuration(str(PYPROJECT))["contracts_options"], "no contract to check"
    # lint-imports itself, but for its command line's changes to sys.path and logging
    with console.capture() as report:
        kept = use_cases.lint_imports(str(PYPROJECT), cache_dir=None, no_logo=True)
    assert kept, report.get()


def imports_of(path: Path, package: str) -> set[str]:
    """The absolute name of every module `path` imports (at its top, in a function, or for type
    checkers only), relative imports resolved against `package`."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level else ""
            names.add(".".join(filter(None, [base, node.module or ""])))
    return names


def test_the_shared_layer_imports_only_the_standard_library_numpy_msgpack_and_itself() -> None:
    folder = Path(fatswarm.domain.__file__).parent
    outside = {
        f"{path.name}: {name}"
        for path in sorted(folder.glob("*.py"))
        for name in imports_of(path, "fatswarm.domain")
        if name.split(".")[0] not in DOMAIN_MAY_IMPORT
        and not (name == "fatswarm.domain" or name.startswith("fatswarm.domain."))
    }
    assert not outside, sorted(outside)


def test_the_allow_list_check_sees_every_kind_of_import(tmp_path: Path) -> None:
    code = "import zenoh\nfrom rich.text import Text\ndef f():\n    from . import seam\n"
    (tmp_path / "m.py").write_text(code)
    assert imports_of(tmp_path / "m.py", "fatswarm.domain") == {
        "zenoh",
        "rich.text",
        "fatswarm.domain",
    }


def test_every_world_module_is_a_shell_or_a_core_module_under_the_contract() -> None:
    contracts = tomllib.loads(PYPROJECT.read_text())["tool"]["importlinter"]["contracts"]
    (core,) = [c for c in contracts if c["name"].startswith(CORE_CONTRACT)]
    modules = {m.name for m in pkgutil.iter_modules(fatswarm.world.__path__)}
    assert modules >= WORLD_SHELLS, "a shell named here is gone: update WORLD_SHELLS"
    assert sorted(core["source_modules"]) == sorted(
        f"fatswarm.world.{m}" for m in modules - WORLD_SHELLS
    ), "name each world module as a core one (pyproject.toml) or a shell (WORLD_SHELLS)"
