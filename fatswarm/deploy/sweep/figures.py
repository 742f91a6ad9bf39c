"""`fatswarm sweep --plot DIR`: the summary figures of a sweep, drawn with matplotlib (an optional
extra): success rate by model, rounds against n, distance ratio against n. A series is a model
(`sweep.model_label`: `fsync`, `async`, `fsync+nr1`, `ssync+crash2`), so non-rigid moves, crash
faults and the async models are series of their own.
"""

from __future__ import annotations

import importlib.util
import itertools
import os
import sys
from collections.abc import Sequence
from typing import Any, Final

from fatswarm.deploy.sweep.summary import Cell, curves, success_rates

FIGURES: Final = ("success.png", "rounds.png", "ratio.png")
LOG_SPAN: Final = 30.0  # rounds spanning more than this factor are drawn on a log axis
DODGE: Final = 0.06  # sideways nudge between curves, in gaps between consecutive n
DODGE_SPAN: Final = 0.3  # all curves' nudges together stay within this much of a gap
MARKERS: Final = ("o", "s", "^", "D", "v", "P", "X")
UPRIGHT_BARS: Final = 8  # more models than this: the success bars lie, a row per model


def draw_figures(cells: Sequence[Cell], folder: str) -> list[str]:
    """Write FIGURES into `folder` (created if missing); the paths written. The ratio figure is
    left out, with a line on stderr saying why, when runs formed but none has the bound (it
    needs scipy). Raises OSError."""
    # matplotlib is an optional extra (fatswarm[plot]), and heavy: loaded only to draw
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # once the backend is chosen

    os.makedirs(folder, exist_ok=True)
    drawers = dict(zip(FIGURES, (_success, _rounds, _ratio), strict=True))
    why = no_ratio_reason(cells)
    if why is not None:
        del drawers["ratio.png"]
        print(f"fatswarm sweep: no ratio.png: {why}", file=sys.stderr)
    paths = []
    for name, draw in drawers.items():
        path = os.path.join(folder, name)
        fig, ax = plt.subplots(figsize=(7, 4.5))
        try:
            draw(ax, cells)
            ax.grid(True, lw=0.3, alpha=0.5)
            fig.tight_layout()
            fig.savefig(path, dpi=120)
        finally:
            plt.close(fig)
        paths.append(path)
    return paths


def no_ratio_reason(cells: Sequence[Cell]) -> str | None:
    """Why the ratio figure would be empty although runs formed (no formed run has the bound:
    scipy missing, or none computed); None when it has points, or when nothing formed (the
    figure says so itself)."""
    if any(c.ratio is not None for c in cells) or not any(c.formed for c in cells):
        return None
    if not has_scipy():
        return (
            "the distance's bound needs scipy, which is not installed (pip install "
            "'fatswarm[sweep]'), so no run has a ratio"
        )
    return "no formed run of the table has the distance's bound (its rows were written without it)"


def has_scipy() -> bool:
    """Whether scipy (the optional `sweep` extra, which computes the bound) can be imported."""
    return importlib.util.find_spec("scipy") is not None


def _success(ax: Any, cells: Sequence[Cell]) -> None:
    """Two bars per model (and algorithm, start): formed, and formed with no collision. Up to
    UPRIGHT_BARS models the bars stand; more (a grid of schedulers x deltas x crash counts has
    45) lie, a row per model in a figure as tall as they need, so every label stays readable."""
    rates = success_rates(cells)
    x = list(range(len(rates)))
    labels = [label for label, *_ in rates]
    formed = [f / r if r else 0.0 for _, r, f, _ in rates]
    clean = [c / r if r else 0.0 for _, r, _, c in rates]
    counts = [f"{done}/{runs}" for _, runs, done, _ in rates]
    if len(rates) <= UPRIGHT_BARS:
        ax.bar([i - 0.2 for i in x], formed, width=0.4, label="formed")
        ax.bar([i + 0.2 for i in x], clean, width=0.4, label="formed, collision-free")
        for i, text in enumerate(counts):
            ax.annotate(text, (i - 0.2, formed[i]), ha="center", va="bottom", fontsize=8)
        slant = len(rates) > 4  # model labels (`ssync+nr0.1`) are long: slant them
        ax.set_xticks(
            x, labels, **({"rotation": 30, "ha": "right", "fontsize": 8} if slant else {})
        )
        ax.set_ylim(0.0, 1.1)
        ax.set_ylabel("fraction of runs")
        ax.legend(loc="lower right", fontsize=8)
    else:
        row_inches = 0.3
        ax.figure.set_size_inches(7, 1.5 + row_inches * len(rates))
        ax.barh([i - 0.2 for i in x], formed, height=0.4, label="formed")
        ax.barh([i + 0.2 for i in x], clean, height=0.4, label="formed, collision-free")
        for i, text in enumerate(counts):
            ax.annotate(f" {text}", (formed[i], i - 0.2), ha="left", va="center", fontsize=7)
        ax.set_yticks(x, labels, fontsize=8)
        ax.set_ylim(len(rates) - 0.5, -0.5)  # the grid's order, top down, no margin
        ax.set_xlim(0.0, 1.15)
        ax.set_xlabel("fraction of runs")
        below = -0.8 / (row_inches * len(rates))  # 0.8 inch under the axes: past the x label
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, below), ncol=2, fontsize=8)
    ax.set_title("success rate by model (every n and seed)")


def _rounds(ax: Any, cells: Sequence[Cell]) -> None:
    _curves(ax, cells, "rounds")
    ax.set_ylabel("rounds, or async cycles (formed runs: median, quartiles)")
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
    _legend(ax)


def _curves(ax: Any, cells: Sequence[Cell], figure: str) -> None:
    """Median (quartiles as error bars) against n, a line per label, each nudged sideways a
    little (and with its own marker) so that equal curves stay visible; with many labels (a
    sweep over models) the nudges shrink so that the points of one n span at most DODGE_SPAN of a
    gap."""
    from matplotlib.ticker import MaxNLocator  # the optional extra, as in draw_figures

    lines = {label: points for label, points in curves(cells, figure).items() if points}
    sizes = sorted({n for points in lines.values() for n, _ in points})
    gap = min((b - a for a, b in itertools.pairwise(sizes)), default=1)
    step = min(DODGE, DODGE_SPAN / max(1, len(lines) - 1))  # many models: closer, not off n
    for k, (label, points) in enumerate(lines.items()):
        shift = (k - (len(lines) - 1) / 2) * step * gap
        ns = [n + shift for n, _ in points]
        median = [q[1] for _, q in points]
        spread = [[q[1] - q[0] for _, q in points], [q[2] - q[1] for _, q in points]]
        ax.errorbar(
            ns,
            median,
            yerr=spread,
            marker=MARKERS[k % len(MARKERS)],
            ms=4,
            capsize=3,
            lw=1.2,
            elinewidth=0.8,
            label=label,
        )
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    drawn = bool(lines)
    if drawn:
        _legend(ax)
    else:
        ax.text(
            0.5,
            0.5,
            "no formed run with this figure",
            ha="center",
            va="center",
            transform=ax.transAxes,
        )
    ax.set_xlabel("n (robots)")


def _legend(ax: Any) -> None:
    """The curves' legend: inside the axes, or for more than UPRIGHT_BARS lines (a sweep over
    models) beside them in smaller type, where it hides no curve."""
    handles, _ = ax.get_legend_handles_labels()
    if len(handles) > UPRIGHT_BARS:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
        ax.legend(fontsize=8)


__all__ = ["FIGURES", "draw_figures"]
