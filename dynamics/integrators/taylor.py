"""Taylor's method: the solution's Taylor series to order ``p`` at every step, from the equations.

Adaptive, explicit, of any order. At each step the coefficients ``y^[k] = y^(k)(t) / k!`` of every
component are generated from ``y^[0] = y(t)`` by the recurrences of automatic differentiation
(Moore; Jorba & Zou, *Exp. Math.* 14 (2005) 99-117): with ``y' = f(y)``,
``y^[k+1] = f(y)^[k] / (k + 1)``, and ``f(y)^[k]`` is built from sums, Cauchy products
``(uv)^[k] = sum_j u^[j] v^[k-j]``, linear solves and the coupled sine/cosine recurrence
``S^[k] = (1/k) sum_j j u^[j] C^[k-j]``, ``C^[k] = -(1/k) sum_j j u^[j] S^[k-j]``. Each system
has its own expansion: the charge's is linear (written here), the free body's quadratic, the
hoop's has three sine/cosine pairs and a 2x2 solve per order. The free body's and the hoop's in
use are generated from their equations (:mod:`mechviz.dynamics.codegen.series`, as fast as
written by hand); the free body's written here is its check. A system known only by its
equations runs with its generated expansion through :func:`run_taylor_with`.

Step size as Jorba and Zou's (and heyoka's): ``h = rho e^-a exp(-0.7 / (p - 1))`` with ``rho``
the smaller of ``(s / |y^[k]|_inf)^(1/k)`` for ``k = p - 1, p`` and
``s = max(atol, rtol |y^[0]|_inf) / tol``, ``tol = min(rtol, atol)``. They take ``a = 2`` and
``p = ln(1/tol)/2 + 1``, the best choice when a step costs ``p^2``; here the order and ``a`` minimise
the work with each system's measured cost per step, and the tolerance is rounded down to a level
(every tolerance of a level takes the same steps; a tighter level never a worse step rule:
:func:`order_for`).
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

import numba
import numpy as np
from numba import prange

from .._jit import njit
from ..codegen.product import product_module
from ..forms import SystemForms, forms_needed
from ..taylor_order import (  # noqa: F401  (the rule's names, re-exported)
    ENTIRE,
    MAX_ORDER,
    STEP_COST,
    TIGHT_A_MIN,
    TIGHT_TOL,
    forget,
    order_for,
)
from .kernels import CYCLOTRON, FREE_BODY, HOOP, NONFINITE, OK, RHS, report
from .taylor_carry import PARALLEL_MIN, TaylorCarry  # (also re-exported)
from .taylor_linear import charge_eval, charge_steps, two_sum

# The series' sums may be contracted to fused multiply-adds (FUSED) and, for the hoop, also
# reassociated (SUMS; the order of the terms of a Cauchy product is arbitrary). No other
# fast-math licence: inf and nan still propagate, so a blow-up is still reported.
FUSED = {"contract"}
SUMS = {"reassoc", "contract"}
N_ROWS = 15  # series per member: the state and the hoop's 11 auxiliary functions
# Ensembles of at least PARALLEL_MIN members run on numba's threads (:mod:`.taylor_carry`).
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


# The free body's and the hoop's expansions in use are generated from their equations
# (:mod:`..codegen.series`; the hoop's solves its mass matrix's system per order): per step
# each costs what the hand-written one did (``mechviz bench --generated-cost``). The free body's
# hand-written one stays here as a check (the tests compare the two to round-off), the hoop's is
# the benchmark's baseline (:mod:`mechviz.bench.handwritten`). The charge's stays hand-written:
# its steps are taken in closed form (:mod:`.taylor_linear`).
def _generated(sys_id: int):
    module = product_module(sys_id, "series")
    if module.ROWS > N_ROWS:
        raise ImportError(f"the generated expansion needs {module.ROWS} rows, N_ROWS is {N_ROWS}")
    return module.expand


free_body_generated = _generated(FREE_BODY)
hoop_generated = _generated(HOOP)


@njit(cache=True)
def _expand(sys_id, A, p, order):
    if sys_id == CYCLOTRON:
        charge_expand(A, p, order)
    elif sys_id == HOOP:
        hoop_generated(A, p, order)
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


@njit  # takes a compiled function: never disk-cached (see mechviz.dynamics.integrators.kernels)
def _advance_given(expand, rows, i, Y, p, t0, t1, order, ctl, stats, carry):
    """:func:`_advance_member` with a given ``expand(A, p, order)`` filling ``rows`` rows (a
    registered system's, :class:`~mechviz.dynamics.forms.SystemForms`): the same step rule,
    time sums and kept step, so the same steps and bits as the shipped loop given the same
    coefficients."""
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
        _horner(K, d, order, (t1 - base[i]) - comp[i], y)
    else:
        if same:  # finish the kept step, then go on from its end
            t, c = two_sum(base[i], span[i])
            c += comp[i]
            _horner(K, d, order, span[i], y)
        else:
            t = t0
            c = 0.0
        A = np.empty((rows, order + 1))
        while True:
            for j in range(d):
                A[j, 0] = y[j]
            expand(A, p, order)
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


@njit  # takes a compiled function: never disk-cached (see mechviz.dynamics.integrators.kernels)
def run_taylor_given(expand, rows, Y, p, t0, t1, rtol, atol, order, a, stats, status, carry):
    """:func:`run_taylor_compiled` with a given expansion (:func:`_advance_given`), members one
    after another: what :func:`run_taylor` runs for a registered system."""
    ctl = controls(rtol, atol, order, a)
    status[0] = OK
    total = 0
    for i in range(Y.shape[0]):
        before = stats[i, 1]
        code = _advance_given(expand, rows, i, Y, p, t0, t1, order, ctl, stats, carry)
        total += stats[i, 1] - before
        if code != OK:
            report(status, code, stats[i, 1], i)
            break
    return total


# the hand-written expansions here and the product's right-hand sides (generated from the same
# equations) they are written for: the tests compare the two, and the generated expansions with
# the hand-written ones (the hoop's: :data:`mechviz.bench.handwritten.EXPANDS`)
EXPANDS = {
    CYCLOTRON: (charge_expand, RHS[CYCLOTRON]),
    FREE_BODY: (free_body_expand, RHS[FREE_BODY]),
}


def run_taylor(sys_id, Y, p, t0, t1, rtol, atol, stats, status, carry: TaylorCarry) -> int:
    """Advance every row of ``Y`` from ``t0`` to ``t1`` with the system's expansion; returns the
    steps taken (summed over the members). An ensemble of at least :data:`PARALLEL_MIN` members
    (``MECHVIZ_PARALLEL_MIN``) runs on numba's threads (``NUMBA_NUM_THREADS``). ``sys_id``: a
    compiled id, or a registered system's forms (:class:`~mechviz.dynamics.forms.SystemForms`),
    whose expansion runs serially (:func:`run_taylor_given`)."""
    order, a = order_for(rtol, atol, sys_id)
    if type(sys_id) is SystemForms:
        expand = forms_needed(sys_id, "Taylor expansion", sys_id.expand)
        args = (Y, p, t0, t1, rtol, atol, order, a, stats, status, carry.arrays)
        return run_taylor_given(expand, sys_id.rows, *args)
    run = run_taylor_parallel if len(Y) >= PARALLEL_MIN and _THREADS > 1 else run_taylor_compiled
    return run(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, carry.arrays)
