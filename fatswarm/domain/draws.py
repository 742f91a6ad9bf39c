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
HIGH_FROM: Final = 33
"""splitmix64's last step, x ^ (x >> 31), leaves a hash's bits from this one up as they were:
`view_orders` sorts by those bits without that step (rows where two hashes share them, about
k^2 2^-31 of rows of k, are argsorted by their whole hashes instead)."""


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
    seed: int,
    round_no: int,
    robots: Sequence[int],
    k: int,
    among_all: bool = False,
    rounds: int = 1,
) -> np.ndarray:
    """`view_order` of every robot of `robots` at once: row i is robot robots[i]'s, (m, k) int64;
    with `among_all`, each index j among the others is that robot's among all k + 1 robots
    (j + 1 from robots[i] on: robots[i] itself skipped), what a round's views gather. With
    `rounds`, those of rounds round_no, round_no + 1, ... at once: (rounds * m, k), row r * m + i
    robot robots[i]'s in round round_no + r.

    The same hashes; they are distinct within a row (splitmix64's finaliser is a bijection and the
    keys differ), so any sort gives each row the very order `view_order` gives. From SORT_VALUES
    hashes on, they are sorted as values, not argsorted (about three times faster), and without
    the finaliser's last step: each one's bits from HIGH_FROM up (which that step leaves as they
    are) with its index in the low bits, where it rides along; a row where two of them could
    share those high bits (sorted neighbours less than 2^HIGH_FROM apart) is argsorted by its
    whole hashes instead.
    """
    bits = k.bit_length() if among_all else (k - 1).bit_length()
    if len(robots) * k * rounds < SORT_VALUES or k < 2 or bits > HIGH_FROM:
        ids = np.asarray(robots, dtype=np.uint64)
        order: np.ndarray = _hashes(seed, round_no, ids, k, True, rounds).argsort(axis=1)
        if among_all:  # (each round's rows in turn)
            rows = order if rounds == 1 else order.reshape(rounds, len(ids), k)
            rows += rows >= ids.view(np.int64)[:, None]
        return order
    ids, low = _rows(tuple(robots), k, among_all)
    z = _hashes(seed, round_no, ids, k, False, rounds)
    z &= _high_mask(bits)  # the hash's high bits, then the index in the low ones
    if rounds == 1:
        z |= low
    else:
        z.reshape(rounds, len(ids), k)[...] |= low
    z.sort(axis=1)
    # sorted, a row's values are distinct; neighbours 2^HIGH_FROM apart or more differ in the
    # high bits, so such a row is in its hashes' order (a sieve across the rows first, at once)
    flat = z.reshape(-1)
    steps = np.subtract(flat[1:], flat[:-1], out=scratch("view_orders", (len(flat) - 1,), _U64))
    if steps[steps.argmin()] < _NEAR:
        return _redo(z, seed, round_no, ids, k, bits, among_all)
    z &= _low_mask(bits)
    return z.view(np.int64)


