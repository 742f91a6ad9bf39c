"""What a robot is shown (a Look: its view, and its colours for a luminous algorithm), and the
Computes' answers compared within tolerance and shown as a message writes them."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from fatswarm.domain.frames import Frame
from fatswarm.domain.lights import Glance
from fatswarm.domain.path import Arc, Line, Path, Points

TOLERANCE_REL: Final = 1e-9  # paths equal within this, relative to the view's extent
SWEEP_TOLERANCE: Final = 1e-9  # radians


@dataclass(frozen=True, slots=True, eq=False)
class Look:
    """One robot's view: the others' centres relative to it, in its frame ((k, 2)), and for a
    luminous algorithm the colours it is shown (`glance.others` lined up with the rows)."""

    view: Points
    glance: Glance | None = None

    @property
    def n(self) -> int:
        return len(self.view) + 1

    def without(self, row: int) -> Look:
        """The look with robot `row` gone (its colour too)."""
        return self.permuted([i for i in range(len(self.view)) if i != row])

    def permuted(self, order: Sequence[int]) -> Look:
        """The look with its rows (and their colours) in `order`."""
        glance = self.glance
        if glance is not None and glance.others is not None:
            glance = Glance(glance.own, tuple(glance.others[i] for i in order))
        return Look(np.array(self.view[list(order)], dtype=np.float64).reshape(-1, 2), glance)

    def in_frame(self, frame: Frame) -> Look:
        """The same look in another private frame (the colours stay with their rows)."""
        return Look(frame.to_local(self.view), self.glance)

    def rounded(self, places: int) -> Look:
        return Look(np.round(self.view, places) + 0.0, self.glance)

    def configuration(self) -> Points:
        """(n, 2): the robot at the origin, then the others."""
        return np.vstack([np.zeros((1, 2)), self.view])

    def scale(self) -> float:
        return max(1.0, float(np.abs(self.view).max())) if len(self.view) else 1.0

    def describe(self) -> str:
        rows = ", ".join(f"[{_num(x)}, {_num(y)}]" for x, y in self.view)
        text = f"[{rows}]"
        if self.glance is not None:
            text += f", own colour {self.glance.own!r}, their colours {self.glance.others!r}"
        return text


Answer = tuple[Path, object]  # a Compute's path, and the colour of a luminous one (else None)


def _num(value: float) -> str:
    return repr(float(value) + 0.0)


def show_path(path: Path) -> str:
    if not path:
        return "stay"
    parts = []
    for seg in path.segments:
        if isinstance(seg, Line):
            parts.append(f"line to ({_num(seg.end[0])}, {_num(seg.end[1])})")
        else:
            parts.append(
                f"arc about ({_num(seg.center[0])}, {_num(seg.center[1])}) by {seg.sweep!r}"
            )
    return " then ".join(parts)


def _same_path(p: Path, q: Path, tol: float) -> bool:
    if len(p) != len(q):
        return False
    for s, t in zip(p.segments, q.segments, strict=True):
        if isinstance(s, Line) and isinstance(t, Line):
            a, b = s.end, t.end
        elif isinstance(s, Arc) and isinstance(t, Arc):
            if abs(s.sweep - t.sweep) > SWEEP_TOLERANCE:
                return False
            a, b = s.center, t.center
        else:
            return False
        if abs(a[0] - b[0]) > tol or abs(a[1] - b[1]) > tol:
            return False
    return True


def same_answer(p: Answer, q: Answer, look: Look) -> bool:
    return p[1] == q[1] and _same_path(p[0], q[0], TOLERANCE_REL * look.scale())
