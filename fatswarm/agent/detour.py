"""Shortest free path of a disc among disc obstacles: A* over the tangent graph of their circles.

The fallback for when the straight path and the single slide around the first obstacle are both
blocked (dense rings deadlock them): it finds a free path whenever one exists, the shortest one.
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fatswarm.agent.geometry import path_distances, segment_distances
from fatswarm.domain.path import Arc, Line, Path, Point, Points, Segment, end_point, segment_end

Floats = NDArray[np.float64]  # (k,)
Ints = NDArray[np.int64]  # (k,)
Bools = NDArray[np.bool_]  # (k,)

PLAN_MARGIN = 0.25
"""Tangents and arcs run at radius r + PLAN_MARGIN * tol: rounding (~1e-12) never takes them near
r - tol, and the margin stays well below tol, so the path is barely longer than the ideal one."""
CHECK_FRACTION = 0.875
"""Lines and arcs keep this fraction of the way from r - tol up to the planning radius: a tangent
passes its own circle's check despite rounding, and (being above r) obstacles that touch overlap
here, so a pinch between them is closed to lines and to arcs alike."""
ANGLE_SNAP = 1e-9
"""A turn this close to a full turn is no turn: it is rounding, and leaving a circle that little
behind the arrival point costs only rho * ANGLE_SNAP**2 / 2 of clearance."""
ZERO_LENGTH = 1e-12
"""Segments this short are dropped: a point on its own circle has a tangent of rounding length.
Far below tol and below END_MATCH, so dropping one moves nothing that matters."""
CHECK_CHUNK = 16
"""Lines checked together when one is first needed: enough to amortise numpy's call overhead,
few enough that lines longer than the answer are rarely checked."""
COVER_SLACK = 1e-9
"""An obstacle counts as buried only if the discs around it overlap by more than this (radians):
the sweep that checks it rounds to ~1e-12, and a false "buried" would lose a path."""
LINK_SLACK = 1.0 / 64.0
"""Discs are linked, for the quick test of an enclosed start or target, only if they overlap by
more than this times tol: far above rounding, below the 3/16 tol of touching obstacles."""
ROW_STRIDE = 16.0
"""Offset per circle in the buried sweep: above 4 pi, the largest end of an angular interval."""
END_MATCH = 1e-9
"""The returned path ends this close to the target (what callers rely on)."""

TWO_PI = 2.0 * math.pi
_UNKNOWN, _FREE, _BLOCKED = 0, 1, 2  # freeness of a line, found out lazily


def shortest_free_path(
    start: Point, target: Point, centres: Points, radii: np.ndarray, *, tol: float
) -> Path | None:
    """Shortest path from `start` to `target` keeping >= radii[j] - tol from every centres[j].

    `centres` is (m, 2), `radii` (m,); the discs may overlap and `start` may touch them. The path
    is the straight segment when that is free, else lines tangent to and arcs along circles of
    radius radii + PLAN_MARGIN * tol (shortest up to that margin). None when the target is
    unreachable, when it (or the start) is closer than radii - tol to a centre. Every path
    returned passes `keeps_clear`. Raises ValueError on malformed input.
    """
    c, r = _checked(centres, radii, tol)
    floor = r - tol
    sx, sy = float(start[0]), float(start[1])
    tx, ty = float(target[0]), float(target[1])
    for px, py in ((tx, ty), (sx, sy)):
        if len(r) and (np.hypot(c[:, 0] - px, c[:, 1] - py) < floor).any():
            return None
    if math.hypot(tx - sx, ty - sy) <= ZERO_LENGTH:
        return Path()
    straight = Path((Line((tx, ty)),))
    if len(r) == 0 or (segment_distances((sx, sy), (tx, ty), c) >= floor).all():
        return straight
    scene = _scene((sx, sy), (tx, ty), c, r, tol)
    path = None if scene.separated else _search(scene)
    if path is None or not keeps_clear(start, target, path, c, r, tol=tol):
        return None  # only rounding at the very limit gets here: a start or target at r - tol
    return path


def keeps_clear(
    start: Point, target: Point, path: Path, centres: Points, radii: np.ndarray, *, tol: float
) -> bool:
    """The contract of `shortest_free_path`: the path keeps >= radii - tol from every centre
    (exact distances of its centre line) and ends within END_MATCH of the target."""
    end = end_point(start, path)
    if math.hypot(end[0] - target[0], end[1] - target[1]) > END_MATCH:
        return False
    if len(centres) == 0:
        return True
    return bool((path_distances(start, path, centres) >= np.asarray(radii) - tol).all())


def _checked(centres: Points, radii: np.ndarray, tol: float) -> tuple[Points, Floats]:
    """The inputs as float64 arrays, or ValueError saying what is wrong."""
    c = np.asarray(centres, dtype=np.float64)
    r = np.asarray(radii, dtype=np.float64)
    if len(c) == 0:
        c = c.reshape(0, 2)
    if c.ndim != 2 or c.shape[1] != 2 or r.shape != (len(c),):
        raise ValueError(
            f"centres must be (m, 2) and radii (m,), got shapes {c.shape} and {r.shape}"
        )
    if not (math.isfinite(tol) and tol > 0.0):
        raise ValueError(f"tol must be a positive finite number, got {tol!r}")
    if not (np.isfinite(c).all() and np.isfinite(r).all() and (r > tol).all()):
        raise ValueError("centres and radii must be finite, and every radius larger than tol")
    return c, r


# --- the scene: planning circles ----------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Scene:
    """Planning circles (centres cx, cy, radius rho) and acceptance radii of one query.

    rho is r + PLAN_MARGIN * tol, lowered to the start's (or target's) distance where that is
    closer: the point then lies on its circle and leaves it along an arc or a tangent of length 0.
    Circle j is cut by the discs in directions cut_vx/vy[cut_at[j]:cut_at[j + 1]] (vectors from
    its centre), each over +-cut_w about that direction.
    """

    start: Point
    target: Point
    cx: Floats
    cy: Floats
    rho: Floats
    thr2: Floats  # squared acceptance radius: lines and arcs keep >= sqrt(thr2) from a centre
    cut_at: Ints
    cut_vx: Floats
    cut_vy: Floats
    cut_w: Floats
    separated: bool  # a ring of overlapping obstacles encloses the start or the target, not both

    @property
    def m(self) -> int:
        return len(self.rho)


def _scene(start: Point, target: Point, c: Points, r: Floats, tol: float) -> _Scene:
    """Planning and acceptance radii, buried obstacles dropped, where other discs cut each circle,
    and whether start and target are separated."""
    cx, cy = np.ascontiguousarray(c[:, 0]), np.ascontiguousarray(c[:, 1])
    d_start = np.hypot(cx - start[0], cy - start[1])
    d_target = np.hypot(cx - target[0], cy - target[1])
    rho = np.minimum(np.minimum(r + PLAN_MARGIN * tol, d_start), d_target)
    floor = r - tol
    thr = floor + CHECK_FRACTION * (rho - floor)
    # pairs (j, k) where disc k reaches circle j, sorted by j
    dx, dy = cx[None, :] - cx[:, None], cy[None, :] - cy[:, None]
    near = dx * dx + dy * dy < (rho[:, None] + thr[None, :]) ** 2
    np.fill_diagonal(near, False)
    j, k = np.nonzero(near)
    reach = thr[:, None] + thr[None, :] - LINK_SLACK * tol
    linked = np.triu((dx * dx + dy * dy < reach * reach) & (reach > 0.0), 1)
    lu, lv = np.nonzero(linked)
    separated = _separated(start, target, cx, cy, lu, lv, LINK_SLACK * tol)
    keep = ~_buried(j, k, cx, cy, rho, thr)
    both = keep[j] & keep[k]
    renum = np.cumsum(keep) - 1
    j, k = renum[j[both]], renum[k[both]]
    cx, cy, rho, thr = cx[keep], cy[keep], rho[keep], thr[keep]
    vx, vy = cx[k] - cx[j], cy[k] - cy[j]
    cos_w = _cos_halfwidth(rho[j], thr[k], np.hypot(vx, vy))
    cut = cos_w < 1.0
    j, vx, vy = j[cut], vx[cut], vy[cut]
    half = np.arccos(np.maximum(cos_w[cut], -1.0))
    cut_at = np.searchsorted(j, np.arange(len(rho) + 1)).astype(np.int64)
    return _Scene(start, target, cx, cy, rho, thr * thr, cut_at, vx, vy, half, separated)


def _separated(
    start: Point, target: Point, cx: Floats, cy: Floats, u: Ints, v: Ints, slack: float
) -> bool:
    """Whether linked discs (pairs u, v overlap) form a ring around exactly one of start and
    target: then nothing is reachable, and saying so at once spares A* exhausting the graph.

    The segments between linked centres lie inside the obstacles, and start and target outside.
    A cycle of them that crosses the segment start-target an odd number of times separates the
    two; one exists iff "crosses" is not a consistent 2-colouring of the link graph. Links whose
    crossing is too close to call are left out: fewer links can only miss a ring, never invent one.
    """
    sx, sy = start
    tx, ty = target
    side = (tx - sx) * (cy - sy) - (ty - sy) * (cx - sx) >= 0.0  # one bit per centre: consistent
    maybe = side[u] != side[v]
    ex, ey = cx[v] - cx[u], cy[v] - cy[u]
    o_start = ex * (sy - cy[u]) - ey * (sx - cx[u])
    o_target = ex * (ty - cy[u]) - ey * (tx - cx[u])
    near_line = np.minimum(np.abs(o_start), np.abs(o_target)) <= slack * np.hypot(ex, ey)
    sure = ~(maybe & near_line)
    u, v, maybe, o_start, o_target = u[sure], v[sure], maybe[sure], o_start[sure], o_target[sure]
    crosses = maybe & ((o_start > 0.0) != (o_target > 0.0))
    if not crosses.any():
        return False
    comp = _components(len(cx), u[~crosses], v[~crosses])
    a, b = comp[u[crosses]], comp[v[crosses]]
    if (a == b).any():
        return True
    colour: dict[int, bool] = {}  # 2-colour the few components that crossing links join
    links: dict[int, list[int]] = {}
    for p, q in zip(a.tolist(), b.tolist(), strict=True):
        links.setdefault(p, []).append(q)
        links.setdefault(q, []).append(p)
    for root in sorted(links):
        if root in colour:
            continue
        colour[root] = False
        todo = [root]
        while todo:
            p = todo.pop()
            for q in links[p]:
                if q not in colour:
                    colour[q] = not colour[p]
                    todo.append(q)
                elif colour[q] == colour[p]:
                    return True
    return False


def _components(n: int, u: Ints, v: Ints) -> Ints:
    """Connected components of the graph with edges (u, v): each vertex's smallest member."""
    label = np.arange(n)
    while True:
        low = np.minimum(label[u], label[v])
        new = label.copy()
        for at in (u, v, label[u], label[v]):
            np.minimum.at(new, at, low)
        while True:  # pointer jumping: labels are members of the same component
            jumped = new[new]
            if (jumped == new).all():
                break
            new = jumped
        if (new == label).all():
            return label
        label = new


