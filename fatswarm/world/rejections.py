"""Refused and dropped messages, counted by kind, and what to say of them: the first of a kind at
once, then at most one line per kind every `every_s` seconds with how many came since, so that a
flood of rogue messages costs a few log lines, not one each. No I/O: the shell passes `now` and
logs the lines it is handed.
"""

from __future__ import annotations

import math
from collections import Counter

SAY_EVERY_S = 5.0  # a kind is said at most this often


class Rejections:
    """Counts by kind (`totals`: the whole life of the process) and the lines due about them."""

    def __init__(self, every_s: float = SAY_EVERY_S) -> None:
        self.every_s = every_s
        self.totals: Counter[str] = Counter()
        self._unsaid: Counter[str] = Counter()  # kind -> counted since it was last said
        self._last: dict[str, str] = {}  # kind -> the detail of the last one not said yet
        self._said_at: dict[str, float] = {}  # kind -> when it was last said

    def count(self, kind: str, detail: str, now: float, times: int = 1) -> str | None:
        """Count `times` messages of `kind` (`detail`: what the last one was); the line to log
        now, or None if this kind was said less than `every_s` ago (it is said later)."""
        self.totals[kind] += times
        self._unsaid[kind] += times
        self._last[kind] = detail
        if now - self._said_at.get(kind, -math.inf) < self.every_s:
            return None
        return self._say(kind, now)

    def due(self, now: float) -> list[str]:
        """The lines of the kinds counted since they were last said, `every_s` ago or more."""
        return [
            self._say(kind, now)
            for kind in sorted(self._unsaid)
            if now - self._said_at.get(kind, -math.inf) >= self.every_s
        ]

    def flush(self, now: float) -> list[str]:
        """The lines of every kind counted since it was last said (at the end)."""
        return [self._say(kind, now) for kind in sorted(self._unsaid)]

    def _say(self, kind: str, now: float) -> str:
        times, detail = self._unsaid.pop(kind), self._last.pop(kind)
        self._said_at[kind] = now
        total = self.totals[kind]
        if times == total == 1:
            return f"rejected ({kind}): {detail}"
        return f"rejected ({kind}): {detail} [{times:,} since it was last said, {total:,} in all]"


def tally(counts: Counter[str] | dict[str, int]) -> str:
    """`counts` in one phrase, most first: "look-garbage 2,000, move-wrong-robot 1,000"."""
    ranked = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))
    return ", ".join(f"{kind} {count:,}" for kind, count in ranked if count)


__all__ = ["SAY_EVERY_S", "Rejections", "tally"]
