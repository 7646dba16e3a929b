"""Taylor's method: the solution's Taylor series to order ``p`` at every step, from the equations.

Adaptive, explicit, of any order. At each step the coefficients ``y^[k] = y^(k)(t) / k!`` of every
component are generated from ``y^[0] = y(t)`` by the recurrences of automatic differentiation
(Moore; Jorba & Zou, *Exp. Math.* 14 (2005) 99-117): with ``y' = f(y)``,
``y^[k+1] = f(y)^[k] / (k + 1)``, and ``f(y)^[k]`` is built from sums, Cauchy products
``(uv)^[k] = sum_j u^[j] v^[k-j]``, linear solves and the coupled sine/cosine recurrence
``S^[k] = (1/k) sum_j j u^[j] C^[k-j]``, ``C^[k] = -(1/k) sum_j j u^[j] S^[k-j]``. Each system
has its own expansion (``*_expand``), written for its right-hand side: the charge's is linear,
the free body's quadratic, the hoop's has three sine/cosine pairs and a 2x2 solve per order.
The free body's in use is generated from its equations (:mod:`mechviz.dynamics.codegen.series`,
as fast); the one written here is its check. A system known only by its equations runs with
its generated expansion through :func:`run_taylor_with`.

Step size as Jorba and Zou's (and heyoka's): ``h = rho e^-a exp(-0.7 / (p - 1))`` with ``rho``
the smaller of ``(s / |y^[k]|_inf)^(1/k)`` for ``k = p - 1, p`` and
``s = max(atol, rtol |y^[0]|_inf) / tol``, ``tol = min(rtol, atol)``. They take ``a = 2`` and
``p = ln(1/tol)/2 + 1``, the best choice when a step costs ``p^2``; here the order and ``a`` minimise
the work with each system's measured cost per step (:func:`order_for`).
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
import os

import numba
import numpy as np
from numba import prange

from .._jit import njit
from ..codegen.product import product_module
from ..taylor_order import (  # noqa: F401  (the rule's names, re-exported)
    ENTIRE,
    MAX_ORDER,
    STEP_COST,
    TIGHT_A_MIN,
    TIGHT_TOL,
    order_for,
)
from .kernels import CYCLOTRON, FREE_BODY, HOOP, NONFINITE, OK, RHS, report
from .taylor_linear import charge_eval, charge_steps, two_sum

# The series' sums may be contracted to fused multiply-adds (FUSED) and, for the hoop, also
# reassociated (SUMS; the order of the terms of a Cauchy product is arbitrary). No other
# fast-math licence: inf and nan still propagate, so a blow-up is still reported.
FUSED = {"contract"}
SUMS = {"reassoc", "contract"}
N_ROWS = 14  # series per member: the state and the hoop's 10 auxiliary functions
# Ensembles of at least PARALLEL_MIN members run their members on numba's threads
# (:func:`run_taylor_parallel`, bitwise the serial result). On idle cores that pays from small
# ensembles on, but on cores busy with other jobs a thread that loses its core holds the whole
# loop up, and in short calls the threads wait on each other (``mechviz bench``, "Ensembles",
# has the figures). Hence a threshold at calls long enough for the waiting not to matter;
# ``MECHVIZ_PARALLEL_MIN`` sets it, 0 turns it off.
PARALLEL_MIN = int(os.environ.get("MECHVIZ_PARALLEL_MIN") or 1000) or 1 << 62
_THREADS = numba.config.NUMBA_NUM_THREADS


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


@njit(cache=True, fastmath=FUSED)
def free_body_expand(A, p, order):
    """Euler's equations and ``q' = q (0, w) / 2``
    (:func:`mechviz.dynamics.codegen.equations.free_body`).

    Each of the seven sums adds one term per index: the three products of a quaternion
    component are formed first, off the chain of dependent additions (1.7x faster at order 5).
    """
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
            b0 -= q1 * w1 + q2 * w2 + q3 * w3
            b1 += q0 * w1 + (q2 * w3 - q3 * w2)
            b2 += q0 * w2 + (q3 * w1 - q1 * w3)
            b3 += q0 * w3 + (q1 * w2 - q2 * w1)
        inv = 1.0 / (k + 1)
        A[0, k + 1] = k1 * a23 * inv
        A[1, k + 1] = k2 * a31 * inv
        A[2, k + 1] = k3 * a12 * inv
        h = 0.5 * inv
        A[3, k + 1] = b0 * h
        A[4, k + 1] = b1 * h
        A[5, k + 1] = b2 * h
        A[6, k + 1] = b3 * h


@njit(cache=True, fastmath=SUMS)
def hoop_expand(A, p, order):
    """The hoop and bead (:func:`mechviz.dynamics.codegen.equations.hoop`): with
    ``u = th1 - th2``, ``r1 = -m sin(u) w2^2 - (M + m)(g/a) sin th1``,
    ``r2 = sin(u) w1^2 - (g/a) sin th2``, the accelerations solve the mass-matrix system
    ``(2M + m) w1' + m cos(u) w2' = r1``, ``cos(u) w1' + w2' = r2``.

    The series are taken of that system rather than of its solved form (the quotients by
    ``det = 2M + m - m cos(u)^2``): order ``k`` of each line is the order-``k`` accelerations
    times the matrix at the step's start, plus the products of the higher orders of ``cos u``
    with the lower orders of the accelerations, so order ``k`` is one 2x2 solve with the matrix
    inverted once per step. That takes two Cauchy products per order (``cos(u) w2'``,
    ``cos(u) w1'``) where the quotients took four and the square ``cos(u)^2``: a fifth fewer
    multiply-adds a step.

    Per order three loops, each accumulating several independent sums (the sums are chains of
    dependent additions; interleaving them keeps the floating-point units busy): the three
    sine/cosine pairs; the squares ``w2^2``, ``w1^2`` (over half the terms, by symmetry); the
    products with ``sin u`` and ``cos u``.
    """
    M, m, ga = p[0], p[1], p[3] / p[2]
    m11 = 2.0 * M + m
    mg = (M + m) * ga
    # rows 0-3: th1, th2, w1, w2
    SU, CU, S1, C1, S2, C2, Q1, Q2, A1, A2 = range(4, 14)
    i11 = i12 = i21 = i22 = 0.0  # the inverse of the matrix at the step's start
    for k in range(order):
        if k == 0:
            s1, c1 = math.sin(A[0, 0]), math.cos(A[0, 0])
            s2, c2 = math.sin(A[1, 0]), math.cos(A[1, 0])
            A[S1, 0], A[C1, 0], A[S2, 0], A[C2, 0] = s1, c1, s2, c2
            su = s1 * c2 - c1 * s2  # sin(th1 - th2): two library calls fewer per step
            cu = c1 * c2 + s1 * s2
            A[SU, 0] = su
            A[CU, 0] = cu
            inv_det = 1.0 / (m11 - m * cu * cu)
            i11, i12, i21, i22 = inv_det, -m * cu * inv_det, -cu * inv_det, m11 * inv_det
        else:
            su = cu = s1 = c1 = s2 = c2 = 0.0
            for j in range(1, k + 1):
                t1 = A[2, j - 1]  # j th1^[j] = w1^[j-1]: th1' = w1
                t2 = A[3, j - 1]
                tu = t1 - t2
                i = k - j
                su += tu * A[CU, i]
                cu += tu * A[SU, i]
                s1 += t1 * A[C1, i]
                c1 += t1 * A[S1, i]
                s2 += t2 * A[C2, i]
                c2 += t2 * A[S2, i]
            inv = 1.0 / k
            A[SU, k] = su * inv
            A[CU, k] = -cu * inv
            A[S1, k] = s1 * inv
            A[C1, k] = -c1 * inv
            A[S2, k] = s2 * inv
            A[C2, k] = -c2 * inv
        # squares: (uu)^[k] = 2 sum_{j < k/2} u_j u_(k-j) (+ u_(k/2)^2 for even k)
        q1 = q2 = 0.0
        for j in range((k + 1) // 2):
            i = k - j
            q1 += A[3, j] * A[3, i]
            q2 += A[2, j] * A[2, i]
        q1 *= 2.0
        q2 *= 2.0
        if k % 2 == 0:
            h = k // 2
            q1 += A[3, h] * A[3, h]
            q2 += A[2, h] * A[2, h]
        A[Q1, k] = q1
        A[Q2, k] = q2
        # the terms j = 1 ... k, which use only lower orders of the squares and accelerations
        s1 = s2 = n1 = n2 = 0.0
        for j in range(1, k + 1):
            i = k - j
            su = A[SU, j]
            cu = A[CU, j]
            s1 += su * A[Q1, i]
            s2 += su * A[Q2, i]
            n1 += cu * A[A2, i]
            n2 += cu * A[A1, i]
        s1 += A[SU, 0] * q1
        s2 += A[SU, 0] * q2
        b1 = -m * s1 - mg * A[S1, k] - m * n1
        b2 = s2 - ga * A[S2, k] - n2
        a1 = i11 * b1 + i12 * b2
        a2 = i21 * b1 + i22 * b2
        A[A1, k] = a1
        A[A2, k] = a2
        inv = 1.0 / (k + 1)
        A[0, k + 1] = A[2, k] * inv
        A[1, k + 1] = A[3, k] * inv
        A[2, k + 1] = a1 * inv
        A[3, k + 1] = a2 * inv


# The free body's expansion in use is generated from its equations (:mod:`..codegen.series`):
# per step it costs what free_body_expand above does (``mechviz bench --generated-cost``), which
# stays as its check (the tests compare the two to round-off). The hoop's and the charge's stay
# hand-written: the hoop's (a 2x2 solve per order) costs less than half the generated one's
# quotients, and the charge's steps are taken in closed form (:mod:`.taylor_linear`).
_GENERATED = product_module(FREE_BODY, "series")
if _GENERATED.ROWS > N_ROWS:
    raise ImportError(f"the generated expansion needs {_GENERATED.ROWS} rows, N_ROWS is {N_ROWS}")
free_body_generated = _GENERATED.expand


@njit(cache=True)
def _expand(sys_id, A, p, order):
    if sys_id == CYCLOTRON:
        charge_expand(A, p, order)
    elif sys_id == HOOP:
        hoop_expand(A, p, order)
    else:
        free_body_generated(A, p, order)


# --------------------------------------------------------------------------- the loop
@njit(cache=True)
def _horner(A, d, order, h, y):
    for j in range(d):
        v = A[j, order]
        for k in range(order - 1, -1, -1):
            v = v * h + A[j, k]
        y[j] = v


@njit(cache=True)
def _eval_kept(sys_id, K, p, d, order, h, y):
    """The kept step at ``h`` into ``y``: the charge's in closed form (:mod:`.taylor_linear`),
    the others by Horner's rule."""
    if sys_id == CYCLOTRON:
        charge_eval(K, p[0], order, h, y)
    else:
        _horner(K, d, order, h, y)


@njit(cache=True)
def controls(rtol, atol, order, a):
    """The step rule's constants for ``rtol``, ``atol`` at ``order`` with ``a``: the scales of the
    state's norm (``rtol / tol``, ``atol / tol``), ``1/(p-1)``, ``1/p`` and the safety factor
    ``exp(-a - 0.7 / (p - 1))`` (module docstring), in one array the loops pass along."""
    tol = min(rtol, atol)
    out = np.empty(5)
    out[0], out[1] = rtol / tol, atol / tol
    out[2], out[3] = 1.0 / (order - 1), 1.0 / order
    out[4] = math.exp(-a - 0.7 / (order - 1))
    return out


@njit(cache=True)
def _step_size(A, d, order, ctl):
    """Jorba and Zou's step from the last two orders (``ctl``: :func:`controls`), as
    ``exp(min(log(s/|a|)/(p-1), log(s/|b|)/p))``: two logarithms and one exponential cost less
    than the two powers they replace."""
    y0 = 0.0
    na = 0.0
    nb = 0.0
    for j in range(d):
        y0 = max(y0, abs(A[j, 0]))
        na = max(na, abs(A[j, order - 1]))
        nb = max(nb, abs(A[j, order]))
    ls = math.log(max(ctl[1], ctl[0] * y0))
    e = math.inf
    if na > 0.0:
        e = (ls - math.log(na)) * ctl[2]
    if nb > 0.0:
        e = min(e, (ls - math.log(nb)) * ctl[3])
    return math.exp(e) * ctl[4]


@njit(cache=True)
def _advance_member(sys_id, i, Y, p, t0, t1, order, ctl, stats, carry):
    """Advance member ``i`` (row ``Y[i]``) from ``t0`` to ``t1``; returns ``OK`` or ``NONFINITE``.
    Touches only row ``i`` of every array, so that members may run on different threads.
    ``ctl``: :func:`controls`; ``carry``: :attr:`TaylorCarry.arrays`."""
    kept, base, comp, span, last = carry
    d = Y.shape[1]
    y = Y[i]
    K = kept[i]
    same = span[i] > 0.0 and base[i] <= t0 <= base[i] + span[i]
    if same:
        for j in range(d):
            if y[j] != last[i, j]:
                same = False
    if same and t1 <= base[i] + span[i]:
        _eval_kept(sys_id, K, p, d, order, (t1 - base[i]) - comp[i], y)
    else:
        # The time is t + c, summed with Kahan's compensation: a rounded t would shift the
        # solution by up to half an ulp of t per step (at t ~ 10^3-10^4 s, 1e-11 over a long run).
        # A kept step carries its start's compensation, so calls that end inside steps (samples,
        # chunks) do the arithmetic of one call.
        e0 = e1 = e2 = 0.0  # the charge's positions' compensations (:mod:`.taylor_linear`)
        if same:  # finish the kept step, then go on from its end
            t, c = two_sum(base[i], span[i])
            c += comp[i]
            if sys_id == CYCLOTRON:
                e0, e1, e2 = charge_eval(K, p[0], order, span[i], y)
            else:
                _horner(K, d, order, span[i], y)
        else:
            t = t0
            c = 0.0
        if sys_id == CYCLOTRON:  # the linear flow's series in closed form
            n, base[i], comp[i], span[i] = charge_steps(
                y, p[0], t, c, t1, order, ctl, K, e0, e1, e2
            )
            stats[i, 0] += n
            stats[i, 1] += n
            if span[i] < 0.0:
                span[i] = 0.0
                return NONFINITE
        # The series of a step, auxiliary rows included, in scratch that fits in the L1 cache;
        # only the state's rows of the last step are kept (every entry is written before read).
        A = np.empty((N_ROWS, order + 1))
        while sys_id != CYCLOTRON:
            for j in range(d):
                A[j, 0] = y[j]
            _expand(sys_id, A, p, order)
            h = _step_size(A, d, order, ctl)
            stats[i, 0] += 1
            stats[i, 1] += 1
            if not (h > 0.0 and t + h > t):  # nan, or a step lost in round-off
                return NONFINITE
            rest = (t1 - t) - c
            if h >= rest:
                base[i] = t
                comp[i] = c
                span[i] = h
                for j in range(d):
                    for k in range(order + 1):
                        K[j, k] = A[j, k]
                _horner(A, d, order, rest, y)
                break
            _horner(A, d, order, h, y)
            t, e = two_sum(t, h)
            c += e
    finite = True
    for j in range(d):
        last[i, j] = y[j]
        if not math.isfinite(y[j]):
            finite = False
    return OK if finite else NONFINITE


@njit(cache=True)
def run_taylor_compiled(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, carry):
    """Advance every row of ``Y`` (N, d) from ``t0`` to ``t1`` in place, at order ``order`` with
    steps ``rho exp(-a - 0.7 / (order - 1))`` (module docstring), one member after another; stops
    at the first member that fails (``status = (NONFINITE, its steps, its index)``).

    ``carry = (kept, base, comp, span, last)`` (:attr:`TaylorCarry.arrays`): ``kept``
    (N, d, MAX_ORDER + 1), ``base``, ``comp`` and ``span`` (N,) and ``last`` (N, d) hold
    each member's last step (the state's series, its start ``base + comp``, its length;
    ``span <= 0``: none) and the state written at ``t1``; they carry the step over to the next
    call (module docstring). Returns the steps taken, summed over the members (also added to
    ``stats``).
    """
    n = Y.shape[0]
    ctl = controls(rtol, atol, order, a)
    status[0] = OK
    total = 0
    for i in range(n):
        before = stats[i, 1]
        code = _advance_member(sys_id, i, Y, p, t0, t1, order, ctl, stats, carry)
        total += stats[i, 1] - before
        if code != OK:
            report(status, code, stats[i, 1], i)
            break
    return total


@njit(cache=True, parallel=True)
def run_taylor_parallel(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, carry):
    """:func:`run_taylor_compiled` with the members spread over numba's threads. Each member's
    arithmetic is the serial loop's (bitwise the same result); a failure does not stop the other
    members, and ``status`` names the first member that failed."""
    n = Y.shape[0]
    ctl = controls(rtol, atol, order, a)
    before = stats[:, 1].copy()
    codes = np.zeros(n, np.int64)
    for i in prange(n):
        codes[i] = _advance_member(sys_id, i, Y, p, t0, t1, order, ctl, stats, carry)
    status[0] = OK
    for i in range(n):
        if codes[i] != OK:
            report(status, codes[i], stats[i, 1], i)
            break
    return int(np.sum(stats[:, 1] - before))


@njit  # takes a compiled function: never disk-cached (see mechviz.dynamics.integrators.kernels)
def run_taylor_with(expand, rows, Y, p, t0, t1, rtol, atol, order, a, stats, status):
    """Taylor's method with a given expansion: every row of ``Y`` (N, d) from ``t0`` to ``t1``
    in place, as :func:`run_taylor_compiled` does on a fresh start (the same step rule and
    time sums, bitwise the same steps given the same coefficients) but with no step kept
    between calls. ``expand(A, p, order)`` fills an array of ``rows`` rows as the hand-written
    expansions do (a generated one: :mod:`mechviz.dynamics.codegen.series`). Returns the
    steps taken; ``stats`` and ``status`` as :func:`run_taylor_compiled`'s."""
    ctl = controls(rtol, atol, order, a)
    d = Y.shape[1]
    A = np.empty((rows, order + 1))
    status[0] = OK
    total = 0
    for i in range(Y.shape[0]):
        y = Y[i]
        t = t0
        c = 0.0
        while True:
            for j in range(d):
                A[j, 0] = y[j]
            expand(A, p, order)
            h = _step_size(A, d, order, ctl)
            stats[i, 0] += 1
            stats[i, 1] += 1
            total += 1
            if not (h > 0.0 and t + h > t):  # nan, or a step lost in round-off
                report(status, NONFINITE, stats[i, 1], i)
                return total
            rest = (t1 - t) - c
            if h >= rest:
                _horner(A, d, order, rest, y)
                break
            _horner(A, d, order, h, y)
            t, e = two_sum(t, h)
            c += e
        for j in range(d):
            if not math.isfinite(y[j]):
                report(status, NONFINITE, stats[i, 1], i)
                return total
    return total


# the hand-written expansions and the product's right-hand sides (generated from the same
# equations) they are written for: the tests compare the two, and the generated expansions with
# the hand-written ones
EXPANDS = {
    CYCLOTRON: (charge_expand, RHS[CYCLOTRON]),
    HOOP: (hoop_expand, RHS[HOOP]),
    FREE_BODY: (free_body_expand, RHS[FREE_BODY]),
}


class TaylorCarry:
    """What one run keeps between calls: each member's last step (see :func:`_run`)."""

    def __init__(self, n: int, d: int) -> None:
        self.kept = np.zeros((n, d, MAX_ORDER + 1))  # the state's series only: 1 kB a hoop
        self.base = np.zeros(n)
        self.comp = np.zeros(n)  # the base time's compensation: it is base + comp
        self.span = np.zeros(n)
        self.last = np.zeros((n, d))

    @property
    def arrays(self) -> tuple[np.ndarray, ...]:
        """``(kept, base, comp, span, last)``, as the compiled loops take them."""
        return self.kept, self.base, self.comp, self.span, self.last

    def forget(self) -> None:
        """Keep no step: the next call starts a fresh one."""
        self.span.fill(0.0)


def run_taylor(sys_id, Y, p, t0, t1, rtol, atol, stats, status, carry: TaylorCarry) -> int:
    """Advance every row of ``Y`` from ``t0`` to ``t1`` with the system's expansion; returns the
    steps taken (summed over the members). An ensemble of at least :data:`PARALLEL_MIN` members
    (``MECHVIZ_PARALLEL_MIN``) runs on numba's threads (``NUMBA_NUM_THREADS``)."""
    order, a = order_for(rtol, atol, sys_id)
    run = run_taylor_parallel if len(Y) >= PARALLEL_MIN and _THREADS > 1 else run_taylor_compiled
    return run(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, carry.arrays)