def _cos_halfwidth(a: Floats, b: Floats, dist: Floats) -> Floats:
    """Cosine of the half-angle over which a disc of radius b at distance `dist` covers a circle
    of radius a: >= 1 where it misses it, <= -1 where it swallows it (b <= 0: an empty disc)."""
    safe = np.where(dist > 0.0, dist, 1.0)
    cos_w = (a * a + dist * dist - b * b) / (2.0 * a * safe)
    cos_w = np.where(dist > 0.0, cos_w, np.where(b > a, -1.0, 1.0))
    return np.where(b > 0.0, cos_w, 1.0)


def _buried(j: Ints, k: Ints, cx: Floats, cy: Floats, rho: Floats, thr: Floats) -> Bools:
    """Obstacles that cannot matter: every point of the acceptance circle lies deeper than
    rho - thr inside some other acceptance disc (pairs j, k, sorted by j: disc k near circle j).

    Nothing free can touch such a circle, and a line or arc that starts free and dips into such
    a disc first enters one that is not buried (where it crosses the union's boundary), so
    dropping them changes no check: in a dense cluster that is most of the obstacles.
    """
    m = len(cx)
    out = np.zeros(m, dtype=bool)
    if len(j) == 0:
        return out
    dx, dy = cx[k] - cx[j], cy[k] - cy[j]
    cos_w = _cos_halfwidth(thr[j], thr[k] - (rho - thr)[j], np.hypot(dx, dy))
    out[j[cos_w <= -1.0]] = True
    cut = cos_w < 1.0
    j, dx, dy, cos_w = j[cut], dx[cut], dy[cut], cos_w[cut]
    if len(j) == 0:
        return out
    half = np.arccos(np.maximum(cos_w, -1.0))
    lo = np.mod(np.arctan2(dy, dx) - half, TWO_PI)
    order = np.lexsort((lo, j))
    j, lo, hi = j[order], lo[order], (lo + 2.0 * half)[order]
    row = ROW_STRIDE * j  # exact; keeps the running maximum from leaking across rows
    reach = np.maximum.accumulate(row + hi) - row
    first = np.searchsorted(j, np.arange(m))
    count = np.bincount(j, minlength=m)
    same = j[1:] == j[:-1]
    gap = np.zeros(m, dtype=bool)
    gap[j[1:][same & (lo[1:] >= reach[:-1] - COVER_SLACK)]] = True
    last = np.minimum(first + count - 1, len(j) - 1)
    safe_first = np.minimum(first, len(j) - 1)
    wraps = reach[last] - TWO_PI > lo[safe_first] + COVER_SLACK
    return np.asarray(out | ((count > 0) & ~gap & wraps))


