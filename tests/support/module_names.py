"""One name per module: which of fatswarm's files a process loaded under a second name (world.record
beside fatswarm.world.record: two modules of one file, and an isinstance across them fails).
Shared by the unit test (the test process) and the integration test (the processes it starts)."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FOLDERS = ("fatswarm",)  # the checkout's folder of the package
# the checkout's top-level links into it (agent -> fatswarm/agent ...), kept for reading: from the
# checkout's root each is importable under its own name, which its __init__.py refuses
LINKS = ("agent", "coordinator", "world", "deploy")


def loaded_files(modules: Mapping[str, object]) -> dict[str, str]:
    """name -> the real path of its file, for every module that has a file (sys.modules); a module
    held under two names is one load (multiprocessing's `__mp_main__` is `__main__`): the first
    name in order is kept."""
    files, seen = {}, set()
    for name, module in sorted(modules.items()):
        file = getattr(module, "__file__", None)
        if isinstance(file, str) and id(module) not in seen:
            seen.add(id(module))
            files[name] = os.path.realpath(file)
    return files


def second_names(files: Mapping[str, str], homes: Iterable[Path] = ()) -> list[str]:
    """One line for each file of fatswarm loaded under a name other than its fatswarm.* one, or
    under two names (`__main__` counts as a name: `python -m X` and an import of X load X twice).
    A file is fatswarm's if a fatswarm.* module has it or it lies in the checkout's FOLDERS or in
    `homes` (an installed copy's folder)."""
    folders = [str(ROOT / folder) for folder in FOLDERS] + [str(h.resolve()) for h in homes]
    by_file: dict[str, list[str]] = {}
    for name, file in files.items():
        by_file.setdefault(file, []).append(name)
    problems = []
    for file, names in sorted(by_file.items()):
        ours = [n for n in names if n == "fatswarm" or n.startswith("fatswarm.")]
        if not ours and not any(file.startswith(folder + os.sep) for folder in folders):
            continue
        if len(names) > 1 or (not ours and names != ["__main__"]):
            problems.append(f"{file}: loaded as {', '.join(sorted(names))}")
    return problems
