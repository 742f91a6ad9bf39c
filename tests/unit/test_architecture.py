"""The house imports one way: every import-linter contract in pyproject.toml holds. Checked in this
process (no cache written), on the fatswarm this interpreter finds: the checkout's or an installed
copy, the same code."""

from __future__ import annotations

from pathlib import Path

from importlinter import api  # importing it configures import-linter (its readers of config)
from importlinter.application import use_cases
from importlinter.application.output import console

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"


def test_every_import_contract_in_pyproject_holds() -> None:
    assert api.read_configuration(str(PYPROJECT))["contracts_options"], "no contract to check"
    # lint-imports itself, but for its command line's changes to sys.path and logging
    with console.capture() as report:
        kept = use_cases.lint_imports(str(PYPROJECT), cache_dir=None, no_logo=True)
    assert kept, report.get()