# --- geometry, vectorised ------------------------------------------------------------------------


def _tangents(
    ax: Floats, ay: Floats, sa: Floats, bx: Floats, by: Floats, sb: Floats
) -> tuple[Bools, Floats, Floats, Floats, Floats]:
    """Directed common tangents from circle a to circle b: (exists, x1, y1, x2, y2).

    Radii are signed by the sense of travel along the circle (positive: counter-clockwise, the
    centre on the left of the line), which picks exactly one of the four bitangents; radius 0 is a
    point. A point on its circle gets the tangent of length 0 at itself, never NaN.
    """
    dx, dy = bx - ax, by - ay
    dist = np.hypot(dx, dy)
    delta = sb - sa  # the left normal n of the line satisfies n . (b - a) = delta
    exists = (dist > 0.0) & (np.abs(delta) <= dist)
    safe = np.where(dist > 0.0, dist, 1.0)
    ux, uy = dx / safe, dy / safe
    q = np.clip(delta / safe, -1.0, 1.0)
    s = np.sqrt(1.0 - q * q)
    nx, ny = q * ux - s * uy, q * uy + s * ux
    return exists, ax - sa * nx, ay - sa * ny, bx - sb * nx, by - sb * ny


def _turn(ax: float, ay: float, bx: Floats, by: Floats, sigma: float) -> Floats:
    """Angle in [0, 2 pi) turning from direction a to each direction b in the sense sigma.

    Built from cross and dot products so that it is the same bits in a mirrored scene.
    """
    ang = np.arctan2(sigma * (ax * by - ay * bx), ax * bx + ay * by)
    ang = np.where(ang < 0.0, ang + TWO_PI, ang)
    return np.where(ang > TWO_PI - ANGLE_SNAP, 0.0, ang)


