"""Every keyed seeded draw of a run and the stream constants that keep them apart.

A run's randomness is a pure function of its seed: each kind of draw has its own stream, so no draw
depends on the order or the number of others, and lock step, a networked run, a resumed run and a
replay all see the same start, frames, schedule and adversary.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Final

import numpy as np

from fatswarm.domain.scratch import scratch

START_STREAM: Final = 0x57A7  # random starts (deploy/scenarios/starts.py)
FRAME_STREAM: Final = 0xF1A9  # each robot's private X mirroring
SCHEDULE_STREAM: Final = 0x5CED  # the round schedulers' choices of active robots
DELAY_STREAM: Final = 0xA5C0  # the async adversary's compute delays and waits
ADVERSARIAL_STREAM: Final = 0xAD5E  # adversarial start families (deploy/scenarios)
CASES_STREAM: Final = 0xCA5E  # the hunt's mix of adversarial cases
LOOK_STREAM: Final = 0x5A0F  # orders the others in a view; compute must not depend on the order
CUT_STREAM: Final = 0xC07A  # where the non-rigid adversary stops a move
CRASH_STREAM: Final = 0xC4A5  # which robots the crash adversary stops for good, and when
ROTATION_STREAM: Final = 0x2074  # each private frame's rotation (--frames chirality, disoriented)
FRAME_LOOK_STREAM: Final = 0xF1A5  # mirrors drawn by key (disoriented, --frame-change every-look)
NOISE_STREAM: Final = 0x9015  # the sensors' error on each position a Look shows (--noise)

SORT_VALUES: Final = 2048
"""`view_orders` sorts hashes as values from this many in all; below, argsort costs less."""


def view_order(seed: int, round_no: int, robot: int, k: int) -> np.ndarray:
    """The order in which robot `robot` sees the k others in round `round_no`: drawn from the run's
    seed, the round and the robot, so it does not depend on who looks first.

    The indices sorted by a keyed splitmix64 hash: 6 microseconds where a seeded numpy generator
    costs 15 on every Look (the order is no figure of the run: compute must not depend on it, and
    records do not keep it).
    """
    order: np.ndarray = view_orders(seed, round_no, (robot,), k)[0]
    return order


def view_orders(
    seed: int, round_no: int, robots: Sequence[int], k: int, among_all: bool = False
) -> np.ndarray:
    """`view_order` of every robot of `robots` at once: row i is robot robots[i]'s, (m, k) int64;
    with `among_all`, each index j among the others is that robot's among all k + 1 robots
    (j + 1 from robots[i] on: robots[i] itself skipped), what a round's views gather.

    The same hashes; they are distinct within a row (splitmix64's finaliser is a bijection and the
    keys differ), so any sort gives each row the very order `view_order` gives. The hashes are
    sorted as values, not argsorted (about three times faster): each with its low bits replaced by
    its index, which then rides along; a row where two hashes could share their high bits (a
    chance of about k^2 2^-65) is argsorted whole instead.
    """
    z = _hashes(seed, round_no, robots, k)
    if z.size < SORT_VALUES or k < 2:
        order: np.ndarray = z.argsort(axis=1)
        if among_all:
            order += order >= np.asarray(robots, dtype=np.int64)[:, None]
        return order
    bits = k.bit_length() if among_all else (k - 1).bit_length()
    low = np.uint64((1 << bits) - 1)
    z &= ~low  # the hash's high bits, then the index in the low ones (increasing along a row)
    z |= _skipping(k, tuple(robots)) if among_all else _indices(k)[None, :]
    z.sort(axis=1)
    m = len(z)
    gaps = np.subtract(z[:, 1:], z[:, :-1], out=scratch("view_orders", (m, k - 1), np.uint64))
    # sorted and distinct, each gap is positive; one within `low`: the high bits may be equal,
    # so which hash is the smaller is not sure in that row
    doubtful = np.flatnonzero((gaps <= low).any(axis=1) if gaps.min() <= low else ())
    z &= low
    order = z.view(np.int64)
    if len(doubtful):
        picked = [robots[i] for i in doubtful.tolist()]
        redone = _hashes(seed, round_no, picked, k).argsort(axis=1)
        if among_all:
            redone += redone >= np.asarray(picked, dtype=np.int64)[:, None]
        order[doubtful] = redone
    return order


@functools.lru_cache(maxsize=2)
def _skipping(k: int, robots: tuple[int, ...]) -> np.ndarray:
    """(m, k) uint64, read-only: j + 1 where j >= robots[i], else j: index j among robot
    robots[i]'s others as one among all robots (the same robots look every fsync round)."""
    j = np.arange(k, dtype=np.int64)[None, :]
    out = (j + (j >= np.asarray(robots, dtype=np.int64)[:, None])).astype(np.uint64)
    out.flags.writeable = False
    return out


