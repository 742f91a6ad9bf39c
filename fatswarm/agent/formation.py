"""FormUCircle (docs/algorithm.md, G6-G15): fill the targets on the current SEC one mover (or mirror
pair) at a time; the Note's swap when nothing else can move."""

from __future__ import annotations

import itertools
import math

import numpy as np

from fatswarm.agent.detour import END_MATCH, shortest_free_path
from fatswarm.agent.geometry import (
    is_free,
    north_point,
    path_x_range,
    required_clearance,
    robot_at,
    sec,
    segment_distances,
    targets_on,
)
from fatswarm.agent.planning import Ctx, Lazy, Step, TieKeys, ranked, without
from fatswarm.domain.path import (
    MAX_SEGMENTS,
    Arc,
    Line,
    Path,
    Point,
    Points,
    end_point,
    mirror,
    path_length,
    segment_end,
    transform,
)
from fatswarm.domain.tolerance import CLEAR_SLACK, CONTACT, ROUND_ABS

SURE_SEC = 4.0
"""`_moves_the_sec` decides only with this many tol_at to spare (one would do in exact
arithmetic): room for the rounding of `sec`'s circles."""
RIM_MAX = 16
"""`_moves_the_sec` leaves swarms with more robots near the SEC than this to `_keeps_sec`."""


def form_u_circle(ctx: Ctx, n: int) -> Step | None:
    """FormUCircle: fill the targets on the current SEC one mover (or mirror pair) at a time;
    None if nothing can move (stuck)."""
    pts, c = ctx.pts, ctx.circle
    cx, cy = c.center
    at_o = robot_at(pts, north_point(c), ctx.tol_at) is not None
    targets = targets_on(c, n, at_o)
    xs, ys = pts[:, 0], pts[:, 1]
    # Targets are >= a* >= 4 apart (G1), so only a robot's angularly nearest target can be within
    # 2 of it: one O(n) pass gives "settled" (G8) and "blocks" (G7) for every robot.
    step = 2.0 * math.pi / n
    theta = np.arctan2(xs - cx, ys - cy)
    if not at_o:
        theta -= step / 2.0
    theta /= step
    nearest = np.rint(theta, out=theta).astype(np.intp)
    nearest %= n
    off = pts - targets.take(nearest, axis=0)
    d_near = np.hypot(off[:, 0], off[:, 1])
    settled_robot = d_near <= ctx.tol_at  # G8: settled robots never move
    settled_target = np.zeros(n, dtype=bool)
    settled_target[nearest[settled_robot]] = True
    moving = ~settled_robot
    unsettled = moving.nonzero()[0]
    vacant = (~settled_target).nonzero()[0]
    # G7: R blocks T iff their discs overlap. A settled robot's own target is not vacant, so only
    # unsettled robots can block a vacant target.
    near = ((d_near < CONTACT - CLEAR_SLACK) & moving).nonzero()[0]
    blockers: dict[int, list[int]] = {}
    for i, k in zip(near.tolist(), nearest[near].tolist(), strict=True):
        blockers.setdefault(k, []).append(i)
    side = -ctx.orientation
    t_x, t_y = targets[:, 0], targets[:, 1]
    order = Lazy(
        int(vacant[j])
        for j in ranked(-t_y[vacant], ctx.tol_eq, lambda: (side * (t_x[vacant] - cx),))
    )
    u_x, u_y = xs[unsettled], ys[unsettled]
    # The paper's paths first (chord, arcs, one slide); only if none is admissible anywhere, any
    # free path (G14b), so that every configuration the old rules moved still moves the same way.
    for wide in (False, True):
        for k in order:
            blocked_by = blockers.get(k, ())
            if len(blocked_by) >= 2:  # double-blocked: wait until one blocker has left (G7)
                continue
            if ctx.symmetric or blocked_by:
                cands = np.array(blocked_by, dtype=np.intp) if blocked_by else unsettled
                if ctx.symmetric:
                    cands = _symmetric_candidates(ctx, cands, targets[k])
                c_x, c_y = xs[cands], ys[cands]
            else:
                cands, c_x, c_y = unsettled, u_x, u_y
            if len(cands) == 0:
                continue
            dist = np.hypot(c_x - t_x[k], c_y - t_y[k])
            ties = _ties(side, cx, c_x, c_y)
            for j in ranked(dist, ctx.tol_eq, ties):
                moves = _try_move(ctx, int(cands[j]), targets, k, wide)
                if moves is not None:
                    return ("detour" if wide else "fill"), moves
    swap = _note_swap(ctx, targets, list(order), settled_robot, at_o, n)
    if swap is not None:
        return "note-swap", swap
    return None