def _turn1(ax: float, ay: float, bx: float, by: float, sigma: float) -> float:
    """`_turn` for one pair, in scalar arithmetic (the path's own sweeps)."""
    ang = math.atan2(sigma * (ax * by - ay * bx), ax * bx + ay * by)
    if ang < 0.0:
        ang += TWO_PI
    return 0.0 if ang > TWO_PI - ANGLE_SNAP else ang


def _clear(scene: _Scene, x1: Floats, y1: Floats, x2: Floats, y2: Floats) -> Bools:
    """Whether each segment (x1, y1) -> (x2, y2) keeps sqrt(thr2) from every centre."""
    vx, vy = (x2 - x1)[:, None], (y2 - y1)[:, None]
    wx, wy = scene.cx[None, :] - x1[:, None], scene.cy[None, :] - y1[:, None]
    len2 = vx * vx + vy * vy
    t = np.clip((wx * vx + wy * vy) / np.where(len2 > 0.0, len2, 1.0), 0.0, 1.0)
    ex, ey = wx - t * vx, wy - t * vy
    return np.asarray((ex * ex + ey * ey >= scene.thr2[None, :]).all(axis=1))


def _extent(scene: _Scene, j: int, ax: float, ay: float, sigma: float) -> float:
    """How far (radians) one may turn along circle j in the sense sigma from direction a before
    meeting an obstacle: 0 when a itself is covered, 2 pi when nothing cuts the circle."""
    lo, hi = int(scene.cut_at[j]), int(scene.cut_at[j + 1])
    if lo == hi:
        return TWO_PI
    w = scene.cut_w[lo:hi]
    rel = _turn(ax, ay, scene.cut_vx[lo:hi], scene.cut_vy[lo:hi], sigma)
    if ((rel <= w) | (rel >= TWO_PI - w)).any():
        return 0.0
    return float((rel - w).min())


