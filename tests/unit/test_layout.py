"""One name per module: the packages live under fatswarm/ (the checkout's top-level agent/,
coordinator/, world/ and deploy/ are links into it, for reading), every module loads under its
fatswarm.* name alone, and every folder of modules is a package, so the wheel finds it."""

from __future__ import annotations

import importlib
import importlib.util
import os
import pkgutil
import sys
from pathlib import Path

import pytest
from module_names import LINKS, ROOT, loaded_files, second_names  # tests/support

import fatswarm

TOP_LEVEL = list(LINKS)


def test_every_folder_of_modules_is_a_package_that_setuptools_finds() -> None:
    # [tool.setuptools.packages.find] skips a folder without __init__.py: its modules would be
    # missing from the wheel, though they import from the checkout (as a namespace package)
    package = ROOT / "fatswarm"
    # the top-level names are links into fatswarm/, which holds the code itself
    assert [(ROOT / f).resolve() for f in TOP_LEVEL] == [package / f for f in TOP_LEVEL]
    assert not any((package / f).is_symlink() for f in TOP_LEVEL)
    folders = [
        Path(folder)
        for folder, _, files in os.walk(package)
        if any(f.endswith(".py") for f in files)
    ]
    assert len(folders) >= 14
    missing = [str(f) for f in folders if not (f / "__init__.py").is_file()]
    assert not missing, f"folders of modules without __init__.py: {missing}"


@pytest.mark.parametrize("folder", TOP_LEVEL)
def test_a_top_level_folder_refuses_to_load_under_its_own_name(folder: str) -> None:
    # as `import world` from the checkout's root would load it
    spec = importlib.util.spec_from_file_location(folder, ROOT / folder / "__init__.py")
    assert spec is not None and spec.loader is not None
    with pytest.raises(ImportError, match=rf"^import fatswarm\.{folder}, not {folder}$"):
        spec.loader.exec_module(importlib.util.module_from_spec(spec))


def test_the_tests_load_every_module_of_fatswarm_under_one_name() -> None:
    for module in pkgutil.walk_packages(fatswarm.__path__, "fatswarm."):
        importlib.import_module(module.name)
    assert not second_names(loaded_files(sys.modules))


def test_a_second_name_is_seen() -> None:
    # the check itself: world.record beside fatswarm.world.record, and __main__ beside its name
    record = str(ROOT / "fatswarm" / "world" / "record.py")
    assert second_names({"fatswarm.world.record": record, "world.record": record}) == [
        f"{record}: loaded as fatswarm.world.record, world.record"
    ]
    assert second_names({"world.record": record}) == [f"{record}: loaded as world.record"]
    parts = str(ROOT / "fatswarm" / "deploy" / "net" / "parts.py")
    assert second_names({"__main__": parts}) == []
    assert len(second_names({"__main__": parts, "fatswarm.deploy.net.parts": parts})) == 1
    elsewhere = str(Path("/elsewhere/fatswarm/world/record.py"))
    assert second_names({"world.record": elsewhere}, [Path("/elsewhere/fatswarm")])
    assert not second_names({"record": str(ROOT / "tests" / "support" / "record.py")})
