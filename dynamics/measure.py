"""Estimators of sampled motion: what the viewer's readouts and the recordings' manifests measure.

Each function takes samples of a run, times ``t`` [s] (K,) and states or coordinates at those
times, and returns the quantity a reader compares with theory. The viewer (on the samples its
exhibit keeps) and the recorder (on the frames it wrote) call the same functions, so one motion
gives one number. ``None`` means the samples cannot support an estimate (too short a stretch,
too few crossings); it is never a guess.

Conventions: angles in radians, frequencies in rad/s, SI units otherwise; states in the layout of
their system module (:mod:`dynamics.cyclotron`, :mod:`dynamics.disk`, :mod:`dynamics.hoop`).
"""

from __future__ import annotations

import math

import numpy as np

from . import disk


def slope(t: np.ndarray, y: np.ndarray) -> float | None:
    """Least-squares slope of ``y`` against ``t``; ``None`` with fewer than two samples."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    if len(t) < 2 or np.ptp(t) <= 0.0:
        return None
    tc = t - t.mean()
    return float(tc @ (y - y.mean()) / (tc @ tc))


def gyrofrequency(t: np.ndarray, v_perp: np.ndarray, *, min_turn: float = 0.5) -> float | None:
    """|rate of turn| [rad/s] of the transverse velocity ``v_perp`` (K, 2), or (K, N, 2) for an
    ensemble (returns the per-member rates then): the least-squares slope of its unwrapped angle.

    The velocity of a charge in a uniform field turns at the gyrofrequency whatever its speed;
    a slope over the whole stretch averages out the step-to-step jitter of an integrator.
    ``None`` until the velocity has turned by ``min_turn`` rad (a shorter arc cannot tell a
    frequency from its neighbours to the digits shown)."""
    v = np.asarray(v_perp, float)
    ang = np.unwrap(np.arctan2(v[..., 1], v[..., 0]), axis=0)
    if len(ang) < 3:
        return None
    if v.ndim == 3:
        rates = [gyrofrequency(t, v[:, j], min_turn=min_turn) for j in range(v.shape[1])]
        return None if any(r is None for r in rates) else np.asarray(rates)  # type: ignore[return-value]
    if abs(ang[-1] - ang[0]) < min_turn:
        return None
    s = slope(t, ang)
    return None if s is None else abs(s)


def fit_circle(xy: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Least-squares (Kasa) circle through points (K, 2): ``(centre (2,), radius)`` [m], or
    ``None`` with fewer than three points or points on a line."""
    xy = np.asarray(xy, float)
    if len(xy) < 3:
        return None
    x, y = xy[:, 0], xy[:, 1]
    A = np.column_stack([2 * x, 2 * y, np.ones_like(x)])
    sol, _res, rank, _sv = np.linalg.lstsq(A, x * x + y * y, rcond=None)
    if rank < 3:
        return None
    cx, cy, c = sol
    return np.array([cx, cy]), float(math.sqrt(max(c + cx * cx + cy * cy, 0.0)))