# --- the fans of tangents out of a point or a circle ---------------------------------------------


@dataclass(frozen=True, slots=True)
class _Fan:
    """All tangent lines leaving one place: index e < 2m arrives at circle e // 2 turning
    counter-clockwise (e even) or clockwise (e odd); index 2m, if present, goes to the target."""

    exists: Bools
    x1: Floats
    y1: Floats
    x2: Floats
    y2: Floats
    length: Floats
    to_go: Floats  # straight distance from the arrival point to the target (the A* heuristic)


def _fan(scene: _Scene, ax: float, ay: float, sa: float, with_target: bool) -> _Fan:
    """The tangents out of the circle about (ax, ay) of signed radius sa (0: the point itself)."""
    bx, by = np.repeat(scene.cx, 2), np.repeat(scene.cy, 2)
    sb = np.tile(np.array([1.0, -1.0]), scene.m) * np.repeat(scene.rho, 2)
    if with_target:
        bx = np.append(bx, scene.target[0])
        by = np.append(by, scene.target[1])
        sb = np.append(sb, 0.0)
    n = len(sb)
    exists, x1, y1, x2, y2 = _tangents(np.full(n, ax), np.full(n, ay), np.full(n, sa), bx, by, sb)
    if with_target:
        x2[-1], y2[-1] = scene.target  # exactly: the path must end there
    tx, ty = scene.target
    return _Fan(exists, x1, y1, x2, y2, np.hypot(x2 - x1, y2 - y1), np.hypot(tx - x2, ty - y2))


# --- the search ----------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Ids:
    """Node numbering. Ends: e = 2 * circle + (0 counter-clockwise, 1 clockwise), E = 2m of them.
    Node e1 * E + e2 is the tangent e1 -> e2, E * E + e2 the tangent start -> e2, E * E + E the
    target (reached by the tangent out of the end its parent arrived at)."""

    big_e: int

    @property
    def from_start(self) -> int:
        return self.big_e * self.big_e

    @property
    def goal(self) -> int:
        return self.big_e * self.big_e + self.big_e

    def arrival_end(self, node: int) -> int:
        """The end (circle and sense) at which line `node` arrives (not for the goal)."""
        return node - self.from_start if node >= self.from_start else node % self.big_e

    def line(self, node: int, prev: int) -> tuple[int, int]:
        """(fan key, index in the fan) of the line `node`, reached from node `prev`."""
        if node == self.goal:
            return self.arrival_end(prev), self.big_e
        if node >= self.from_start:
            return -1, node - self.from_start
        return node // self.big_e, node % self.big_e


