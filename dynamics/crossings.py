"""Where a sampled oscillation crosses zero, to well below a sample's spacing: the crossings'
times on the local cubic (or on a local sinusoid where that predicts the neighbouring samples
better), the mean over each period and the drift it shows (the helpers of
:func:`mechviz.dynamics.measure.crossing_frequency`)."""

from __future__ import annotations

import math

import numpy as np


def _zero_crossings(
    t: np.ndarray, y: np.ndarray, band: float, w: float | None = None
) -> np.ndarray:
    """Times where ``y`` passes from below ``-band`` to above ``band`` or back (hysteresis: a
    wobble inside the band is not a crossing). Each is located, when ``y`` changes sign once on
    the way, from the four samples about the sign change (:func:`_root_between`: the cubic
    through them, or given the frequency ``w`` the sinusoid if it fits better; a line's root is
    off by the curve's bend, 2e-5 of a period at 10 samples a half period); else (noise near
    zero) as the root of a least-squares line through the samples of that passage."""
    side = np.where(y > band, 1, np.where(y < -band, -1, 0))
    idx = np.nonzero(side)[0]
    if len(idx) < 2:
        return np.empty(0)
    change = np.nonzero(side[idx[:-1]] != side[idx[1:]])[0]
    out = []
    for k in change:
        a, b = idx[k], idx[k + 1]
        ys, ts = y[a : b + 1], t[a : b + 1]
        flips = np.nonzero(np.signbit(ys[:-1]) != np.signbit(ys[1:]))[0]
        if len(flips) == 1:
            out.append(_root_between(t, y, a + int(flips[0]), w))
        else:
            m, c = np.polyfit(ts - ts[0], ys, 1)
            out.append(ts[0] - c / m)
    return np.asarray(out)


def _root_between(t: np.ndarray, y: np.ndarray, j: int, w: float | None = None) -> float:
    """The zero of ``y`` between samples ``j`` and ``j + 1`` (which differ in sign), from the
    four samples ``j - 1 .. j + 2`` (at the record's ends the four nearest): of the cubic through
    them, or, given the frequency ``w``, of the least-squares ``c + a cos(w t) + b sin(w t)``
    through them if that predicts the next samples out better (a sinusoid's crossing exactly
    however few samples a period, where the cubic is off by ``(w dt)^4``; a swing far from a
    sinusoid's shape is the cubic's); of the line through the two where there are not four."""
    h = t[j + 1] - t[j]
    x = -y[j] * h / (y[j + 1] - y[j])
    if len(t) < 4:
        return float(t[j] + x)
    first = min(max(j - 1, 0), len(t) - 4)  # at the record's ends, the four samples nearest
    ts, ys = t[first : first + 4] - t[j], y[first : first + 4]
    c = np.polyfit(ts, ys, 3)
    root = _cubic_root(c, x, h)
    if w is None:
        return float(t[j] + root)
    A = np.column_stack([np.ones(4), np.cos(w * ts), np.sin(w * ts)])
    c0, ca, cb = np.linalg.lstsq(A, ys, rcond=None)[0]
    amp = math.hypot(ca, cb)
    if not amp > abs(c0):
        return float(t[j] + root)
    outer = [k for k in (first - 1, first + 4) if 0 <= k < len(t)]
    if outer:
        to = t[outer] - t[j]
        wave = c0 + ca * np.cos(w * to) + cb * np.sin(w * to)
        if np.sum((wave - y[outer]) ** 2) >= np.sum((np.polyval(c, to) - y[outer]) ** 2):
            return float(t[j] + root)
    # c0 + amp cos(w z - delta) = 0: w z = delta +- arccos(-c0 / amp)
    delta, spread = math.atan2(cb, ca), math.acos(-c0 / amp)
    for phase in (delta + spread, delta - spread):
        z = (phase % (2.0 * math.pi)) / w
        for cand in (z, z - 2.0 * math.pi / w):
            if -1e-9 * h <= cand <= h * (1 + 1e-9):
                return float(t[j] + cand)
    return float(t[j] + root)


def _cubic_root(c: np.ndarray, x: float, h: float) -> float:
    """The root in ``[0, h]`` of the cubic ``c`` (highest power first), whose ends differ in
    sign: Newton from ``x``, kept inside the bracket (bisection otherwise)."""
    lo, hi = 0.0, h
    f_lo = c[3]
    z = x
    for _ in range(60):
        f = ((c[0] * z + c[1]) * z + c[2]) * z + c[3]
        if f == 0.0:
            break
        if (f < 0) == (f_lo < 0):
            lo, f_lo = z, f
        else:
            hi = z
        d = (3.0 * c[0] * z + 2.0 * c[1]) * z + c[2]
        step = z - f / d if d != 0.0 else math.nan
        if abs(step - z) <= 1e-15 * h:
            return step
        z = step if lo <= step <= hi else 0.5 * (lo + hi)
        if hi - lo <= 1e-15 * h:
            break
    return z


def _sinusoid_noise(y: np.ndarray) -> float:
    """The noise's standard deviation if ``y`` (K,) is one sampled sinusoid, an offset and white
    noise: a sinusoid sampled at any rate obeys ``y[k+1] + y[k-1] = c y[k] + d`` exactly, so the
    residual of that fit is the noise's, of variance ``(2 + c^2) sigma^2``. Unlike the third
    differences (:func:`noise_level`), it does not mistake a clean oscillation a few samples a
    period for noise; a signal that is not one sinusoid leaves a larger residual."""
    if len(y) < 8:
        return math.inf
    A = np.column_stack([y[1:-1], np.ones(len(y) - 2)])
    b = y[2:] + y[:-2]
    coef, *_ = np.linalg.lstsq(A, b, rcond=None)
    r = b - A @ coef
    return math.sqrt(float(r @ r) / (len(b) - 2) / (2.0 + float(coef[0]) ** 2))


def _period_means(t: np.ndarray, y: np.ndarray, tc: np.ndarray, w: float) -> np.ndarray:
    """The mean of ``y`` over each whole period between crossings ``tc[k]`` and ``tc[k + 2]``:
    the constant of a least-squares ``m + a cos(w t) + b sin(w t)`` through its samples (exact
    for a sinusoid at any sampling, where a sum over the samples is not)."""
    out = []
    for k in range(len(tc) - 2):
        inside = (t >= tc[k]) & (t <= tc[k + 2])
        if inside.sum() < 4:
            continue
        ti = t[inside] - tc[k]
        A = np.column_stack([np.ones_like(ti), np.cos(w * ti), np.sin(w * ti)])
        out.append(np.linalg.lstsq(A, y[inside], rcond=None)[0][0])
    return np.asarray(out)


def _drifting(means: np.ndarray, amp: float, threshold: float) -> float | None:
    """How far the period means move, as a fraction of ``amp``, if they move steadily (one way:
    a drift, not the beat of a second frequency) by more than ``threshold`` of it; else None."""
    if len(means) < 3:
        return None
    moved = float(np.ptp(means)) / amp
    k = np.arange(len(means), dtype=float)
    if moved > threshold and abs(float(np.corrcoef(k, means)[0, 1])) > 0.9:
        return moved
    return None


#: A steady drift of the period means beyond this fraction of the amplitude is refused.
MAX_DRIFT = 0.05