def _redo(
    z: np.ndarray, seed: int, round_no: int, ids: np.ndarray, k: int, bits: int, among_all: bool
) -> np.ndarray:
    """`view_orders`' sorted values `z` (rounds * m, k) as the order: the index in each one's
    low bits, but in every row where two neighbours are less than 2^HIGH_FROM apart (their high
    bits may be the same), the argsort of that row's whole hashes."""
    near = (z[:, 1:] - z[:, :-1] < _NEAR).any(axis=1)
    z &= _low_mask(bits)
    order = z.view(np.int64)
    m = len(ids)
    for row in np.flatnonzero(near).tolist():  # a few rows in a thousand, at n = 256
        robot = ids[row % m : row % m + 1]
        redone = _hashes(seed, round_no + row // m, robot, k).argsort(axis=1)
        if among_all:
            redone += redone >= robot.view(np.int64)[:, None]
        order[row] = redone[0]
    return order


@functools.lru_cache(maxsize=4)
def _rows(robots: tuple[int, ...], k: int, among_all: bool) -> tuple[np.ndarray, np.ndarray]:
    """`robots` as uint64 (m,), and what `view_orders` puts in the low bits of a row's k hashes:
    with `among_all`, (m, k) j + 1 where j >= robots[i], else j (index j among robot robots[i]'s
    others as one among all robots), else (k,) j; read-only (the same robots look every fsync
    round)."""
    ids = np.array(robots, dtype=np.uint64)
    j = np.arange(k, dtype=np.uint64)
    low = j[None, :] + (j[None, :] >= ids[:, None]) if among_all else j
    ids.flags.writeable = low.flags.writeable = False
    return ids, low


@functools.lru_cache(maxsize=64)
def _high_mask(bits: int) -> np.ndarray:
    """Every bit but the lowest `bits` (uint64, 0-d)."""
    return _constant(_MASK64 ^ ((1 << bits) - 1))


@functools.lru_cache(maxsize=64)
def _low_mask(bits: int) -> np.ndarray:
    """The lowest `bits` bits (uint64, 0-d)."""
    return _constant((1 << bits) - 1)


@functools.lru_cache(maxsize=16)
def _round_key(seed: int, round_no: int) -> np.ndarray:
    """The key of round `round_no`'s views (uint64, 0-d): what each robot's id is mixed with
    (every Look of a round asks it)."""
    return _constant(_mix64(_mix64(LOOK_STREAM ^ (seed & _MASK64)) ^ round_no))


def _hashes(
    seed: int,
    round_no: int,
    robots: Sequence[int] | np.ndarray,
    k: int,
    last: bool = True,
    rounds: int = 1,
) -> np.ndarray:
    """(m, k) uint64: the keyed splitmix64 hash of index j (1-based) of robot robots[i]'s view
    in round `round_no`, what `view_orders` sorts (a new array); without the finaliser's last
    step, x ^ (x >> 31), unless `last`. With `rounds`, (rounds * m, k): those of round_no,
    round_no + 1, ... one after the other."""
    ids = np.asarray(robots, dtype=np.uint64)
    if rounds == 1:
        x = np.bitwise_xor(ids, _round_key(seed, round_no))
    else:
        keys = np.arange(round_no, round_no + rounds, dtype=np.uint64)
        keys ^= _constant(_mix64(LOOK_STREAM ^ (seed & _MASK64)))
        x = np.bitwise_xor(_mix64_all(keys)[:, None], ids).reshape(-1)
    z: np.ndarray = np.add(_spread(k), _mix64_all(x)[:, None])
    t = scratch("view_orders", z.shape, _U64)  # in place: fresh arrays cost page faults
    np.right_shift(z, _S30, out=t)
    z ^= t
    z *= _C2
    np.right_shift(z, _S27, out=t)
    z ^= t
    z *= _C3
    if last:
        np.right_shift(z, _S31, out=t)
        z ^= t
    return z


def _mix64_all(x: np.ndarray) -> np.ndarray:
    """`_mix64` of every value of `x` (uint64, changed in place: returned); uint64 arrays wrap
    silently, as the hash does."""
    x += _C1
    t = x >> _S30
    x ^= t
    x *= _C2
    np.right_shift(x, _S27, out=t)
    x ^= t
    x *= _C3
    np.right_shift(x, _S31, out=t)
    x ^= t
    return x


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
_U64: Final = np.dtype(np.uint64)


def _constant(value: int) -> np.ndarray:
    """A uint64 constant as a read-only 0-d array: numpy takes one faster than a scalar."""
    out = np.array(value, dtype=np.uint64)
    out.flags.writeable = False
    return out


# splitmix64's constants (0-d uint64 arrays)
_C1, _C2, _C3 = (_constant(c) for c in (0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB))
_S30, _S27, _S31 = _constant(30), _constant(27), _constant(31)
_NEAR: Final = _constant(1 << HIGH_FROM)


@functools.lru_cache(maxsize=8)
def _spread(k: int) -> np.ndarray:
    """(1..k) times splitmix64's increment: the per-index part of view_order's hash (read-only)."""
    out: np.ndarray = np.arange(1, k + 1, dtype=np.uint64) * _C1
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