@dataclass(frozen=True, slots=True)
class _Batch:
    """The lines out of one expanded node, in the order A* wants them."""

    prev: int  # the expanded node (-1: the start)
    key: int  # the fan the lines belong to
    nodes: Ints
    index: Ints  # positions in the fan
    cost: Floats  # length from the start to the end of each line
    f: Floats  # cost plus the straight distance on to the target
    x: Floats  # arrival points, for ties
    y: Floats


def _batch(prev: int, key: int, fan: _Fan, nodes: Ints, index: Ints, cost: Floats) -> _Batch:
    """Sort by estimated total length, then arrival point, then node."""
    f, x, y = cost + fan.to_go[index], fan.x2[index], fan.y2[index]
    order = np.lexsort((nodes, y, x, f))
    return _Batch(prev, key, nodes[order], index[order], cost[order], f[order], x[order], y[order])


@dataclass(frozen=True, slots=True)
class _Arrival:
    """An expanded arrival on a circle end: direction (ax, ay) from the centre, length g, and how
    far (radians) the circle is free onwards."""

    ax: float
    ay: float
    g: float
    reach: float


def _dominated(
    arrivals: list[_Arrival], ax: float, ay: float, g: float, sigma: float, rho: float
) -> bool:
    """Whether an earlier arrival on the same end reaches (ax, ay) along its free arc no longer
    than g: then everything this arrival could reach, that one reached first, no longer."""
    for a in arrivals:
        turn = _turn1(a.ax, a.ay, ax, ay, sigma)
        if turn <= a.reach and a.g + rho * turn <= g:
            return True
    return False


def _search(scene: _Scene) -> Path | None:
    """A* over arrival points: a node is a tangent line, reached at its end on a circle; an edge
    turns along that circle, as far as no other obstacle cuts it, then leaves on another tangent.

    The heuristic is the straight distance to the target. Edges are checked lazily, a chunk at a
    time when first popped: most tangents out of a node are longer than the answer and never are.
    An arrival that an earlier one on the same circle end reaches no longer is not expanded.
    Ties in length go to the smaller arrival point (x, y), then to the earlier expanded node, so
    the result does not depend on the order of the obstacles.
    """
    return _AStar(scene).run()


