"""The whole algorithm docs/algorithms.md shows, and its tests, as the page has them (for the
tests that run them: tests/unit/test_algorithms_doc.py, tests/integration/
test_algorithms_doc_swarm.py)."""

from __future__ import annotations

import re
from pathlib import Path

DOC = Path(__file__).resolve().parents[2] / "docs" / "algorithms.md"
HEADING = "### A whole algorithm to start from"


def page_blocks() -> tuple[str, str]:
    """The section's two Python blocks: the algorithm (`huddle.py`) and its tests."""
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index(HEADING) :]
    section = section[: section.index("\n### ", len(HEADING))]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 2, "the section shows huddle.py and test_huddle.py"
    return blocks[0], blocks[1]
