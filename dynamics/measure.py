"""Estimators of sampled motion: what the viewer's readouts and the recordings' manifests measure.

Each function takes samples of a run, times ``t`` [s] (K,) and states or coordinates at those
times, and returns the quantity a reader compares with theory as an :class:`Estimate`. The
viewer (on the samples its exhibit keeps) and the recorder (on the frames it wrote) call the same
functions, so one motion gives one number. An estimate the samples cannot support is not a
guess: it has no value and says why (``Estimate.reason``, its first words the kind): aliased
(the motion turns too far between samples to tell its rate; samples beyond the Nyquist limit are
those of a slower motion, as clean, so the estimators take the frequency theory predicts,
``expected``, and refuse what it puts beyond their reach), too short (an arc, too few
crossings), drift (the mean moving), two frequencies (crossings wandering more than noise
explains), too little growth, or noise leaving the figure uncertain beyond the estimator's
stated accuracy.

The estimators are built for frames at 10-60 per second with measurement noise: fits are made on
centred data, circles by their geometric distance, zero crossings with hysteresis and with the
mean removed, and derivatives with the known bias of their differences removed. Their accuracy at
those frame rates, exact and with 0.1 % noise, is measured in ``tests/test_measure.py`` and stated
in the manual (docs/recording.md).

Conventions: angles in radians, frequencies in rad/s, SI units otherwise; states in the layout of
their system module
(:mod:`mechviz.dynamics.cyclotron`, :mod:`mechviz.dynamics.disk`, :mod:`mechviz.dynamics.hoop`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import disk
from .crossings import (  # noqa: F401
    MAX_DRIFT,
    _cubic_root,
    _drifting,
    _period_means,
    _root_between,
    _sinusoid_noise,
    _zero_crossings,
)

#: The largest turn between consecutive samples [rad] a rate is read from: beyond a quarter turn
#: the sense and size of the turn are no longer safely told apart from an alias.
MAX_TURN_PER_SAMPLE = 0.5 * math.pi


@dataclass(frozen=True, eq=False)
class Estimate:
    """A measured ``value`` or, when the samples cannot support one, ``None`` and the
    ``reason`` in a few words. True when resolved; :meth:`text` shows the value or
    ``"not resolved (reason)"``."""

    value: Any = None
    reason: str = ""

    def __post_init__(self) -> None:
        if (self.value is None) == (not self.reason):
            raise ValueError("an Estimate has a value or a reason, not both or neither")

    def __bool__(self) -> bool:
        return self.value is not None

    def text(self, digits: int = 4) -> str:
        """The value to ``digits`` significant digits, or ``"not resolved (reason)"``."""
        if self.value is None:
            return f"not resolved ({self.reason})"
        return f"{float(self.value):.{digits}g}"


def unresolved(reason: str) -> Estimate:
    """No estimate, for ``reason``."""
    return Estimate(None, reason)


def slope(t: np.ndarray, y: np.ndarray) -> float | None:
    """Least-squares slope of ``y`` against ``t``; ``None`` with fewer than two samples."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    if len(t) < 2 or np.ptp(t) <= 0.0:
        return None
    tc = t - t.mean()
    return float(tc @ (y - y.mean()) / (tc @ tc))


