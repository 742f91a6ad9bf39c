"""oblot-sim's `GatheringWithMultiplicity`, ported: gathering of an even number n > 2 of point
robots that detect multiplicity, by a dense point, a centre of biangularity, or a leader chosen by
the string of angles (docs/ports.md, "oblot-gathering-multiplicity").

Every rule cites `algorithms/GatheringWithMultiplicity.java` at the peer's commit by line (`:N`).
The peer reads its view in robot-id order in four places; fatswarm's robots are anonymous, so each
of those is replaced by the smallest order-free rule, named where it is used and in docs/ports.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Final

from fatswarm.agent.oblot_common import (
    PEER_EPSILON,
    STAY,
    TOLERANCE_SPEC,
    OblotParams,
    OblotRuleError,
    circle_of,
    gathered,
    go_to,
    make_oblot_params,
    peer_assumptions,
    same_point,
    spread,
    with_self,
)
from fatswarm.domain.assumptions import Assumptions
from fatswarm.domain.path import Path, Point, Points
from fatswarm.domain.seam import AlgorithmParamsError, ParamSpec, ParamValue

# "multiplicity detection and infinite visibility for an even amount of robots > 2" (`:14-17`);
# n is the view's length (`:21,24`); no rule needs axes the robots agree on (the leftmost point of
# `:182` only starts a test whose outcome is geometric).


def _angle(a: Point, b: Point) -> float:
    """The signed angle from vector a to vector b, in (-pi, pi] (0 when either is zero)."""
    return math.atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])


def _sub(p: Point, q: Point) -> Point:
    return (p[0] - q[0], p[1] - q[1])


def _dense_target(pts: list[Point]) -> Point | None:
    """Rule 2 (`:29-38`): the one point holding the most robots when some point holds more than
    one; None when every point holds one; OblotRuleError when several share the largest count.

    Robots are grouped by the peer's equality (each coordinate within 1e-13, `:29`), each joining
    the first group whose first point it equals; a group is named by its lexicographically smallest
    point (the peer names it by the first robot in id order: they differ by < 1e-13)."""
    groups: list[list[Point]] = []
    for p in pts:
        for g in groups:
            if same_point(g[0], p):
                g.append(p)
                break
        else:
            groups.append([p])
    most = max(len(g) for g in groups)
    if most == 1:
        return None
    dense = [g for g in groups if len(g) == most]
    if len(dense) > 1:
        raise OblotRuleError(
            f"{len(dense)} dense points hold {most} robots each (GatheringWithMultiplicity.java:33)"
        )
    return min(dense[0])


def _same_direction(u: Point, v: Point) -> bool:
    """u and v point the same way within the peer's tolerance (relative)."""
    nu, nv = math.hypot(*u), math.hypot(*v)
    cross = u[0] * v[1] - u[1] * v[0]
    dot = u[0] * v[0] + u[1] * v[1]
    return dot > 0.0 and abs(cross) <= PEER_EPSILON * nu * nv