def crossing_frequency(t: np.ndarray, y: np.ndarray) -> float | None:
    """Angular frequency [rad/s] of an oscillating coordinate ``y`` (K,): ``pi`` over the mean
    spacing of its zero crossings (every crossing, up and down, is a half period; crossings are
    located by linear interpolation between samples). ``None`` below two crossings."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    if len(y) < 2:
        return None
    idx = np.nonzero(np.signbit(y[:-1]) != np.signbit(y[1:]))[0]
    idx = idx[(y[idx] != 0) | (y[idx + 1] != 0)]
    if len(idx) < 2:
        return None
    tc = t[idx] - y[idx] * (t[idx + 1] - t[idx]) / (y[idx + 1] - y[idx])
    return math.pi * (len(tc) - 1) / (tc[-1] - tc[0])


def mode_frequencies(
    t: np.ndarray, angles: np.ndarray, shapes: np.ndarray, *, min_share: float = 0.02
) -> list[float | None]:
    """Frequencies [rad/s] of the hoop's two normal modes measured from the angles (K, 2).

    The angles are projected on the mode ``shapes`` (rows, :func:`dynamics.hoop.normal_modes`),
    giving the modal coordinates, and each is timed by :func:`crossing_frequency`. A mode whose
    coordinate stays below ``min_share`` of the larger one is not excited: ``None``."""
    q = modal_coordinates(angles, shapes)
    peak = np.abs(q).max(axis=0) if len(q) else np.zeros(2)
    top = float(peak.max()) if len(q) else 0.0
    return [
        crossing_frequency(t, q[:, k]) if top > 0 and peak[k] > min_share * top else None
        for k in range(2)
    ]


def modal_coordinates(angles: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """Coordinates (K, 2) of the angles (K, 2) on the mode shapes: ``angles = q @ shapes``."""
    return np.linalg.solve(np.asarray(shapes, float).T, np.asarray(angles, float).T).T


def bearing_force(p: disk.DiskParams, t: np.ndarray, angle: np.ndarray, omega) -> np.ndarray:
    """Force at bearing B [N] (K, 3) of the driven disk, measured from its motion.

    ``L(t) = R(angle) I_A omega y`` about A, the torque ``N = dL/dt`` by second-order central
    differences over the samples, and ``F_B = -(y x N) / 2R`` (the bearings are 2R apart on the
    axle ``y``, :mod:`dynamics.disk`). Needs at least three samples."""
    t = np.asarray(t, float)
    omega = np.broadcast_to(np.asarray(omega, float), t.shape)
    body = disk.inertia_tensor(p) @ disk.AXLE
    L = np.einsum("kij,j->ki", disk.rotation_about_axle(np.asarray(angle, float)), body)
    L = L * omega[:, None]
    N = np.gradient(L, t, axis=0, edge_order=2)
    return -np.cross(disk.AXLE, N) / (2.0 * p.radius)


def bearing_force_amplitude(
    p: disk.DiskParams, t: np.ndarray, angle: np.ndarray, omega
) -> float | None:
    """Median magnitude [N] of :func:`bearing_force` (uniform rotation: a constant magnitude that
    turns with the disk); ``None`` below three samples."""
    if len(t) < 3:
        return None
    return float(np.median(np.linalg.norm(bearing_force(p, t, angle, omega), axis=1)))


def wobble_growth_rate(t: np.ndarray, w_body: np.ndarray) -> float | None:
    """Growth rate [1/s] of a wobble about the intermediate axis from body angular velocities
    (K, 3) in the principal frame about the centre of mass (spin along the second axis): the
    slope of ``log |w_perp|`` while the wobble lies between 3x its start and 3 % of the spin.
    ``None`` with fewer than four samples in that stretch."""
    w = np.asarray(w_body, float)
    if len(w) < 4:
        return None
    perp = np.hypot(w[:, 0], w[:, 2])
    spin = abs(w[0, 1])
    lo, hi = 3 * max(perp[0], 1e-12), 0.03 * spin
    first_big = int(np.argmax(perp > hi)) if np.any(perp > hi) else len(perp)
    sel = (np.arange(len(perp)) < first_big) & (perp > lo)
    if sel.sum() < 4:
        return None
    return slope(np.asarray(t, float)[sel], np.log(perp[sel]))


def wobble_growth_rate_theory(moments: np.ndarray, w0: np.ndarray) -> float:
    """Linear growth rate [1/s] of a wobble about the intermediate axis of principal moments
    ``I1 < I2 < I3``: ``|w2| sqrt((I2 - I1)(I3 - I2) / (I1 I3))``."""
    i1, i2, i3 = (float(m) for m in moments)
    return abs(float(w0[1])) * math.sqrt((i2 - i1) * (i3 - i2) / (i1 * i3))