def _slope_and_error(t: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Least-squares slope of ``y`` against ``t`` and its standard error (from the residuals)."""
    tc = t - t.mean()
    yc = y - y.mean()
    s = float(tc @ yc / (tc @ tc))
    r = yc - s * tc
    return s, math.sqrt(float(r @ r) / max(len(t) - 2, 1) / float(tc @ tc))


def noise_level(y: np.ndarray) -> float:
    """Standard deviation of white noise on a smooth sampled signal ``y`` (K, ...), from the
    median absolute third difference (a smooth signal's third differences are small; white
    noise's have variance ``20 sigma^2``). The largest over the trailing axes."""
    y = np.asarray(y, float).reshape(len(y), -1)
    if len(y) < 8:
        return 0.0
    d3 = np.diff(y, 3, axis=0)
    mad = np.median(np.abs(d3 - np.median(d3, axis=0)), axis=0)
    return float(np.max(1.4826 * mad / math.sqrt(20.0)))


def _beyond_theory(
    t: np.ndarray, expected: float | None, limit: float, what: str
) -> Estimate | None:
    """ "aliased" if the frequency theory predicts, ``expected`` [rad/s], advances the motion more
    than ``limit`` rad between some two samples, else None. Samples of a motion beyond the
    Nyquist limit (pi a sample) are those of a slower one, as clean: only theory tells them
    apart, so an estimator that is told what theory predicts refuses rather than read the
    alias."""
    if expected is None or len(t) < 2:
        return None
    worst = abs(float(expected)) * float(np.max(np.diff(t)))
    if worst > limit:
        return unresolved(
            f"aliased: at the {abs(float(expected)):.4g} rad/s theory predicts, {what} "
            f"{worst:.2g} rad between samples (at most {limit:.2g} is read; the Nyquist limit "
            "is pi)"
        )
    return None


def _wrapped(a: np.ndarray) -> np.ndarray:
    """Angles wrapped to ``[-pi, pi)``."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


# --------------------------------------------------------------------------- cyclotron
def gyrofrequency(
    t: np.ndarray,
    v_perp: np.ndarray,
    *,
    xy: np.ndarray | None = None,
    min_turn: float = 0.5,
    max_uncertainty: float = 3e-5,
    expected: float | None = None,
) -> Estimate:
    """Magnitude of the rate of turn [rad/s] of the transverse velocity ``v_perp`` (K, 2), or
    (K, N, 2) for an ensemble (the value is then the per-member rates): the least-squares slope of its angle.

    The velocity of a charge in a uniform field turns at the gyrofrequency whatever its speed;
    a slope over the whole stretch averages out the step-to-step jitter of an integrator.
    Not resolved: before the velocity has turned by ``min_turn`` rad (a shorter arc cannot tell
    a frequency from its neighbours to the digits shown); when it turns more than a quarter turn
    between samples (aliased: a turn of ``phi`` and one of ``phi - 2 pi`` look alike); when the
    positions ``xy`` (K, 2) (or (K, N, 2)), if given, do not move the distance that rate implies
    (an alias the velocity alone cannot reveal); when the rate theory predicts, ``expected``
    [rad/s] if given, turns the velocity more than a quarter turn between samples (an alias by a
    whole turn a sample looks like a slow, clean turn: only theory or the positions reveal it);
    when noise leaves the slope uncertain by more than ``max_uncertainty`` of itself."""
    v = np.asarray(v_perp, float)
    t = np.asarray(t, float)
    if v.ndim == 3:
        rates = []
        for j in range(v.shape[1]):
            e = gyrofrequency(
                t,
                v[:, j],
                xy=None if xy is None else np.asarray(xy)[:, j],
                min_turn=min_turn,
                max_uncertainty=max_uncertainty,
                expected=expected,
            )
            if not e:
                return unresolved(f"member {j}: {e.reason}")
            rates.append(e.value)
        return Estimate(np.asarray(rates))
    if len(t) < 3:
        return unresolved("too short: fewer than 3 samples")
    beyond = _beyond_theory(t, expected, MAX_TURN_PER_SAMPLE, "the velocity turns")
    if beyond is not None:
        return beyond
    step = _wrapped(np.diff(np.arctan2(v[:, 1], v[:, 0])))
    worst = float(np.max(np.abs(step)))
    if worst > MAX_TURN_PER_SAMPLE:
        return unresolved(f"aliased: the velocity turns up to {worst:.2g} rad between samples")
    turned = abs(float(np.sum(step)))
    if turned < min_turn:
        return unresolved(f"too short: the velocity has turned {turned:.2g} of {min_turn:g} rad")
    angle = np.concatenate([[0.0], np.cumsum(step)])
    s, se = _slope_and_error(t, angle)
    if se > max_uncertainty * abs(s):
        return unresolved(f"noise: the rate is uncertain by {se / abs(s):.1g} of itself")
    if xy is not None:
        speed = np.hypot(v[:, 0], v[:, 1])
        chord = np.linalg.norm(np.diff(np.asarray(xy, float), axis=0), axis=1)
        dt = np.diff(t)
        expected = (speed[:-1] + speed[1:]) * np.abs(np.sin(0.5 * s * dt)) / abs(s)
        ratio = float(np.median(chord / np.maximum(expected, 1e-300)))
        if not 0.8 < ratio < 1.25:
            return unresolved(
                f"aliased: the charge moves {ratio:.2g} times the distance this rate implies"
            )
    return Estimate(abs(s))


def fit_circle(xy: np.ndarray, *, min_arc: float = 0.5, max_uncertainty: float = 3e-4) -> Estimate:
    """Circle through points (K, 2): value ``(centre (2,), radius)`` [m].

    The points are centred and scaled first (a circle far from the origin loses no digits),
    fitted algebraically (Kasa), and the fit refined to least squares of the geometric distance
    ``|x - c| - r``, which, unlike the algebraic fit, is not biased towards small circles on a
    short noisy arc. Not resolved: fewer than three points, points on a line, an arc below
    ``min_arc`` rad about the centre, or a radius uncertain (from the residuals) by more than
    ``max_uncertainty`` of itself."""
    xy = np.asarray(xy, float)
    if len(xy) < 3:
        return unresolved("fewer than 3 points")
    mid = xy.mean(axis=0)
    scale = float(np.max(np.abs(xy - mid)))
    if scale == 0.0:
        return unresolved("all points coincide")
    p = (xy - mid) / scale
    A = np.column_stack([2 * p[:, 0], 2 * p[:, 1], np.ones(len(p))])
    sol, _res, rank, _sv = np.linalg.lstsq(A, (p * p).sum(axis=1), rcond=None)
    if rank < 3:
        return unresolved("the points lie on a line")
    cx, cy, c = sol
    r0 = math.sqrt(max(c + cx * cx + cy * cy, 0.0))
    if not r0 < 1e6:
        return unresolved("the points lie on a line")
    from scipy.optimize import least_squares  # deferred: importing dynamics should not pay

    def residuals(q):
        return np.hypot(p[:, 0] - q[0], p[:, 1] - q[1]) - q[2]

    def jacobian(q):
        d = np.hypot(p[:, 0] - q[0], p[:, 1] - q[1])
        d = np.where(d > 0.0, d, 1.0)
        return np.column_stack([(q[0] - p[:, 0]) / d, (q[1] - p[:, 1]) / d, -np.ones(len(p))])

    fit = least_squares(
        residuals, [cx, cy, r0], jac=jacobian, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    (cx, cy, r) = fit.x
    r = abs(r)
    angle = np.arctan2(p[:, 1] - cy, p[:, 0] - cx)
    arc = abs(float(np.sum(_wrapped(np.diff(angle)))))
    if arc < min_arc:
        return unresolved(f"too short an arc: {arc:.2g} of {min_arc:g} rad")
    J = fit.jac
    dof = max(len(p) - 3, 1)
    sigma2 = float(fit.fun @ fit.fun) / dof
    try:
        var_r = float(np.linalg.inv(J.T @ J)[2, 2]) * sigma2
    except np.linalg.LinAlgError:
        return unresolved("the points do not fix a circle")
    if math.sqrt(max(var_r, 0.0)) > max_uncertainty * r:
        return unresolved(
            f"noise on a short arc: the radius is uncertain by {math.sqrt(var_r) / r:.1g}"
        )
    return Estimate((mid + scale * np.array([cx, cy]), float(r * scale)))


# --------------------------------------------------------------------------- oscillations


def crossing_frequency(
    t: np.ndarray,
    y: np.ndarray,
    *,
    min_crossings: int = 3,
    hysteresis: float = 0.1,
    max_uncertainty: float = 1e-4,
    expected: float | None = None,
) -> Estimate:
    """Angular frequency [rad/s] of an oscillating coordinate ``y`` (K,) from its zero crossings,
    up and down, each half a period apart.

    The mean is removed (over whole periods, between crossings of the same direction); a
    crossing counts only once ``y`` has gone from beyond ``-band`` to beyond ``band`` (or back),
    ``band`` the larger of ``hysteresis`` times the amplitude and four times the noise level, so
    noise near zero does not add crossings; and the crossing times ``t_k`` are fitted as
    ``t_0 + k T/2 + (-1)^k d``, the alternating term taking up any difference between the
    up and the down half periods (an offset, an asymmetric wave).

    Samples of an oscillation beyond the Nyquist limit (pi a sample) are those of a slower one,
    just as clean: given ``expected``, the frequency [rad/s] theory predicts (the highest the
    motion may have), the estimate is refused as aliased when that advances more than a quarter
    turn between samples. Not resolved, with the reason: "aliased" (that, or fewer than two
    samples per half period); "too short" (below ``min_crossings`` crossings: one full period at
    least); "noise" (above a fifth of the amplitude, or leaving the half period uncertain from
    the fit's residuals by more than ``max_uncertainty`` of itself, the crossings wandering as
    much as the noise explains); "drift" (the mean moving steadily by more than
    :data:`MAX_DRIFT` of the amplitude, or the crossings wandering with it); "two frequencies"
    (the crossings wandering more than noise explains, without a drift)."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    if len(y) < 4:
        return unresolved("too short: fewer than 4 samples")
    beyond = _beyond_theory(t, expected, 0.5 * math.pi, "it advances")
    if beyond is not None:
        return beyond
    y = y - y.mean()
    amp = 0.5 * float(np.percentile(y, 98) - np.percentile(y, 2))
    if not amp > 0.0:
        return unresolved("no oscillation")
    sigma = min(noise_level(y), _sinusoid_noise(y))
    if sigma > 0.2 * amp:
        return unresolved(f"noise: {sigma / amp:.1g} of the amplitude")
    band = max(hysteresis * amp, 4.0 * sigma)
    tc = _zero_crossings(t, y, band)
    if len(tc) >= 3:  # remove the mean over the whole periods between the crossings
        end = len(tc) - 1 if (len(tc) - 1) % 2 == 0 else len(tc) - 2
        inside = (t >= tc[0]) & (t <= tc[end])
        if inside.sum() >= 2:
            ti, yi = t[inside], y[inside]
            y = y - float(np.sum(0.5 * (yi[1:] + yi[:-1]) * np.diff(ti))) / (ti[-1] - ti[0])
            tc = _zero_crossings(t, y, band)
    if len(tc) < min_crossings:
        return unresolved(f"too short: {len(tc)} zero crossings of the {min_crossings} needed")
    half = np.median(np.diff(tc))
    if half < 2.0 * np.median(np.diff(t)):
        return unresolved("aliased: fewer than two samples per half period")
    gap = max(float(tc[0] - t[0]), float(np.max(np.diff(tc))), float(t[-1] - tc[-1]))
    if gap > 3.0 * half:  # an oscillation about a fixed mean crosses it every half period
        return unresolved(f"drift: no zero crossing for {gap:.2g} s, {gap / half:.2g} half periods")
    tc = _zero_crossings(t, y, band, math.pi / half)  # located again, knowing the frequency
    means = _period_means(t, y, tc, math.pi / half)
    moved = _drifting(means, amp, MAX_DRIFT)
    if moved is not None:
        return unresolved(f"drift: the mean moves by {moved:.2g} of the amplitude")
    k = np.arange(len(tc), dtype=float)
    A = np.column_stack([np.ones_like(k), k, (-1.0) ** k])
    coef, *_ = np.linalg.lstsq(A, tc - tc[0], rcond=None)
    for _ in range(3):  # located again at the fitted frequency, until it no longer moves
        again = _zero_crossings(t, y, band, math.pi / float(coef[1]))
        if len(again) != len(tc):
            break
        previous, tc = float(coef[1]), again
        coef, *_ = np.linalg.lstsq(A, tc - tc[0], rcond=None)
        if abs(float(coef[1]) - previous) < 1e-14 * previous:
            break
    half_period = float(coef[1])
    if len(tc) > 3:
        r = A @ coef - (tc - tc[0])
        var = float(r @ r) / (len(tc) - 3) * float(np.linalg.inv(A.T @ A)[1, 1])
        if math.sqrt(var) > max_uncertainty * half_period:
            spread = math.sqrt(float(r @ r) / (len(tc) - 3))
            # a crossing's time jitters by the noise over the slope there, amp w
            jitter = sigma * half_period / (math.pi * amp)
            what = f"the period is uncertain by {math.sqrt(var) / half_period:.1g} of itself"
            if spread <= 3.0 * jitter:
                return unresolved(f"noise: {what}")
            if _drifting(means, amp, 0.0) is not None:
                return unresolved(f"drift: {what}, the mean moving steadily")
            return unresolved(
                f"two frequencies: {what}, the crossings wandering by {spread:.2g} s, "
                "more than noise explains"
            )
    return Estimate(math.pi / half_period)


def mode_frequencies(
    t: np.ndarray,
    angles: np.ndarray,
    shapes: np.ndarray,
    *,
    min_share: float = 0.02,
    expected=None,
) -> list[Estimate]:
    """Frequencies [rad/s] of the hoop's two normal modes measured from the angles (K, 2).

    The angles are projected on the mode ``shapes`` (rows, :func:`mechviz.dynamics.hoop.normal_modes`),
    giving the modal coordinates, and each is timed by :func:`crossing_frequency`, told the
    frequency ``expected[k]`` theory gives it if given (linear theory's: a swing's frequency is
    below it), so that a mode too fast for the samples is refused as aliased rather than read
    at its alias. A mode whose coordinate stays below ``min_share`` of the larger one is not
    excited: not resolved."""
    q = modal_coordinates(angles, shapes)
    peak = np.abs(q).max(axis=0) if len(q) else np.zeros(2)
    top = float(peak.max()) if len(q) else 0.0
    theory = (None, None) if expected is None else tuple(float(x) for x in expected)
    return [
        crossing_frequency(t, q[:, k], expected=theory[k])
        if top > 0 and peak[k] > min_share * top
        else unresolved("not excited")
        for k in range(2)
    ]


def modal_coordinates(angles: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """Coordinates (K, 2) of the angles (K, 2) on the mode shapes: ``angles = q @ shapes``."""
    return np.linalg.solve(np.asarray(shapes, float).T, np.asarray(angles, float).T).T


# --------------------------------------------------------------------------- disk
def bearing_force(p: disk.DiskParams, t: np.ndarray, angle: np.ndarray, omega) -> np.ndarray:
    """Force at bearing B [N] (K, 3) of the driven disk, measured from its motion.

    ``L(t) = R(angle) I_A omega y`` about A, the torque ``N = dL/dt`` from differences over the
    samples, and ``F_B = -(y x N) / 2R`` (the bearings are 2R apart on the axle ``y``,
    :mod:`mechviz.dynamics.disk`). The difference of a vector turning by ``2 theta`` between two samples
    is its derivative times ``sin(theta) / theta``; that known factor is divided out, with
    ``theta`` half the sampled turn, so a uniform rotation gives its torque exactly at any frame
    rate below the aliasing limit. Central differences inside, one-sided at the two ends (there
    the direction is half a sample off). Needs at least two samples."""
    t = np.asarray(t, float)
    angle = np.asarray(angle, float)
    omega = np.broadcast_to(np.asarray(omega, float), t.shape)
    body = disk.inertia_tensor(p) @ disk.AXLE
    L = np.einsum("kij,j->ki", disk.rotation_about_axle(angle), body) * omega[:, None]
    n = len(t)
    lo = np.concatenate([[0], np.arange(n - 2), [n - 2]])
    hi = np.concatenate([[1], np.arange(2, n), [n - 1]])
    half = 0.5 * (angle[hi] - angle[lo])
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(half != 0.0, half / np.sin(half), 1.0)
    N = (L[hi] - L[lo]) / (t[hi] - t[lo])[:, None] * factor[:, None]
    return -np.cross(disk.AXLE, N) / (2.0 * p.radius)


def bearing_force_amplitude(
    p: disk.DiskParams, t: np.ndarray, angle: np.ndarray, omega
) -> Estimate:
    """Median magnitude [N] of :func:`bearing_force` over the inner samples (uniform rotation: a
    constant magnitude that turns with the disk). Not resolved below three samples or when the
    disk turns more than a quarter turn between samples (aliased)."""
    if len(t) < 3:
        return unresolved("fewer than 3 samples")
    turn = float(np.max(np.abs(np.diff(np.asarray(angle, float)))))
    if turn > MAX_TURN_PER_SAMPLE:
        return unresolved(f"aliased: the disk turns {turn:.2g} rad between samples")
    F = bearing_force(p, t, angle, omega)[1:-1]
    return Estimate(float(np.median(np.linalg.norm(F, axis=1))))


def wobble_growth_rate(
    t: np.ndarray,
    w_body: np.ndarray,
    *,
    saturation: float = 0.03,
    min_growth: float = 2.0,
    max_uncertainty: float = 1e-3,
) -> Estimate:
    """Growth rate [1/s] of a wobble about the intermediate axis from body angular velocities
    (K, 3) in the principal frame about the centre of mass (spin along the second axis).

    In linear theory each wobble component is ``c e^(lambda t) + d e^(-lambda t)``: the growing
    mode and a decaying one, comparable at the start (a wobble started along one axis is a
    cosh). Both components are fitted to that form, sharing ``lambda``, by least squares of
    their relative deviation (noise-weighted) over the samples before the wobble first exceeds
    ``saturation`` of the spin (beyond it the spin itself changes), so the decaying transient
    does not bias the rate however soon the fit starts. Not resolved: fewer than six samples in
    that stretch, a wobble growing less than ``min_growth`` times above the noise in it, or a
    rate uncertain (from the fit's residuals) by more than ``max_uncertainty`` of itself."""
    t, w = np.asarray(t, float), np.asarray(w_body, float)
    if len(w) < 6:
        return unresolved("fewer than 6 samples")
    spin = abs(float(w[0, 1]))
    perp = np.hypot(w[:, 0], w[:, 2])
    over = perp > saturation * spin
    end = int(np.argmax(over)) if np.any(over) else len(perp)
    if end < 6:
        return unresolved(f"{end} samples before the wobble reaches {saturation:g} of the spin")
    t, u, perp = t[:end], w[:end][:, [0, 2]], perp[:end]
    floor = 3.0 * noise_level(u)
    growth = float(perp.max()) / max(float(perp.min()), floor, 1e-300)
    if growth < min_growth:
        return unresolved(f"too little growth: {growth:.2g} times of the {min_growth:g} needed")
    weight = 1.0 / np.sqrt(perp**2 + floor**2)
    half = len(t) // 2
    lam0 = slope(t[half:], np.log(np.maximum(perp[half:], floor + 1e-300)))
    if lam0 is None or not lam0 > 0.0:
        return unresolved("the wobble is not growing")

    def misfit(lam: float) -> float:
        B = np.column_stack([np.exp(lam * (t - t[-1])), np.exp(-lam * (t - t[0]))])
        Bw, uw = B * weight[:, None], u * weight[:, None]
        coef, *_ = np.linalg.lstsq(Bw, uw, rcond=None)
        r = Bw @ coef - uw
        return float(np.sum(r * r))

    from scipy.optimize import minimize_scalar  # deferred: importing dynamics should not pay

    try:  # a wobble at the edge of the doubles (1e-300 rad/s) can defeat the linear algebra
        with np.errstate(all="ignore"):
            best = minimize_scalar(
                misfit,
                bounds=(0.2 * lam0, 5.0 * lam0),
                method="bounded",
                options={"xatol": 1e-12 * lam0},
            )
            lam = float(best.x)
            # Its standard error from the misfit's curvature (Gauss-Newton: misfit'' = 2 J^T J),
            # the residual variance over 2 K - 5 degrees of freedom (two components, five
            # parameters).
            h = 1e-3 * lam
            curvature = (misfit(lam + h) - 2.0 * best.fun + misfit(lam - h)) / (h * h)
    except (np.linalg.LinAlgError, ValueError, FloatingPointError):
        return unresolved("the fit of the growth did not converge")
    if not (math.isfinite(lam) and math.isfinite(curvature) and math.isfinite(best.fun)):
        return unresolved("the fit of the growth did not converge")
    dof = max(2 * len(t) - 5, 1)
    se = math.sqrt(2.0 * max(best.fun, 0.0) / dof / curvature) if curvature > 0.0 else math.inf
    if se > max_uncertainty * lam:
        return unresolved(f"noise: the rate is uncertain by {se / lam:.1g} of itself")
    return Estimate(lam)


def wobble_growth_rate_theory(moments: np.ndarray, w0: np.ndarray) -> float:
    """Linear growth rate [1/s] of a wobble about the intermediate axis
    (:func:`mechviz.dynamics.disk.wobble_growth_rate`), the figure :func:`wobble_growth_rate` is
    compared with."""
    return disk.wobble_growth_rate(moments, w0)