class _AStar:
    """The state of one `_search`: the fans out of the start and of each circle end expanded,
    which of their lines are known free or blocked, the arrivals expanded on each end, every
    node's parent, the closed nodes, and the heap of the batches' next lines."""

    def __init__(self, scene: _Scene) -> None:
        self.scene = scene
        self.ids = _Ids(2 * scene.m)
        self.fans: dict[int, _Fan] = {}
        self.status: dict[int, NDArray[np.int8]] = {}
        self.arrivals: dict[int, list[_Arrival]] = {}
        self.parent: dict[int, int] = {}
        self.closed = np.zeros(self.ids.goal + 1, dtype=bool)
        self.batches: list[_Batch] = []
        self.heap: list[tuple[float, float, float, int, int, int]] = []

    def run(self) -> Path | None:
        """The shortest path found, or None."""
        scene, ids, fans, closed, heap = self.scene, self.ids, self.fans, self.closed, self.heap
        sx, sy = scene.start
        fans[-1] = _fan(scene, sx, sy, 0.0, with_target=False)
        self.status[-1] = np.zeros(ids.big_e, dtype=np.int8)
        first = np.flatnonzero(fans[-1].exists)
        self.push(_batch(-1, -1, fans[-1], ids.from_start + first, first, fans[-1].length[first]))

        while heap:
            _, _, _, node, which, pos = heapq.heappop(heap)
            b = self.batches[which]
            if pos + 1 < len(b.nodes):
                self.queue(which, pos + 1)
            if closed[node] or not self.free(b, pos):
                continue
            closed[node] = True
            self.parent[node] = b.prev
            if node == ids.goal:
                return _assemble(scene, fans, self.parent, ids)
            self.expand(node, b.cost.item(pos))
        return None

    def push(self, b: _Batch) -> None:
        """Keep a batch and queue its first line."""
        if len(b.nodes):
            self.batches.append(b)
            self.queue(len(self.batches) - 1, 0)

    def queue(self, which: int, pos: int) -> None:
        """Put line `pos` of batch `which` on the heap, ordered by (f, x, y, node)."""
        b = self.batches[which]
        entry = (b.f.item(pos), b.x.item(pos), b.y.item(pos), b.nodes.item(pos), which, pos)
        heapq.heappush(self.heap, entry)

    def free(self, b: _Batch, pos: int) -> bool:
        """Whether line `pos` of the batch is free of obstacles: checked, when not known yet, with
        the next lines of the batch that are still open and unknown (a chunk at a time)."""
        st, k = self.status[b.key], b.index.item(pos)
        if st[k] == _UNKNOWN:
            end = min(pos + CHECK_CHUNK, len(b.nodes))
            idx = b.index[pos:end][~self.closed[b.nodes[pos:end]]]
            idx = idx[st[idx] == _UNKNOWN]
            fan = self.fans[b.key]
            ok = _clear(self.scene, fan.x1[idx], fan.y1[idx], fan.x2[idx], fan.y2[idx])
            st[idx] = np.where(ok, _FREE, _BLOCKED)
        return bool(st[k] == _FREE)

    def expand(self, node: int, g: float) -> None:
        """Queue the lines out of the circle end at which `node` arrives, after a length g."""
        scene, ids, fans = self.scene, self.ids, self.fans
        key, k = ids.line(node, self.parent[node])
        e = ids.arrival_end(node)
        j, sigma = e // 2, 1.0 - 2.0 * (e % 2)
        cx, cy, rho = scene.cx.item(j), scene.cy.item(j), scene.rho.item(j)
        ax, ay = fans[key].x2.item(k) - cx, fans[key].y2.item(k) - cy
        seen = self.arrivals.setdefault(e, [])
        if _dominated(seen, ax, ay, g, sigma, rho):
            return
        if e not in fans:
            fans[e] = _fan(scene, cx, cy, sigma * rho, with_target=True)
            self.status[e] = np.zeros(ids.big_e + 1, dtype=np.int8)
        fan, st = fans[e], self.status[e]
        reach = _extent(scene, j, ax, ay, sigma)
        seen.append(_Arrival(ax, ay, g, reach))
        turn = _turn(ax, ay, fan.x1 - cx, fan.y1 - cy, sigma)
        cand = np.flatnonzero(fan.exists & (turn <= reach) & (st != _BLOCKED))
        nodes = np.where(cand == ids.big_e, ids.goal, e * ids.big_e + cand)
        open_ = ~self.closed[nodes]
        cand, nodes = cand[open_], nodes[open_]
        cost = g + rho * turn[cand] + fan.length[cand]
        self.push(_batch(node, e, fan, nodes, cand, cost))


def _assemble(scene: _Scene, fans: dict[int, _Fan], parent: dict[int, int], ids: _Ids) -> Path:
    """The segments of the path that ends at the goal, with rounding-length ones dropped."""
    chain = [ids.goal]
    while chain[-1] in parent:
        chain.append(parent[chain[-1]])
    chain.reverse()  # -1 (the start), first line, ..., goal
    segs: list[Segment] = []
    here = scene.start
    for prev, node in itertools.pairwise(chain):
        key, k = ids.line(node, prev)
        fan = fans[key]
        if key >= 0:  # turn along the circle the previous line arrived at, up to this line
            j, sigma = key // 2, 1.0 - 2.0 * (key % 2)
            cx, cy = float(scene.cx[j]), float(scene.cy[j])
            turn = _turn1(
                here[0] - cx, here[1] - cy, float(fan.x1[k]) - cx, float(fan.y1[k]) - cy, sigma
            )
            if turn * float(scene.rho[j]) > ZERO_LENGTH:
                arc = Arc((cx, cy), sigma * turn)
                segs.append(arc)
                here = segment_end(here, arc)
        end = (float(fan.x2[k]), float(fan.y2[k]))
        if math.hypot(end[0] - here[0], end[1] - here[1]) > ZERO_LENGTH:
            segs.append(Line(end))
            here = end
    return Path(tuple(segs))