def _ties(side: float, cx: float, c_x: np.ndarray, c_y: np.ndarray) -> TieKeys:
    """The candidates' tie keys after distance: the highest, then the agreed side (G12)."""
    return lambda: (-c_y, side * (c_x - cx))


def _symmetric_candidates(ctx: Ctx, cands: np.ndarray, target: np.ndarray) -> np.ndarray:
    """G13: targets on L go to robots on L; an off-L target to robots on its side or on L."""
    tx = float(target[0]) - ctx.cx
    x = ctx.pts[cands, 0] - ctx.cx
    on_l = np.abs(x) <= ctx.tol_at
    keep = on_l if abs(tx) <= ctx.tol_at else on_l | ((x > 0) == (tx > 0))
    return np.asarray(cands[keep])


def _try_move(
    ctx: Ctx, i: int, targets: Points, k: int, wide: bool = False
) -> dict[int, Path] | None:
    """The move of robot i to target k if it is admissible (free, keeps the SEC), else None.

    `wide`: look for any free path (the shortest, `detour.shortest_free_path`) instead of the
    chord, arcs and single slide.
    """
    pts, cx, tol = ctx.pts, ctx.cx, ctx.tol_at
    x_i = float(pts[i, 0]) - cx
    i_on_l = abs(x_i) <= tol
    target = (float(targets[k, 0]), float(targets[k, 1]))
    if ctx.symmetric and i_on_l and abs(target[0] - cx) > tol and target[0] < cx:
        # A robot on L choosing between mirror targets takes the one on its own +X side (G12);
        # it moves alone, so this frame-dependent choice breaks the symmetry safely.
        target = (2.0 * cx - target[0], target[1])
    start = (float(pts[i, 0]), float(pts[i, 1]))
    others = without(pts, i)
    if _moves_the_sec(ctx, start, target, others):
        return None  # `_keeps_sec` would refuse it (i moving alone) whatever the path: spare it
    path = _detour(start, target, others) if wide else _free_path(ctx, start, target, others)
    if path is None:
        return None
    moves = {i: path}
    if ctx.symmetric and not i_on_l:  # the mirror partner makes the mirrored move (G11)
        partner_path = _partner_move(ctx, i, start, path)
        if partner_path is None:
            return None
        moves[partner_path[0]] = partner_path[1]
    if not _keeps_sec(ctx, moves):
        return None
    return moves


