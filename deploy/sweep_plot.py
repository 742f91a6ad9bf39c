"""`fatswarm sweep --plot DIR`: the summary figures of a sweep, drawn with matplotlib (an optional
extra): success rate by scheduler, rounds against n, distance ratio against n.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Sequence
from typing import Any, Final

from fatswarm.deploy.sweep import Cell, curves, success_rates

FIGURES: Final = ("success.png", "rounds.png", "ratio.png")
LOG_SPAN: Final = 30.0  # rounds spanning more than this factor are drawn on a log axis
DODGE: Final = 0.06  # sideways nudge between curves, in gaps between consecutive n
MARKERS: Final = ("o", "s", "^", "D", "v", "P", "X")


def draw_figures(cells: Sequence[Cell], folder: str) -> list[str]:
    """Write FIGURES into `folder` (created if missing); the paths written. Raises OSError."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(folder, exist_ok=True)
    paths = [os.path.join(folder, name) for name in FIGURES]
    for path, draw in zip(paths, (_success, _rounds, _ratio), strict=True):
        fig, ax = plt.subplots(figsize=(7, 4.5))
        try:
            draw(ax, cells)
            ax.grid(True, lw=0.3, alpha=0.5)
            fig.tight_layout()
            fig.savefig(path, dpi=120)
        finally:
            plt.close(fig)
    return paths


def _success(ax: Any, cells: Sequence[Cell]) -> None:
    """Two bars per scheduler (and algorithm, start): formed, and formed with no collision."""
    rates = success_rates(cells)
    x = list(range(len(rates)))
    formed = [f / r if r else 0.0 for _, r, f, _ in rates]
    clean = [c / r if r else 0.0 for _, r, _, c in rates]
    ax.bar([i - 0.2 for i in x], formed, width=0.4, label="formed")
    ax.bar([i + 0.2 for i in x], clean, width=0.4, label="formed, collision-free")
    for i, (_, runs, done, _) in enumerate(rates):
        ax.annotate(f"{done}/{runs}", (i - 0.2, formed[i]), ha="center", va="bottom",
                    fontsize=8)
    ax.set_xticks(x, [label for label, *_ in rates], rotation=20 if len(rates) > 4 else 0)
    ax.set_ylim(0.0, 1.1)
    ax.set_ylabel("fraction of runs")
    ax.set_title("success rate by scheduler (every n and seed)")
    ax.legend(loc="lower right", fontsize=8)


def _rounds(ax: Any, cells: Sequence[Cell]) -> None:
    _curves(ax, cells, "rounds")
    ax.set_ylabel("rounds (formed runs: median and quartiles)")
    ax.set_title("rounds to form against n")
    tops = [q[2] for line in curves(cells, "rounds").values() for _, q in line]
    lows = [q[0] for line in curves(cells, "rounds").values() for _, q in line]
    if tops and min(lows) > 0 and max(tops) / min(lows) > LOG_SPAN:
        ax.set_yscale("log")


def _ratio(ax: Any, cells: Sequence[Cell]) -> None:
    _curves(ax, cells, "ratio")
    ax.axhline(1.0, color="black", lw=0.8, ls="--", label="the bound")
    ax.set_ylabel("total distance / optimal-assignment bound")
    ax.set_title("distance against its lower bound, against n (formed runs)")
    ax.legend(fontsize=8)


def _curves(ax: Any, cells: Sequence[Cell], figure: str) -> None:
    """Median (quartiles as error bars) against n, a line per label, each nudged sideways a
    little (and with its own marker) so that equal curves stay visible."""
    from matplotlib.ticker import MaxNLocator

    lines = {label: points for label, points in curves(cells, figure).items() if points}
    sizes = sorted({n for points in lines.values() for n, _ in points})
    gap = min((b - a for a, b in itertools.pairwise(sizes)), default=1)
    for k, (label, points) in enumerate(lines.items()):
        shift = (k - (len(lines) - 1) / 2) * DODGE * gap
        ns = [n + shift for n, _ in points]
        median = [q[1] for _, q in points]
        spread = [[q[1] - q[0] for _, q in points], [q[2] - q[1] for _, q in points]]
        ax.errorbar(ns, median, yerr=spread, marker=MARKERS[k % len(MARKERS)], ms=4,
                    capsize=3, lw=1.2, elinewidth=0.8, label=label)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    drawn = bool(lines)
    if drawn:
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no formed run with this figure", ha="center", va="center",
                transform=ax.transAxes)
    ax.set_xlabel("n (robots)")


__all__ = ["FIGURES", "draw_figures"]
