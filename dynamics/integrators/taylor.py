"""Taylor's method: the solution's Taylor series to order ``p`` at every step, from the equations.

Adaptive, explicit, of any order. At each step the coefficients ``y^[k] = y^(k)(t) / k!`` of every
component are generated from ``y^[0] = y(t)`` by the recurrences of automatic differentiation
(Moore; Jorba & Zou, *Exp. Math.* 14 (2005) 99-117): with ``y' = f(y)``,
``y^[k+1] = f(y)^[k] / (k + 1)``, and ``f(y)^[k]`` is built from sums, Cauchy products
``(uv)^[k] = sum_j u^[j] v^[k-j]``, quotients and the coupled sine/cosine recurrence
``S^[k] = (1/k) sum_j j u^[j] C^[k-j]``, ``C^[k] = -(1/k) sum_j j u^[j] S^[k-j]``. Each system
has its own expansion (``*_expand``), written for its right-hand side: the charge's is linear,
the free body's quadratic, the hoop's has three sine/cosine pairs and a 2x2 solve.

Order and step follow Jorba and Zou, as heyoka does: ``p = ceil(-ln(tol)/2 + 1)`` for
``tol = min(rtol, atol)``, and ``h = rho / e^2 * exp(-0.7 / (p - 1))`` with ``rho`` the smaller of
``(s / |y^[k]|_inf)^(1/k)`` for ``k = p - 1, p`` and ``s = max(atol, rtol |y^[0]|_inf) / tol``.
There is no rejected step. The series is its own dense output: a state inside a step is the
polynomial evaluated there. The last step before ``t1`` is kept (base time, length and
coefficients), so a run sampled at many times takes the steps an unsampled run takes, and a
sample costs one polynomial evaluation. The kept step is used only if the state handed back is
still the one this integrator wrote there (a state changed in between starts a fresh step).

Counts: ``stats[i] = (expansions, accepted steps, 0)``; one expansion per step (there is no
right-hand-side evaluation to count).
"""

from __future__ import annotations

import math

import numpy as np

from .. import cyclotron, disk, hoop
from .._jit import njit
from .kernels import CYCLOTRON, FREE_BODY, HOOP, NONFINITE, OK

MAX_ORDER = 30
STEP_SAFETY = math.exp(-2.0)  # rho / e^2 (Jorba and Zou)
N_ROWS = 18  # series per member: the state and the hoop's 14 auxiliary functions


def order_for(rtol: float, atol: float) -> int:
    """The order Jorba and Zou choose for this tolerance: ``ceil(-ln(tol)/2 + 1)``, 2 ... 30."""
    tol = min(rtol, atol)
    return int(min(MAX_ORDER, max(2, math.ceil(-math.log(tol) / 2.0 + 1.0))))


# --------------------------------------------------------------------------- expansions
# Every series is a row of one array ``A`` (rows, MAX_ORDER + 1): ``A[j, k]`` is the order-k
# coefficient of series j. The state's components are rows 0 ... d - 1, a system's auxiliary
# functions the rows after them. A convolution then runs over contiguous memory.


@njit(cache=True)
def charge_expand(A, p, order):
    """Charge in a uniform field along z: ``r' = v``, ``v' = Omega (vy, -vx, 0)``."""
    w = p[0]
    for k in range(order):
        inv = 1.0 / (k + 1)
        A[0, k + 1] = A[3, k] * inv
        A[1, k + 1] = A[4, k] * inv
        A[2, k + 1] = A[5, k] * inv
        wi = w * inv  # one multiplication on the dependency chain from order k to k + 1
        A[3, k + 1] = wi * A[4, k]
        A[4, k + 1] = -wi * A[3, k]
        A[5, k + 1] = 0.0


