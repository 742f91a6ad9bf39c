"""`fatswarm plot RECORD OUT.svg|OUT.png`: trajectories, start and end discs and the final circle.

Drawn to scale (equal axes, unit discs) with matplotlib, an optional extra (`fatswarm[plot]`);
without it the command says how to install it and exits with 2.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from fatswarm.deploy.view.dashboard import algorithm_text, enclosing_circle
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.path import Points, sample, truncate
from fatswarm.world.record import RecordFormatError, RunRecord, move_origin
from fatswarm.world.record_read import read_record, torn_end_note

FORMATS = (".svg", ".png")
TRAIL_STEP = 0.1  # world units between samples of a drawn path
MISSING_MATPLOTLIB = (
    "fatswarm plot needs matplotlib: install it with `pip install 'fatswarm[plot]'` "
    "(or `pip install matplotlib`)"
)


def trajectories(record: RunRecord) -> list[Points]:
    """Each robot's whole route through the run as a (k, 2) polyline, arcs sampled finely."""
    n = record.header.n
    here = np.array(record.header.initial, dtype=np.float64)
    routes: list[list[Points]] = [[here[i : i + 1].copy()] for i in range(n)]
    for rr in record.rounds:
        for move in rr.moves:
            start = move_origin(rr, move.robot, here)
            covered = truncate(start, move.path, move.traveled)
            if covered:
                routes[move.robot].append(sample(start, covered, TRAIL_STEP)[1:])
        here = np.array(rr.positions, dtype=np.float64)
    return [np.concatenate(parts) for parts in routes]


def final_positions(record: RunRecord) -> Points:
    """Where the robots ended (the result line, else the last round, else the start)."""
    if record.result is not None:
        return record.result.positions
    if record.rounds:
        return record.rounds[-1].positions
    return record.header.initial


def default_title(record: RunRecord, rc: float) -> str:
    """The run in one line: algorithm and parameters, n, scheduler, seed, outcome, final r_c."""
    header = record.header
    status = record.result.status if record.result is not None else "unfinished"
    rounds = record.rounds[-1].round if record.rounds else 0
    return (
        f"{algorithm_text(header.algorithm, header.params)}, n={header.n}, {header.scheduler}, "
        f"seed {header.seed}: {status} after {rounds} rounds (final SEC r_c={rc:.3f})"
    )


def draw(record: RunRecord, out: str, title: str | None = None) -> None:
    """Render the record to `out` (format from its suffix); needs matplotlib."""
    # matplotlib is an optional extra (fatswarm[plot]), and heavy: loaded only to draw
    import matplotlib

    matplotlib.use("Agg")
    # once the backend is chosen
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    header = record.header
    end = final_positions(record)
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.set_aspect("equal")
    cmap = plt.get_cmap("tab20")
    for i, route in enumerate(trajectories(record)):
        color = cmap(i % 20)
        ax.plot(route[:, 0], route[:, 1], "-", color=color, linewidth=0.8, alpha=0.9)
        start = header.initial[i]
        ax.add_patch(Circle((start[0], start[1]), 1.0, fill=False, ls="--", ec=color, lw=0.7))
        ax.add_patch(Circle((end[i, 0], end[i, 1]), 1.0, fc=color, ec="black", lw=0.5, alpha=0.6))
    (cx, cy), rc = enclosing_circle(end)
    ax.add_patch(Circle((cx, cy), rc, fill=False, ec="black", lw=1.0, label="final SEC"))
    ax.plot([cx], [cy], "k+", markersize=6)
    everything = np.vstack([header.initial, end, [[cx - rc, cy - rc], [cx + rc, cy + rc]]])
    lo, hi = everything.min(axis=0) - 1.5, everything.max(axis=0) + 1.5
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_title(title or default_title(record, rc), fontsize=9)
    ax.set_xlabel("x (robot radii)")
    ax.set_ylabel("y (robot radii)")
    ax.grid(True, lw=0.3, alpha=0.5)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm plot`."""
    p.add_argument("record", metavar="RECORD", help="run record (JSON Lines)")
    p.add_argument("out", metavar="OUT", help="picture to write: OUT.svg or OUT.png")
    p.add_argument("--title", help="title instead of the run's parameters")


def main(args: argparse.Namespace) -> int:
    """`fatswarm plot`: exit 0 on success, 2 on bad input or without matplotlib."""
    suffix = os.path.splitext(args.out)[1].lower()
    if suffix not in FORMATS:
        print(f"fatswarm plot: OUT must end in .svg or .png, got {args.out!r}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    try:
        record = read_record(args.record, allow_torn_end=True)  # a crashed run shows too
    except RecordFormatError as exc:
        print(f"fatswarm plot: {exc}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    note = torn_end_note(args.record, record)
    if note is not None:
        print(f"fatswarm plot: {note}", file=sys.stderr)
    try:  # matplotlib is an optional extra (fatswarm[plot]): without it, say how to install it
        import matplotlib  # noqa: F401
    except ImportError:
        print(MISSING_MATPLOTLIB, file=sys.stderr)
        return ExitCode.BAD_INPUT
    try:
        draw(record, args.out, args.title)
    except OSError as exc:
        print(f"fatswarm plot: cannot write {args.out}: {exc.strerror or exc}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    return ExitCode.OK