def _median_from(apex: Point, others: list[Point]) -> Point | None:
    """The point of `others` at the median direction seen from `apex` (an odd count, all of them
    on one side of a line through `apex`, so the order of directions needs no reference ray), or
    None when another point lies on that same ray (`:184-191`, `:197-204`)."""
    ordered = sorted(others, key=lambda p: math.atan2(p[1] - apex[1], p[0] - apex[0]))
    mid = ordered[len(ordered) // 2]
    ray = _sub(mid, apex)
    if sum(1 for p in others if _same_direction(_sub(p, apex), ray)) > 1:
        return None
    return mid


def _intersection(a: Point, b: Point, c: Point, d: Point) -> Point:
    """Where the lines ab and cd cross; OblotRuleError when they are parallel (`:207-210`)."""
    u, v = _sub(b, a), _sub(d, c)
    det = u[0] * v[1] - u[1] * v[0]
    if abs(det) <= PEER_EPSILON * math.hypot(*u) * math.hypot(*v):
        raise OblotRuleError(
            "the two median lines of the biangularity test are parallel "
            "(GatheringWithMultiplicity.java:208)"
        )
    w = _sub(c, a)
    t = (w[0] * v[1] - w[1] * v[0]) / det
    return (a[0] + t * u[0], a[1] + t * u[1])


def centre_of_biangularity(pts: list[Point]) -> Point | None:
    """Rule 3 (`:180-240`, after Anderegg, Cieliebak and Prencipe 2003): the centre of
    biangularity of `pts` (an even count >= 4, no two equal), or None.

    x is the leftmost point (`:182`; on a tie, ours takes the lowest of them: the peer takes the
    first in id order); x's median point xm (`:184-191`); y, the point of largest direction seen
    from x (`:193-195`; on a tie, ours takes the nearest to x); y's median point ym (`:197-204`;
    the peer's duplicate test there counts x's angles, `:200`, ours y's own, as at `:187`). The
    candidate is where the lines x-xm and y-ym cross (`:207`); it is the centre if a point stands
    on it (`:212-214`), else if the angles at it from x to every point, sorted, go up by two
    alternating steps within 1e-13 (`:216-238`; the step across the cut is not checked, `:220`).
    """
    left = min(p[0] for p in pts)
    x = min((p for p in pts if p[0] == left), key=lambda p: p[1])
    from_x = [p for p in pts if p is not x]
    xm = _median_from(x, from_x)
    if xm is None:
        return None
    top = max(math.atan2(p[1] - x[1], p[0] - x[0]) for p in from_x)
    y = min(
        (p for p in from_x if math.atan2(p[1] - x[1], p[0] - x[0]) == top),
        key=lambda p: math.hypot(p[0] - x[0], p[1] - x[1]),
    )
    ym = _median_from(y, [p for p in pts if p is not y])
    if ym is None:
        return None
    cob = _intersection(x, xm, y, ym)
    if any(same_point(p, cob) for p in pts):
        return cob
    ref = _sub(x, cob)
    angles = sorted(_angle(ref, _sub(p, cob)) for p in pts)
    steps = [angles[i] - angles[i - 1] for i in range(1, len(angles))]
    odd, even = steps[0::2], steps[1::2]
    if any(abs(s - odd[0]) > PEER_EPSILON for s in odd):
        return None
    if even and any(abs(s - even[0]) > PEER_EPSILON for s in even):
        return None
    return cob


def _leader(pts: list[Point], centre: Point, radius: float) -> int:
    """Rule 5 (`:98-144`): the index in `pts` of the leader: of all strings of angles (every start,
    both senses), the lexicographically smallest, exact comparison (`:152-172`); in its order, the
    first robot not on the circle, else its first (`:135-143`).

    Raises OblotRuleError when the string does not sum to a full turn within 1e-13 (`:99-101`) or
    when the smallest string is met twice, a tie of leaders (`:116-117`, `:131-132`: the peer
    throws on any exact tie with its best so far, and never tries the reverse of its first
    string, `:106`; ours tries every string and refuses only a tie for the smallest).
    """
    n = len(pts)
    vecs = [_sub(p, centre) for p in pts]
    # The circular order: by direction about the centre; a robot on one ray with another comes
    # after it when farther out (the peer: the id order, `:52`). A robot at the centre has
    # direction atan2(0, 0) = 0, as in the peer's sort.
    order = sorted(
        range(n), key=lambda i: (math.atan2(vecs[i][1], vecs[i][0]), math.hypot(*vecs[i]))
    )
    sa = [_angle(vecs[order[i]], vecs[order[(i + 1) % n]]) for i in range(n)]  # `:54-58`
    if abs(math.fsum(sa) - 2.0 * math.pi) > PEER_EPSILON:
        raise OblotRuleError(
            "the string of angles does not sum to a full turn (GatheringWithMultiplicity.java:99)"
        )
    best: list[float] | None = None
    best_order: list[int] = []
    ties = 0
    for j in range(n):
        forward = sa[j:] + sa[:j]
        forward_pts = [order[(j + i) % n] for i in range(n)]
        backward = [sa[(j - 1 - i) % n] for i in range(n)]
        backward_pts = [order[(j - i) % n] for i in range(n)]
        for string, who in ((forward, forward_pts), (backward, backward_pts)):
            if best is None or string < best:
                best, best_order, ties = string, who, 1
            elif string == best and who != best_order:
                ties += 1
    if ties > 1:
        raise OblotRuleError(
            "two robots tie for leader: the case with multiple leaders is not implemented "
            "(GatheringWithMultiplicity.java:117)"
        )
    for i in best_order:
        d = math.hypot(*vecs[i])
        if not (radius * (1.0 - PEER_EPSILON) < d < radius * (1.0 + PEER_EPSILON)):
            return i
    return best_order[0]


def _check_n(n: int) -> None:
    """Rule 1 (`:21-26`): refuse n = 2 and odd n (OblotRuleError)."""
    if n == 2:
        raise OblotRuleError(
            "gathering with multiplicity does not support 2 robots "
            "(GatheringWithMultiplicity.java:21)"
        )
    if n % 2:
        raise OblotRuleError(
            f"gathering with multiplicity does not support an odd n = {n} "
            "(GatheringWithMultiplicity.java:24)"
        )


def _pick_one(pts: list[Point]) -> Point:
    """The peer's "pick a random one" (`:78-79`, `:83`), which is robot 0 (robot 1 for robot 0
    itself): no anonymous robot can name it. Ours: the nearest other robot, then the smallest x,
    then the smallest y, in the robot's frame."""
    return min(pts[1:], key=lambda p: (math.hypot(*p), p[0], p[1]))


class OblotGatheringMultiplicity:
    """oblot-sim's proof-of-concept gathering for an even n > 2 with multiplicity detection
    (`algorithms/GatheringWithMultiplicity.java:14-17`). Rules, in the order applied (numbered as
    in docs/ports.md):

    1. n = 2 or odd n: refuse (`:21-26`).
    2. Some point holds more robots than any other: go there (`:29-38`; two such points: refuse).
    3. A centre of biangularity exists: go there (`:40-43`).
    4. The smallest enclosing circle and its centre c (`:46-47`), whether a robot stands at c
       (`:49`), the string of angles and whether it is mixed (some angle below 1e-13, `:52-60`),
       NI, the robots inside the circle by more than 1e-13 (`:63`).
    5. The leader, by the smallest string of angles (`:98-144`).
    6. Only the leader moves (`:66-67`): no robot at c, not mixed: out to the circle if NI > 1
       (`:72-73`), else to c (`:74-75`); no robot at c, mixed: to one robot (`:77-79`); a robot
       at c: to one robot if not mixed (`:82-83`), to c if mixed (`:84-85`).
    """

    name: str = "oblot-gathering-multiplicity"
    summary: str = (
        "oblot-sim's GatheringWithMultiplicity: even n > 2 point robots with multiplicity "
        "detection gather (dense point, centre of biangularity, leader by string of angles)"
    )
    parameters: tuple[ParamSpec, ...] = (TOLERANCE_SPEC,)
    assumptions: Assumptions = peer_assumptions(None)

    def make_params(self, n: int | None, values: Mapping[str, ParamValue]) -> OblotParams:
        return make_oblot_params(n, values)

    def check_start(self, positions: Points, params: OblotParams) -> None:
        """Refuse n = 2 and odd n before the run (rule 1: the peer throws at the first Look)."""
        try:
            _check_n(len(positions))
        except OblotRuleError as exc:
            raise AlgorithmParamsError(str(exc)) from None

    def compute(self, view: Points, params: OblotParams) -> Path:
        """The path of rules 1-10; raises OblotRuleError where the peer throws."""
        arr = with_self(view)
        n = len(arr)
        _check_n(n)
        pts: list[Point] = [(float(x), float(y)) for x, y in arr]
        dense = _dense_target(pts)
        if dense is not None:
            return go_to(dense, params)
        cob = centre_of_biangularity(pts)
        if cob is not None:
            return go_to(cob, params)
        circle = circle_of(arr)
        c, r = circle.center, circle.radius
        robot_at_c = any(same_point(p, c) for p in pts)
        leader = _leader(pts, c, r)
        if leader != 0:  # row 0 is this robot
            return STAY
        vecs = [_sub(p, c) for p in pts]
        order = sorted(range(n), key=lambda i: math.atan2(vecs[i][1], vecs[i][0]))
        mixed = any(
            abs(_angle(vecs[order[i]], vecs[order[(i + 1) % n]])) < PEER_EPSILON for i in range(n)
        )
        inside = sum(1 for v in vecs if math.hypot(*v) < r - PEER_EPSILON)
        if not robot_at_c and not mixed:
            if inside > 1:  # out to the circle: radially (`Util/Circle.java:56-64`)
                here = math.hypot(*vecs[0])
                if r * (1.0 - PEER_EPSILON) < here < r * (1.0 + PEER_EPSILON) or here == 0.0:
                    return STAY
                f = r / here
                return go_to((c[0] - c[0] * f, c[1] - c[1] * f), params)
            return go_to(c, params)
        if robot_at_c != mixed:  # (not at c, mixed) or (at c, not mixed)
            return go_to(_pick_one(pts), params)
        return go_to(c, params)

    def goal(self, positions: Points, params: OblotParams) -> bool:
        """Every robot at one point (within GOAL_REL of the largest coordinate)."""
        return gathered(positions)

    def figures(self, positions: Points, params: OblotParams) -> dict[str, float]:
        return spread(positions)


ALGORITHM: Final = OblotGatheringMultiplicity()

__all__ = ["ALGORITHM", "OblotGatheringMultiplicity", "centre_of_biangularity"]
