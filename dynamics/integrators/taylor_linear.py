"""Taylor's method on the charge's linear flow, with its recurrences summed in closed form.

The charge in a uniform field along z has ``r' = v``, ``v' = Omega (vy, -vx, 0)``: the
transverse velocity's series is ``v^[k] = (Omega^k / k!) J^k v`` with ``J (vx, vy) = (vy, -vx)``
and ``J^2 = -1``. Truncated at order ``p`` and evaluated at a step ``h`` (``theta = Omega h``) it
is therefore ``C v + S J v``, with ``C`` and ``S`` the cosine's and sine's series truncated at
``p``; the position's is ``r + h (C1 v + S1 J v)`` with ``C1 = sum theta^k / (k+1)!`` over the
even ``k < p`` (alternating) and ``S1`` over the odd; ``z`` moves by ``h vz``. The same
polynomial as the generic expansion and Horner's evaluation (:mod:`.taylor`), in four
scalar series of ``theta^2`` and a 2x2 update per step, instead of six series of ``p`` terms. A
step whose phase exceeds 1 is taken as ``2^n`` equal substeps of that polynomial (composed in
closed form, :func:`series_at`), which keeps the alternating sums from cancelling; the
positions are summed with compensation (:func:`_flow`).

The step is Jorba and Zou's rule of :mod:`.taylor` with the transverse speed's Euclidean norm
``|v_perp|`` in place of the largest component of the last two orders' coefficients: the
series' own size, the same at every phase of the gyration (at most 2^(1/(2p)) smaller a step
than the componentwise rule). ``|v_perp|`` is conserved by the flow, so the step changes only
with the state's size through the relative tolerance, and the four series are summed again only
when it does.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit

MAX_ORDER = 40  # as :data:`.taylor.MAX_ORDER`


# (-1)^j / k! for k = 2j and 2j + 1: the cosine's and sine's coefficients in powers of theta^2
SIGNED_INV_FACT = np.array(
    [(-1.0) ** (k // 2) / math.factorial(k) for k in range(MAX_ORDER + 3)], dtype=np.float64
)


@njit(cache=True)
def _series(theta, order):
    """``(C, S, C1, S1)`` at ``theta``: Horner's rule in ``theta^2`` on three sums
    (``S = theta C1``: the same terms)."""
    u = theta * theta
    f = SIGNED_INV_FACT
    c = 0.0
    for k in range(order - order % 2, -1, -2):  # even k <= p: 1/k!
        c = c * u + f[k]
    s = 0.0
    top = order if order % 2 == 1 else order - 1
    for k in range(top, 0, -2):  # odd k <= p: 1/k!
        s = s * u + f[k]
    s1 = 0.0
    for k in range(order - order % 2, 1, -2):  # even 2 <= k <= p: theta^(k-1)/k!, sign of k - 2
        s1 = s1 * u - f[k]
    return c, theta * s, s, theta * s1


@njit(cache=True)
def series_at(theta, order):
    """``(C, S, C1, S1)`` of a step of phase ``theta`` (module docstring). A phase beyond 1 is
    taken as ``2^n`` equal substeps of the series, composed (``R = C + S J``, ``P = C1 + S1 J``:
    two substeps give ``R'^2`` and ``P' (1 + R') / 2``): the alternating sums then never cancel
    more than a few units of round-off, where at a phase of 5 their terms reach 10^2 and the
    error repeated over every step of a long run stops the error from falling below 1e-12."""
    n = 0
    t = theta
    while abs(t) > 1.0:
        t *= 0.5
        n += 1
    c, s, c1, s1 = _series(t, order)
    for _ in range(n):
        # (c1 + s1 J)(1 + c + s J) / 2, then (c + s J)^2, with J^2 = -1
        c1, s1 = 0.5 * (c1 * (1.0 + c) - s1 * s), 0.5 * (c1 * s + s1 * (1.0 + c))
        c, s = c * c - s * s, 2.0 * c * s
    return c, s, c1, s1


@njit(cache=True)
def two_sum(a, b):
    """Knuth's two-sum: ``a + b = s + e`` exactly, ``s`` the rounded sum."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


@njit(cache=True)
def _flow(K, h, C, S, C1, S1, y):
    """``y`` = the step that starts at ``K[:, 0]`` (positions' compensations in ``K[0:3, 1]``)
    after ``h``; returns the positions' new compensations. The positions are summed with
    Knuth's two-sum: over hundreds of steps of a large position (the drift along the field) the
    rounding of each sum would otherwise add up to more than the tightest tolerance."""
    vx, vy, vz = K[3, 0], K[4, 0], K[5, 0]
    y[0], e0 = two_sum(K[0, 0], h * (C1 * vx + S1 * vy) + K[0, 1])
    y[1], e1 = two_sum(K[1, 0], h * (C1 * vy - S1 * vx) + K[1, 1])
    y[2], e2 = two_sum(K[2, 0], h * vz + K[2, 1])
    y[3] = C * vx + S * vy
    y[4] = C * vy - S * vx
    y[5] = vz
    return e0, e1, e2


@njit(cache=True)
def charge_eval(K, w, order, h, y):
    """``y`` = the step kept in ``K`` evaluated at ``h``; returns the positions' compensations."""
    C, S, C1, S1 = series_at(w * h, order)
    return _flow(K, h, C, S, C1, S1, y)


@njit(cache=True)
def charge_steps(y, w, t, c, t1, order, ctl, K, e0, e1, e2):
    """Steps from ``y`` (its positions' compensations ``e0, e1, e2``) at ``t + c`` (time and its
    compensation) until the step that passes ``t1``; that step is kept (its start in
    ``K[:, 0]``, the compensations in ``K[0:3, 1]``) and ``y`` is left at ``t1``. Returns
    ``(steps, base, comp, span)``, the kept step's start and length; ``span`` is ``-1`` for a
    step that is not finite or lost in round-off (``y`` then holds the last state reached).
    ``ctl``: the step rule's constants (:func:`mechviz.dynamics.integrators.taylor.controls`)."""
    aw = abs(w)
    # The logarithms of the last two orders' coefficients over |v_perp| (module docstring):
    # |v^[k]| = |w|^k / k! |v_perp|, |r^[k]| = |w|^(k-1) / k! |v_perp|.
    big = math.log(max(aw, 1.0))
    la = (order - 2) * math.log(aw) - math.lgamma(order) + big
    lb = (order - 1) * math.log(aw) - math.lgamma(order + 1.0) + big
    vx, vy = y[3], y[4]
    vv = vx * vx + vy * vy
    lv = 0.5 * math.log(vv) if vv > 0.0 else -math.inf
    steps = 0
    ls_last = math.nan
    h = 0.0
    C = S = C1 = S1 = 0.0
    while True:
        for j in range(6):
            K[j, 0] = y[j]
        K[0, 1], K[1, 1], K[2, 1] = e0, e1, e2
        m = 0.0
        for j in range(6):
            m = max(m, abs(y[j]))
        ls = math.log(max(ctl[1], ctl[0] * m))
        if ls != ls_last:
            e = math.inf
            if lv > -math.inf:
                e = min((ls - lv - la) * ctl[2], (ls - lv - lb) * ctl[3])
            h = math.exp(e) * ctl[4]
            ls_last = ls
            if math.isfinite(h):
                C, S, C1, S1 = series_at(w * h, order)
        steps += 1
        if not (h > 0.0 and t + h > t):  # nan, or a step lost in round-off
            return steps, t, c, -1.0
        rest = (t1 - t) - c
        if h >= rest:
            charge_eval(K, w, order, rest, y)
            return steps, t, c, h
        e0, e1, e2 = _flow(K, h, C, S, C1, S1, y)
        t, et = two_sum(t, h)
        c += et