def _partner_move(ctx: Ctx, i: int, start: Point, path: Path) -> tuple[int, Path] | None:
    """G11: robot i's mirror partner and its move, the mirror image of i's, or None if unsafe.

    The partner repeats i's displacement mirrored, from where it is: in a swarm symmetric only
    within EPS_AT it is `d` = (dx, dy) off the exact mirror image of i, and then the two centres
    are, at every instant, hypot(2 (x_i(t) - c_x) - dx, dy) apart (for i right of L; mirrored
    for the left). So the pair is safe iff that holds at i's extreme x towards L, by the rule of
    G6: >= 2 - CLEAR_SLACK, or, already touching closer, no closer than now.
    """
    pts, cx = ctx.pts, ctx.cx
    mirror_start = (2.0 * cx - start[0], start[1])
    partner = int(np.argmin(np.hypot(pts[:, 0] - mirror_start[0], pts[:, 1] - mirror_start[1])))
    if partner == i:
        return None
    p_start = (float(pts[partner, 0]), float(pts[partner, 1]))
    dx, dy = p_start[0] - mirror_start[0], p_start[1] - mirror_start[1]
    side = 1.0 if start[0] > cx else -1.0
    lo, hi = path_x_range(start, path)
    gap = side * (2.0 * ((lo if side > 0 else hi) - cx) - dx)
    now = math.hypot(start[0] - p_start[0], start[1] - p_start[1])
    if gap <= 0.0 or math.hypot(gap, dy) < min(CONTACT - CLEAR_SLACK, now) - ROUND_ABS:
        return None
    relative = transform(path, (-start[0], -start[1]), False)
    mirrored = transform(mirror(relative), p_start, False)
    if dx != 0.0 or dy != 0.0:  # not an exact mirror image: its own path must be free too
        lo_i, hi_i = min(i, partner), max(i, partner)
        rest = np.concatenate((pts[:lo_i], pts[lo_i + 1 : hi_i], pts[hi_i + 1 :]))
        if not is_free(p_start, mirrored, rest):
            return None
    return partner, mirrored


def _moves_the_sec(ctx: Ctx, start: Point, target: Point, others: Points) -> bool:
    """True only if robot i on the SEC at `start`, moving alone to within END_MATCH of `target`,
    surely moves the SEC by more than tol_at (G9): `_keeps_sec` refuses it, whatever the path,
    and with it any pair move of i (SSYNC may activate i alone).

    Every circle `sec` returns passes through two or three robots and holds its centre between
    them. One within tol_at of the current circle (centre and radius) passes through robots at
    least R - 2 tol_at from the centre c; if all of those, and the target, lie beyond one line
    through c by more than tol_at, its centre is not between them: there is no such circle. The
    test keeps SURE_SEC times that room, and says False whenever it is not plain.
    """
    c = ctx.circle
    cx, cy = c.center
    if math.hypot(start[0] - cx, start[1] - cy) < c.radius - ctx.tol_at:
        return False  # an interior mover keeps the SEC
    sure = SURE_SEC * ctx.tol_at
    dist = np.hypot(others[:, 0] - cx, others[:, 1] - cy)
    rim = (dist >= c.radius - 2.0 * sure - ROUND_ABS).nonzero()[0]
    if len(rim) > RIM_MAX:
        return False
    rows = others.take(rim, axis=0).tolist()
    vecs = [(x - cx, y - cy) for x, y in rows] + [(target[0] - cx, target[1] - cy)]
    # The line: across the middle of the widest angular gap between them, if it exceeds pi.
    angles = sorted(math.atan2(vy, vx) for vx, vy in vecs)
    gap = angles[0] + 2.0 * math.pi - angles[-1]
    mid = (angles[-1] + angles[0] + 2.0 * math.pi) / 2.0
    for a0, a1 in itertools.pairwise(angles):
        if a1 - a0 > gap:
            gap, mid = a1 - a0, (a0 + a1) / 2.0
    if gap <= math.pi:
        return False
    ux, uy = -math.cos(mid), -math.sin(mid)
    need = sure + END_MATCH + ROUND_ABS
    return all(vx * ux + vy * uy > need for vx, vy in vecs)


def _keeps_sec(ctx: Ctx, moves: dict[int, Path]) -> bool:
    """G9: the SEC after the move equals the current one, for every subset SSYNC may activate."""
    pts, c = ctx.pts, ctx.circle
    cx, cy = c.center
    movers = list(moves)
    inside = c.radius - ctx.tol_at
    if all(math.hypot(float(pts[i, 0]) - cx, float(pts[i, 1]) - cy) < inside for i in movers):
        return True  # only interior robots move onto the circle: the support stays
    subsets = [movers] if len(movers) == 1 else [movers, movers[:1], movers[1:]]
    for subset in subsets:
        after = pts.copy()
        for i in subset:
            after[i] = end_point((float(pts[i, 0]), float(pts[i, 1])), moves[i])
        new = sec(after)
        if (
            math.hypot(new.center[0] - cx, new.center[1] - cy) > ctx.tol_at
            or abs(new.radius - c.radius) > ctx.tol_at
            or new.radius < ctx.r - ctx.tol_eq  # it would send the swarm back to expansion
        ):
            return False
    return True