@njit(cache=True)
def free_body_expand(A, p, order):
    """Euler's equations and ``q' = q (0, w) / 2`` (:func:`dynamics.disk.free_derivatives`)."""
    i1, i2, i3 = p[0], p[1], p[2]
    k1, k2, k3 = (i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3
    for k in range(order):
        a23 = a31 = a12 = 0.0
        b0 = b1 = b2 = b3 = 0.0
        for j in range(k + 1):
            m = k - j
            w1, w2, w3 = A[0, j], A[1, j], A[2, j]
            a23 += w2 * A[2, m]
            a31 += w3 * A[0, m]
            a12 += w1 * A[1, m]
            q0, q1, q2, q3 = A[3, m], A[4, m], A[5, m], A[6, m]
            b0 += -q1 * w1 - q2 * w2 - q3 * w3
            b1 += q0 * w1 + q2 * w3 - q3 * w2
            b2 += q0 * w2 + q3 * w1 - q1 * w3
            b3 += q0 * w3 + q1 * w2 - q2 * w1
        inv = 1.0 / (k + 1)
        A[0, k + 1] = k1 * a23 * inv
        A[1, k + 1] = k2 * a31 * inv
        A[2, k + 1] = k3 * a12 * inv
        h = 0.5 * inv
        A[3, k + 1] = b0 * h
        A[4, k + 1] = b1 * h
        A[5, k + 1] = b2 * h
        A[6, k + 1] = b3 * h


@njit(cache=True, inline="always")
def _sincos(A, U, S, C, k):
    """Order ``k >= 1`` of ``S = sin u``, ``C = cos u`` from the series ``u`` in row ``U``."""
    s = 0.0
    c = 0.0
    for j in range(1, k + 1):
        ju = j * A[U, j]
        s += ju * A[C, k - j]
        c += ju * A[S, k - j]
    A[S, k] = s / k
    A[C, k] = -c / k


@njit(cache=True)
def hoop_expand(A, p, order):
    """The hoop and bead (:func:`dynamics.hoop.acceleration`): with ``u = th1 - th2``,
    ``r1 = -m sin(u) w2^2 - (M + m)(g/a) sin th1``, ``r2 = sin(u) w1^2 - (g/a) sin th2``,
    ``det = 2M + m - m cos(u)^2``, ``w1' = (r1 - m cos(u) r2) / det``,
    ``w2' = ((2M + m) r2 - cos(u) r1) / det``."""
    M, m, ga = p[0], p[1], p[3] / p[2]
    m11 = 2.0 * M + m
    mg = (M + m) * ga
    # rows 0-3: th1, th2, w1, w2
    U, SU, CU, S1, C1, S2, C2, Q1, Q2, R1, R2, DET, A1, A2 = range(4, 18)
    for k in range(order):
        A[U, k] = A[0, k] - A[1, k]
        if k == 0:
            A[SU, 0] = math.sin(A[U, 0])
            A[CU, 0] = math.cos(A[U, 0])
            A[S1, 0] = math.sin(A[0, 0])
            A[C1, 0] = math.cos(A[0, 0])
            A[S2, 0] = math.sin(A[1, 0])
            A[C2, 0] = math.cos(A[1, 0])
        else:
            _sincos(A, U, SU, CU, k)
            _sincos(A, 0, S1, C1, k)
            _sincos(A, 1, S2, C2, k)
        q1 = q2 = cc = 0.0
        for j in range(k + 1):
            q1 += A[3, j] * A[3, k - j]  # w2^2
            q2 += A[2, j] * A[2, k - j]  # w1^2
            cc += A[CU, j] * A[CU, k - j]  # cos(u)^2
        A[Q1, k] = q1
        A[Q2, k] = q2
        s1 = s2 = 0.0
        for j in range(k + 1):
            s1 += A[SU, j] * A[Q1, k - j]
            s2 += A[SU, j] * A[Q2, k - j]
        r1 = -m * s1 - mg * A[S1, k]
        r2 = s2 - ga * A[S2, k]
        A[R1, k] = r1
        A[R2, k] = r2
        A[DET, k] = (m11 if k == 0 else 0.0) - m * cc
        n1 = n2 = 0.0
        for j in range(k + 1):
            n1 += A[CU, j] * A[R2, k - j]
            n2 += A[CU, j] * A[R1, k - j]
        n1 = r1 - m * n1
        n2 = m11 * r2 - n2
        for j in range(1, k + 1):
            n1 -= A[DET, j] * A[A1, k - j]
            n2 -= A[DET, j] * A[A2, k - j]
        a1 = n1 / A[DET, 0]
        a2 = n2 / A[DET, 0]
        A[A1, k] = a1
        A[A2, k] = a2
        inv = 1.0 / (k + 1)
        A[0, k + 1] = A[2, k] * inv
        A[1, k + 1] = A[3, k] * inv
        A[2, k + 1] = a1 * inv
        A[3, k + 1] = a2 * inv


@njit(cache=True)
def _expand(sys_id, A, p, order):
    if sys_id == CYCLOTRON:
        charge_expand(A, p, order)
    elif sys_id == HOOP:
        hoop_expand(A, p, order)
    else:
        free_body_expand(A, p, order)


# --------------------------------------------------------------------------- the loop
@njit(cache=True)
def _horner(A, d, order, h, y):
    for j in range(d):
        v = A[j, order]
        for k in range(order - 1, -1, -1):
            v = v * h + A[j, k]
        y[j] = v


@njit(cache=True)
def _step_size(A, d, order, scale_r, scale_a, inv_a, inv_b, factor):
    """Jorba and Zou's step from the last two orders (``inv_a = 1/(p-1)``, ``inv_b = 1/p``)."""
    y0 = 0.0
    na = 0.0
    nb = 0.0
    for j in range(d):
        y0 = max(y0, abs(A[j, 0]))
        na = max(na, abs(A[j, order - 1]))
        nb = max(nb, abs(A[j, order]))
    s = max(scale_a, scale_r * y0)
    rho = math.inf
    if na > 0.0:
        rho = (s / na) ** inv_a
    if nb > 0.0:
        rho = min(rho, (s / nb) ** inv_b)
    return rho * factor


@njit(cache=True)
def run_taylor_compiled(sys_id, Y, p, t0, t1, rtol, atol, order, stats, status, kept, base, span,
                        last):  # fmt: skip
    """Advance every row of ``Y`` (N, d) from ``t0`` to ``t1`` in place.

    ``kept`` (N, N_ROWS, MAX_ORDER + 1), ``base`` (N,), ``span`` (N,) and ``last`` (N, d) hold each
    member's last step (all series, base time, length; ``span <= 0``: none) and the state written
    at ``t1``; they carry the step over to the next call (module docstring).
    """
    n, d = Y.shape
    tol = min(rtol, atol)
    scale_r, scale_a = rtol / tol, atol / tol
    inv_a, inv_b = 1.0 / (order - 1), 1.0 / order
    factor = STEP_SAFETY * math.exp(-0.7 / (order - 1))
    status[0] = OK
    for i in range(n):
        y = Y[i]
        A = kept[i]
        same = span[i] > 0.0 and base[i] <= t0 <= base[i] + span[i]
        if same:
            for j in range(d):
                if y[j] != last[i, j]:
                    same = False
        if same and t1 <= base[i] + span[i]:
            _horner(A, d, order, t1 - base[i], y)
        else:
            if same:  # finish the kept step, then go on from its end
                t = base[i] + span[i]
                _horner(A, d, order, span[i], y)
            else:
                t = t0
            while True:
                for j in range(d):
                    A[j, 0] = y[j]
                _expand(sys_id, A, p, order)
                h = _step_size(A, d, order, scale_r, scale_a, inv_a, inv_b, factor)
                stats[i, 0] += 1
                stats[i, 1] += 1
                if not (h > 0.0 and t + h > t):  # nan, or a step lost in round-off
                    status[0] = NONFINITE
                    status[1] = stats[i, 1]
                    status[2] = i
                    return
                if t + h >= t1:
                    base[i] = t
                    span[i] = h
                    _horner(A, d, order, t1 - t, y)
                    break
                _horner(A, d, order, h, y)
                t += h
        finite = True
        for j in range(d):
            last[i, j] = y[j]
            if not math.isfinite(y[j]):
                finite = False
        if not finite:
            status[0] = NONFINITE
            status[1] = stats[i, 1]
            status[2] = i
            return


# the right-hand sides the expansions are written for (tests compare the two)
EXPANDS = {
    CYCLOTRON: (charge_expand, cyclotron.rhs),
    HOOP: (hoop_expand, hoop.rhs),
    FREE_BODY: (free_body_expand, disk.free_rhs),
}


class TaylorCarry:
    """What one run keeps between calls: each member's last step (see :func:`_run`)."""

    def __init__(self, n: int, d: int) -> None:
        self.kept = np.zeros((n, N_ROWS, MAX_ORDER + 1))
        self.base = np.zeros(n)
        self.span = np.zeros(n)
        self.last = np.zeros((n, d))


def run_taylor(sys_id, Y, p, t0, t1, rtol, atol, stats, status, carry: TaylorCarry) -> None:
    """Advance every row of ``Y`` from ``t0`` to ``t1`` with the system's expansion."""
    run_taylor_compiled(sys_id, Y, p, t0, t1, rtol, atol, order_for(rtol, atol), stats, status,
                        carry.kept, carry.base, carry.span, carry.last)  # fmt: skip
