"""A sub-cell drawing surface for the terminal: discs, circles and points to scale, and labels.

Each terminal cell holds 2 x 4 dots (braille) or 1 x 2 dots (half blocks); a cell is about twice
as tall as wide, so dots are square and circles stay round. World y points up, screen rows down.
A label is text in whole cells, on a disc (reverse video) or just beside it, where there is room.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from rich.segment import Segment
from rich.style import Style
from rich.text import Text

Mode = Literal["braille", "half"]
DOTS_PER_CELL: dict[str, tuple[int, int]] = {"braille": (2, 4), "half": (1, 2)}

LABEL_ON = 128  # a label cell drawn on its disc has layer LABEL_ON + the disc's layer (reverse)

# Braille dot bits by (column, row) inside a cell (Unicode block U+2800).
_BRAILLE_BITS = np.array([[0x01, 0x02, 0x04, 0x40], [0x08, 0x10, 0x20, 0x80]], dtype=np.int64)
BRAILLE_BLANK = 0x2800


@dataclass(frozen=True, slots=True)
class Viewport:
    """Maps world coordinates to dot coordinates with one scale on both axes (y up)."""

    cols: int
    rows: int
    mode: Mode
    left: float  # world x of the left edge
    top: float  # world y of the top edge
    units_per_dot: float

    @property
    def dots_wide(self) -> int:
        return self.cols * DOTS_PER_CELL[self.mode][0]

    @property
    def dots_high(self) -> int:
        return self.rows * DOTS_PER_CELL[self.mode][1]

    @classmethod
    def fit(
        cls,
        xmin: float,
        xmax: float,
        ymin: float,
        ymax: float,
        cols: int,
        rows: int,
        mode: Mode = "braille",
    ) -> Viewport:
        """The viewport showing the world box [xmin, xmax] x [ymin, ymax] whole, centred."""
        if cols < 1 or rows < 1:
            raise ValueError(f"a canvas needs at least one cell, got {cols} x {rows}")
        dx, dy = DOTS_PER_CELL[mode]
        width, height = max(xmax - xmin, 1e-9), max(ymax - ymin, 1e-9)
        units = max(width / (cols * dx), height / (rows * dy))
        cx, cy = (xmin + xmax) / 2.0, (ymin + ymax) / 2.0
        return cls(
            cols=cols,
            rows=rows,
            mode=mode,
            left=cx - units * cols * dx / 2.0,
            top=cy + units * rows * dy / 2.0,
            units_per_dot=units,
        )

    def to_dot(self, x: float, y: float) -> tuple[float, float]:
        """Continuous dot coordinates (column, row) of a world point; dot (i, j) spans [i, i+1)."""
        return ((x - self.left) / self.units_per_dot, (self.top - y) / self.units_per_dot)

    def to_cell(self, x: float, y: float) -> tuple[int, int]:
        """The cell (column, row) a world point falls in (may lie outside the canvas)."""
        i, j = self.to_dot(x, y)
        dx, dy = DOTS_PER_CELL[self.mode]
        return (math.floor(i) // dx, math.floor(j) // dy)


class Canvas:
    """Dots tagged with a layer number; where layers meet in one cell, the highest one is shown."""

    def __init__(self, viewport: Viewport) -> None:
        self.viewport = viewport
        self.dots: NDArray[np.uint8] = np.zeros(
            (viewport.dots_high, viewport.dots_wide), dtype=np.uint8
        )
        self.labels: dict[tuple[int, int], tuple[str, int]] = {}  # (row, col) -> (char, layer)

    def _set(self, rows: NDArray[np.int64], cols: NDArray[np.int64], layer: int) -> None:
        keep = (rows >= 0) & (rows < self.dots.shape[0]) & (cols >= 0) & (cols < self.dots.shape[1])
        r, c = rows[keep], cols[keep]
        self.dots[r, c] = np.maximum(self.dots[r, c], layer)

    def point(self, x: float, y: float, layer: int) -> None:
        """Light the dot containing the world point (x, y)."""
        i, j = self.viewport.to_dot(x, y)
        self._set(np.array([math.floor(j)]), np.array([math.floor(i)]), layer)

    def points(self, pts: Iterable[tuple[float, float]], layer: int) -> None:
        """Light the dot under each world point."""
        for x, y in pts:
            self.point(x, y, layer)

    def marker(self, x: float, y: float, layer: int) -> None:
        """A plus of five dots centred on the world point: visible at any scale."""
        i, j = self.viewport.to_dot(x, y)
        ci, cj = math.floor(i), math.floor(j)
        cols = np.array([ci, ci - 1, ci + 1, ci, ci], dtype=np.int64)
        rows = np.array([cj, cj, cj, cj - 1, cj + 1], dtype=np.int64)
        self._set(rows, cols, layer)

    def disc(self, x: float, y: float, radius: float, layer: int) -> None:
        """Fill the dots whose centres lie in the disc; a disc smaller than a dot lights one dot."""
        vp = self.viewport
        ci, cj = vp.to_dot(x, y)
        rd = radius / vp.units_per_dot
        i0, i1 = math.floor(ci - rd), math.ceil(ci + rd)
        j0, j1 = math.floor(cj - rd), math.ceil(cj + rd)
        if i1 < 0 or j1 < 0 or i0 >= vp.dots_wide or j0 >= vp.dots_high:
            return
        ii, jj = np.meshgrid(np.arange(i0, i1 + 1), np.arange(j0, j1 + 1))
        inside = (ii + 0.5 - ci) ** 2 + (jj + 0.5 - cj) ** 2 <= rd * rd
        if not inside.any():
            self.point(x, y, layer)
            return
        self._set(jj[inside], ii[inside], layer)

    def circle(self, x: float, y: float, radius: float, layer: int) -> None:
        """Draw the outline of a circle, one dot thick (samples at most half a dot apart)."""
        rd = radius / self.viewport.units_per_dot
        steps = max(16, math.ceil(2.0 * math.pi * rd * 2.0))
        theta = np.linspace(0.0, 2.0 * math.pi, steps, endpoint=False)
        self._light_dots(
            np.column_stack((x + radius * np.cos(theta), y + radius * np.sin(theta))), layer
        )

    def clear_discs(self, centres: NDArray[np.float64], radius: float, below: int) -> None:
        """Unlight the dots of layers under `below` whose centres lie within `radius` of any of
        the world points (k, 2): a margin that keeps what is drawn next (the robots) apart from
        the lines through them (a circle, a path). One pass over the lit dots, not one per disc."""
        vp = self.viewport
        rows, cols = np.nonzero((self.dots > 0) & (self.dots < below))
        if not len(rows) or not len(centres):
            return
        ci = (np.asarray(centres)[:, 0] - vp.left) / vp.units_per_dot  # dot coordinates
        cj = (vp.top - np.asarray(centres)[:, 1]) / vp.units_per_dot
        rd2 = (radius / vp.units_per_dot) ** 2
        near = np.zeros(len(rows), dtype=bool)
        for start in range(0, len(ci), 256):  # in slices: (dots x 256) at a time
            di = cols[:, None] + 0.5 - ci[None, start : start + 256]
            dj = rows[:, None] + 0.5 - cj[None, start : start + 256]
            near |= (di * di + dj * dj <= rd2).any(axis=1)
        self.dots[rows[near], cols[near]] = 0

    def label(self, x: float, y: float, radius: float, text: str, layer: int) -> bool:
        """Write `text` on the disc about (x, y) if it fits inside it, else just right of it if
        those cells (and one more) are blank; False when there is no room for it."""
        vp = self.viewport
        dx, dy = DOTS_PER_CELL[vp.mode]
        rd = radius / vp.units_per_dot
        col, row = vp.to_cell(x, y)
        if rd >= (len(text) / 2 + 0.5) * dx and rd >= 0.75 * dy:  # the disc holds it
            first = col - (len(text) - 1) // 2
            if self._place(row, first, text, LABEL_ON + layer, blank=False):
                return True
        after, _ = vp.to_cell(x + radius + vp.units_per_dot, y)
        return self._place(row, after + 1, text, layer, blank=True)

    def _place(self, row: int, first: int, text: str, layer: int, blank: bool) -> bool:
        """Put `text` in cells (row, first...) unless one is off the canvas or labelled already,
        or (`blank`) one of them or the cell after them has a dot lit."""
        vp = self.viewport
        cells = [(row, first + k) for k in range(len(text) + (1 if blank else 0))]
        if not 0 <= row < vp.rows or first < 0 or first + len(text) > vp.cols:
            return False
        if any(cell in self.labels for cell in cells):
            return False
        if blank and self._lit_cells(row, first, min(first + len(cells), vp.cols)):
            return False
        for k, char in enumerate(text):
            self.labels[(row, first + k)] = (char, layer)
        return True

    def _lit_cells(self, row: int, first: int, end: int) -> bool:
        """Whether any dot of the cells (row, first..end-1) is lit."""
        dx, dy = DOTS_PER_CELL[self.viewport.mode]
        return bool(self.dots[row * dy : (row + 1) * dy, first * dx : end * dx].any())

    def polyline(self, pts: NDArray[np.float64], layer: int) -> None:
        """Draw the world points (k, 2) joined by straight strokes (open), half a dot apart."""
        if len(pts) == 0:
            return
        seg = np.diff(pts, axis=0)
        per_dot = 2.0 / self.viewport.units_per_dot
        counts = np.maximum(1, np.ceil(np.hypot(seg[:, 0], seg[:, 1]) * per_dot)).astype(np.int64)
        which = np.repeat(np.arange(len(seg)), counts)
        first = np.concatenate(([0], np.cumsum(counts)[:-1]))
        t = (np.arange(int(counts.sum())) - first[which] + 1) / counts[which]
        samples = pts[which] + t[:, None] * seg[which]
        self._light_dots(np.concatenate((pts[:1], samples)), layer)

    def _light_dots(self, pts: NDArray[np.float64], layer: int) -> None:
        """Light the dot under each world point of (k, 2)."""
        vp = self.viewport
        cols = np.floor((pts[:, 0] - vp.left) / vp.units_per_dot).astype(np.int64)
        rows = np.floor((vp.top - pts[:, 1]) / vp.units_per_dot).astype(np.int64)
        self._set(rows, cols, layer)

    def cell_layers(self) -> NDArray[np.uint8]:
        """(rows, cols) of the highest layer lit in each cell (0 where the cell is blank)."""
        dx, dy = DOTS_PER_CELL[self.viewport.mode]
        r, c = self.viewport.rows, self.viewport.cols
        out: NDArray[np.uint8] = self.dots.reshape(r, dy, c, dx).max(axis=(1, 3))
        return out

    def glyphs(self) -> list[str]:
        """The canvas as plain text, one string per cell row."""
        vp = self.viewport
        lit = (self.dots > 0).astype(np.int64)
        if vp.mode == "braille":
            cells = lit.reshape(vp.rows, 4, vp.cols, 2)
            codes = BRAILLE_BLANK + np.einsum("rjci,ij->rc", cells, _BRAILLE_BITS)
            return ["".join(map(chr, row)).replace(chr(BRAILLE_BLANK), " ") for row in codes]
        top, bottom = lit[0::2], lit[1::2]
        table = np.array([" ", "▄", "▀", "█"])
        return ["".join(row) for row in table[top * 2 + bottom]]

    def runs(self) -> list[list[tuple[str, int]]]:
        """Each cell row as runs of (text, layer) where the shown layer stays the same; a label's
        cells show its characters, on layer LABEL_ON + the disc's when it sits on its disc."""
        out: list[list[tuple[str, int]]] = []
        labelled: dict[int, list[tuple[int, str, int]]] = {}
        for (r, c), (char, layer) in self.labels.items():
            labelled.setdefault(r, []).append((c, char, layer))
        for row_no, (row, row_layers) in enumerate(
            zip(self.glyphs(), self.cell_layers().tolist(), strict=True)
        ):
            if row_no in labelled:
                chars = list(row)
                for c, char, layer in labelled[row_no]:
                    chars[c], row_layers[c] = char, layer
                row = "".join(chars)
            cuts = [0] + [c for c in range(1, len(row)) if row_layers[c] != row_layers[c - 1]]
            cuts.append(len(row))
            out.append([(row[a:b], row_layers[a]) for a, b in itertools.pairwise(cuts)])
        return out

    def render(self, styles: Mapping[int, str | Style]) -> Text:
        """The canvas as rich Text; each cell takes the style of the highest layer lit in it."""
        text = Text(no_wrap=True, overflow="crop")
        for row_no, runs in enumerate(self.runs()):
            if row_no:
                text.append("\n")
            for chunk, layer in runs:
                text.append(chunk, style=_style_of(styles, layer) or "")
        return text

    def segments(self, styles: Mapping[int, Style]) -> Iterator[Segment]:
        """The canvas as rich Segments, one line per cell row (fast path for live frames)."""
        for runs in self.runs():
            for chunk, layer in runs:
                style = _style_of(styles, layer)
                yield Segment(chunk, style if isinstance(style, Style) else None)
            yield Segment.line()


_ON_DISC = Style(reverse=True, bold=True)


def _style_of(styles: Mapping[int, str | Style], layer: int) -> str | Style | None:
    """The style of a layer (None for blank cells); a label on its disc: the disc's, reversed."""
    if layer >= LABEL_ON:
        base = styles.get(layer - LABEL_ON)
        base = Style.parse(base) if isinstance(base, str) else base
        return _ON_DISC if base is None else base + _ON_DISC
    return styles.get(layer) if layer else None