def _free_path(ctx: Ctx, start: Point, target: Point, others: Points) -> Path | None:
    """Shortest free way to the target: along the SEC, the chord, or sliding over an obstacle."""
    c = ctx.circle
    options = [Path((Line(target),))]
    rho = math.hypot(start[0] - c.center[0], start[1] - c.center[1])
    if rho >= c.radius - ctx.tol_at:  # a robot on the SEC may slide along it (G15)
        a0 = math.atan2(start[1] - c.center[1], start[0] - c.center[0])
        a1 = math.atan2(target[1] - c.center[1], target[0] - c.center[0])
        ccw = (a1 - a0) % (2.0 * math.pi)
        for sweep in (ccw, ccw - 2.0 * math.pi):
            options.append(_arc_to(c.center, sweep, start, target))
    path = _first_free(ctx, start, options, others)
    if path is not None:
        return path
    obstacle = _first_blocker(start, target, others)
    if obstacle is None:
        return None
    return _first_free(ctx, start, _slides(start, target, obstacle), others)


def _detour(start: Point, target: Point, others: Points) -> Path | None:
    """G14b: the shortest free path of any shape (G6's clearance), if one exists."""
    if len(others) == 0:
        return Path((Line(target),))
    d0 = np.hypot(others[:, 0] - start[0], others[:, 1] - start[1])
    radii = np.minimum(d0 + CLEAR_SLACK, CONTACT)  # minus CLEAR_SLACK: required_clearance
    # The planner checks its result against radii - CLEAR_SLACK, stricter than is_free's bound.
    path = shortest_free_path(start, target, others, radii, tol=CLEAR_SLACK)
    if path is None or len(path) > MAX_SEGMENTS:
        return None
    return path


def _arc_to(center: Point, sweep: float, start: Point, target: Point) -> Path:
    arc = Arc(center, sweep)
    end = segment_end(start, arc)
    if math.hypot(end[0] - target[0], end[1] - target[1]) > 1e-12:
        return Path((arc, Line(target)))
    return Path((arc,))


def _first_free(ctx: Ctx, start: Point, options: list[Path], others: Points) -> Path | None:
    """The shortest free option; equal lengths go to the agreed side (G12)."""
    if len(options) == 1:
        return options[0] if is_free(start, options[0], others) else None
    lengths = np.array([path_length(start, p) for p in options])
    for j in ranked(lengths, ctx.tol_eq, lambda: (_sides(ctx, start, options),)):
        if is_free(start, options[j], others):
            return options[j]
    return None


def _sides(ctx: Ctx, start: Point, options: list[Path]) -> np.ndarray:
    """How far each option's x range lies on the agreed side of L (a tie key: lower first)."""
    sides = []
    for p in options:
        lo, hi = path_x_range(start, p)
        sides.append(-ctx.orientation * ((lo + hi) / 2.0 - ctx.cx))
    return np.array(sides)


def _first_blocker(start: Point, target: Point, others: Points) -> Point | None:
    """The first robot along the straight path start -> target whose disc it would touch."""
    if len(others) == 0:
        return None
    d = segment_distances(start, target, others)
    hit = (d < required_clearance(start, others)).nonzero()[0]
    if len(hit) == 0:
        return None
    dx, dy = target[0] - start[0], target[1] - start[1]
    along = (others[hit, 0] - start[0]) * dx + (others[hit, 1] - start[1]) * dy
    j = int(hit[np.argmin(along)])
    return (float(others[j, 0]), float(others[j, 1]))