def _hashes(seed: int, round_no: int, robots: Sequence[int], k: int) -> np.ndarray:
    """(m, k) uint64: the keyed splitmix64 hash of index j (1-based) of robot robots[i]'s view
    in round `round_no`: what `view_orders` sorts (a new array)."""
    base = _mix64(_mix64(LOOK_STREAM ^ (seed & _MASK64)) ^ round_no)
    x = np.asarray(robots, dtype=np.uint64) ^ np.uint64(base)  # uint64 arrays wrap silently:
    x += _C1  # that is the hash (`_mix64` of every robot's key at once, the same bits)
    x = (x ^ (x >> _S30)) * _C2
    x = (x ^ (x >> _S27)) * _C3
    keys = x ^ (x >> _S31)
    z: np.ndarray = np.add(_spread(k)[None, :], keys[:, None])
    if z.size < SORT_VALUES:  # few: fewer calls
        z = (z ^ (z >> _S30)) * _C2
        z = (z ^ (z >> _S27)) * _C3
        z ^= z >> _S31
        return z
    t = scratch("view_orders", z.shape, np.uint64)  # in place: fresh arrays cost page faults
    np.right_shift(z, _S30, out=t)
    z ^= t
    z *= _C2
    np.right_shift(z, _S27, out=t)
    z ^= t
    z *= _C3
    np.right_shift(z, _S31, out=t)
    z ^= t
    return z


def cut_fraction(seed: int, round_no: int, robot: int) -> float:
    """The non-rigid adversary's draw u in [0, 1) for robot `robot`'s move in round `round_no`:
    a keyed splitmix64 hash of (seed, round, robot), as `view_order`, so every run mode (and a
    resumed world) draws the same, and no other draw of the run shifts it."""
    return keyed_fraction(CUT_STREAM, seed, round_no, robot)


def keyed_fraction(stream: int, seed: int, *keys: int) -> float:
    """A draw u in [0, 1) that is a pure function of (stream, seed, keys): a chain of splitmix64
    finalisers, its top 53 bits. The adversaries' draws (`cut_fraction`, async delays) use it, so
    no draw depends on the order or the number of others."""
    key = _mix64(stream ^ (seed & _MASK64))
    for k in keys:
        key = _mix64(key ^ (k & _MASK64))
    return (key >> 11) * 2.0**-53  # the top 53 bits: a double in [0, 1)


def crash_plan(seed: int, n: int, f: int) -> dict[int, int]:
    """The crash adversary's plan: robot -> the round from which it is crashed, for f of n robots.

    Each robot gets a keyed splitmix64 hash of (seed, robot) (its own stream, as `cut_fraction`);
    the f robots with the smallest hashes crash, each in round 1 + floor(u * 2n), u in [0, 1) the
    top 53 bits of the hash mixed once more: within the first two default fairness bounds. A pure
    function of (seed, n, f), so every run mode, a resumed world and a replay agree.
    Raises ValueError unless 0 < f < n.
    """
    if not 0 < f < n:
        raise ValueError(f"--crash must be between 1 and n - 1 = {n - 1}, got {f}")
    base = _mix64(CRASH_STREAM ^ (seed & _MASK64))
    keys = {robot: _mix64(base ^ robot) for robot in range(n)}
    chosen = sorted(range(n), key=lambda r: (keys[r], r))[:f]
    return {r: 1 + int(((_mix64(keys[r]) >> 11) * 2.0**-53) * 2 * n) for r in sorted(chosen)}


_MASK64: Final = (1 << 64) - 1
_C1, _C2, _C3 = (np.uint64(c) for c in (0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB))
_S30, _S27, _S31 = np.uint64(30), np.uint64(27), np.uint64(31)


@functools.lru_cache(maxsize=8)
def _indices(k: int) -> np.ndarray:
    """0..k-1 as uint64 (read-only): the low bits `view_orders` sorts its hashes with."""
    out = np.arange(k, dtype=np.uint64)
    out.flags.writeable = False
    return out


@functools.lru_cache(maxsize=8)
def _spread(k: int) -> np.ndarray:
    """(1..k) times splitmix64's increment: the per-index part of view_order's hash (read-only)."""
    out = np.arange(1, k + 1, dtype=np.uint64) * _C1
    out.flags.writeable = False
    return out


def _mix64(x: int) -> int:
    """splitmix64's finaliser on a Python int (64-bit)."""
    x = (x + 0x9E3779B97F4A7C15) & _MASK64
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _MASK64
    return x ^ (x >> 31)


def look_noise(seed: int, robot: int, look_round: int, k: int) -> np.ndarray:
    """The standard normal errors of robot `robot`'s Look of round `look_round` (an async run:
    its instant) on the k positions it shows, (k, 2), row i for the view's row i: a seeded
    generator of its own per (seed, robot, Look), so every run mode (and a re-Look) draws the
    same and no other draw of the run shifts it. `--noise` scales them by sigma."""
    rng = np.random.default_rng([NOISE_STREAM, seed & 0xFFFFFFFF, robot, look_round])
    errors: np.ndarray = rng.standard_normal((k, 2))
    return errors


def draw_flip(seed: int, robot: int) -> bool:
    """Robot `robot`'s X mirroring in a run seeded with `seed` (same in lockstep and networked)."""
    rng = np.random.default_rng([FRAME_STREAM, seed & 0xFFFFFFFF, robot])
    return bool(rng.random() < 0.5)