def _slides(start: Point, target: Point, obstacle: Point) -> list[Path]:
    """Tangent-arc-tangent paths around the radius-2 circle about the obstacle, both sides (G14)."""
    ox, oy = obstacle
    out: list[Path] = []
    ds = math.hypot(start[0] - ox, start[1] - oy)
    dt = math.hypot(target[0] - ox, target[1] - oy)
    if dt < CONTACT - CLEAR_SLACK:
        return out
    phi_s = math.atan2(start[1] - oy, start[0] - ox)
    phi_t = math.atan2(target[1] - oy, target[0] - ox)
    beta_s = math.acos(min(1.0, CONTACT / ds)) if ds > CONTACT else 0.0
    beta_t = math.acos(min(1.0, CONTACT / dt)) if dt > CONTACT else 0.0
    for sigma in (1.0, -1.0):  # counter-clockwise, clockwise around the obstacle
        a_ang = phi_s + sigma * beta_s
        b_ang = phi_t - sigma * beta_t
        sweep = sigma * ((sigma * (b_ang - a_ang)) % (2.0 * math.pi))
        a_pt = (ox + CONTACT * math.cos(a_ang), oy + CONTACT * math.sin(a_ang))
        segs: list[Line | Arc] = []
        if math.hypot(a_pt[0] - start[0], a_pt[1] - start[1]) > 1e-12:
            segs.append(Line(a_pt))
        segs.append(Arc(obstacle, sweep))
        segs.append(Line(target))
        out.append(Path(tuple(segs)))
    return out


# --- the Note's swap (G15) ---------------------------------------------------------------------


def _note_swap(
    ctx: Ctx,
    targets: Points,
    order: list[int],
    settled_robot: np.ndarray,
    at_o: bool,
    n: int,
) -> dict[int, Path] | None:
    """Fallback when nothing else can move: a settled robot R2 next to a vacant target T' slides
    on to T', vacating T2 so that an unsettled SEC robot can take T2 in the next cycle."""
    pts, c = ctx.pts, ctx.circle
    cx, cy = c.center
    step = 2.0 * math.pi / n
    on_sec = np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) >= c.radius - ctx.tol_at
    waiting = (~settled_robot & on_sec).nonzero()[0]
    if len(waiting) == 0:
        return None
    o_pt = north_point(c)
    for k in order:
        tk = (float(targets[k, 0]), float(targets[k, 1]))
        for j in range(n):
            tj = (float(targets[j, 0]), float(targets[j, 1]))
            ang = math.atan2(tj[1] - cy, tj[0] - cx) - math.atan2(tk[1] - cy, tk[0] - cx)
            ang = (ang + math.pi) % (2.0 * math.pi) - math.pi
            if abs(abs(ang) - step) > 1e-6:
                continue
            r2 = robot_at(pts, tj, ctx.tol_at)
            if r2 is None or (at_o and math.hypot(tj[0] - o_pt[0], tj[1] - o_pt[1]) <= ctx.tol_at):
                continue
            if ctx.symmetric and abs(tj[0] - cx) > ctx.tol_at:
                continue  # a lone mover off L would break G11 in a mirror-symmetric swarm
            others = without(pts, r2)
            path = _arc_to(c.center, -ang, tj, tk)
            if not is_free(tj, path, others) or not _keeps_sec(ctx, {r2: path}):
                continue
            after = pts.copy()
            after[r2] = tk
            if _someone_reaches(ctx, after, waiting, tj):
                return {r2: path}
    return None


def _someone_reaches(ctx: Ctx, after: Points, waiting: np.ndarray, target: Point) -> bool:
    """After the swap, some waiting robot has a free path to the vacated target (progress)."""
    for i in waiting:
        start = (float(after[i, 0]), float(after[i, 1]))
        others = without(after, int(i))
        if _free_path(ctx, start, target, others) is not None:
            return True
    return False
