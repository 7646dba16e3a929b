"""Today's hand-specialised DOP853 loop, kept as the baseline the generic Runge-Kutta runner
(:mod:`mechviz.dynamics.integrators.rk`) is measured against (:mod:`.tableau_cost`).

This is the compiled DOP853 as it was before every pair ran through one runner: scipy's tableau
read from its file, the stage sums, the blended error estimate and Hairer's dense output written
for DOP853 alone. Nothing in the product uses it; the benchmark times it side by side with the
generic runner on each system, and a test checks that both give the same states.
"""

from __future__ import annotations

import functools
import importlib.util
import math
from pathlib import Path

import numpy as np
import scipy

from mechviz.dynamics._jit import njit
from mechviz.dynamics.integrators.kernels import (
    CYCLOTRON,
    FREE_BODY,
    HOOP,
    NONFINITE,
    OK,
    RHS,
    TOO_SMALL_STEP,
    report,
)


def _scipy_tableau():
    """scipy's ``dop853_coefficients`` module, loaded from its file: importing it the usual way
    imports all of ``scipy.integrate`` first (about 0.1 s before a first answer)."""
    path = Path(scipy.__file__).parent / "integrate" / "_ivp" / "dop853_coefficients.py"
    spec = importlib.util.spec_from_file_location("_mechviz_dop853_coefficients_before", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_coef = _scipy_tableau()

N_STAGES = 12
N_STAGES_EXTENDED = 16  # the 12 stages, the derivative at the step's end, the dense output's 3
INTERPOLATOR_POWER = 7  # rows of interpolation coefficients (a polynomial of degree 7)
_SHAPE = (N_STAGES, N_STAGES_EXTENDED, INTERPOLATOR_POWER)
if (_coef.N_STAGES, _coef.N_STAGES_EXTENDED, _coef.INTERPOLATOR_POWER) != _SHAPE:
    raise ImportError(f"scipy's DOP853 tableau changed shape; this port expects {_SHAPE}")
_A = np.ascontiguousarray(_coef.A[:N_STAGES, :N_STAGES])
_B = np.ascontiguousarray(_coef.B)
_C = np.ascontiguousarray(_coef.C[:N_STAGES])
_E3 = np.ascontiguousarray(_coef.E3)
_E5 = np.ascontiguousarray(_coef.E5)
_A_DENSE = np.ascontiguousarray(_coef.A[:N_STAGES_EXTENDED, :N_STAGES_EXTENDED])
_D = np.ascontiguousarray(_coef.D)  # (INTERPOLATOR_POWER - 3, N_STAGES_EXTENDED)
# The tableau reaches the compiled loop as an argument: numba bakes a global array into the
# machine code only below about 1 kB, and a function holding a larger one is not disk-cached.
TABLEAU = (_A, _B, _E3, _E5, _A_DENSE, _D)

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
ERROR_EXPONENT = -1.0 / 8.0  # error estimator of order 7


@njit()  # not cached: the benchmark keeps no kernel in the cache
def _rms(x):
    return math.sqrt(np.sum(x * x) / x.size)


@njit()  # not cached: the benchmark keeps no kernel in the cache
def _interpolate(Q, y0, x, out):
    """The continuous extension at the fraction ``x`` of the step (0: its start, 1: its end),
    into ``out`` (scipy's ``Dop853DenseOutput``: nested in ``x`` and ``1 - x``, alternately)."""
    d = y0.size
    for j in range(d):
        v = 0.0
        for k in range(INTERPOLATOR_POWER - 1, -1, -1):
            v += Q[k, j]
            if (INTERPOLATOR_POWER - 1 - k) % 2 == 0:
                v *= x
            else:
                v *= 1.0 - x
        out[j] = v + y0[j]


# the product's right-hand sides (the generic runner's), so that only the loops differ
_CHARGE_RHS, _HOOP_RHS, _FREE_BODY_RHS = (RHS[i] for i in (CYCLOTRON, HOOP, FREE_BODY))


@njit()  # not cached: the benchmark keeps no kernel in the cache
def _rhs(sys_id, y, p, out):
    """The right-hand side of system ``sys_id`` (:mod:`.kernels`' ids). Called with a constant
    ``sys_id``, the compiled loop keeps only its branch."""
    if sys_id == CYCLOTRON:
        _CHARGE_RHS(y, p, out)
    elif sys_id == HOOP:
        _HOOP_RHS(y, p, out)
    else:
        _FREE_BODY_RHS(y, p, out)


@njit()  # not cached: the benchmark keeps no kernel in the cache
def _initial_step(sys_id, y0, f0, p, interval, rtol, atol, tmp, f1):
    """scipy's ``select_initial_step`` (one extra evaluation)."""
    d = y0.size
    scale = atol + np.abs(y0) * rtol
    d0 = _rms(y0 / scale)
    d1 = _rms(f0 / scale)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, interval)
    for j in range(d):
        tmp[j] = y0[j] + h0 * f0[j]
    _rhs(sys_id, tmp, p, f1)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval)


@njit()  # not cached: the benchmark keeps no kernel in the cache
def _dense_coefficients(sys_id, p, y0, y1, K, h, Q, tmp, kout, A_DENSE, D):
    """The continuous extension of the step ``y0 -> y1`` of length ``h`` whose stages are
    ``K[0 ... N_STAGES]`` (scipy's ``DOP853._dense_output_impl``): the three extra stages into
    ``K[N_STAGES + 1:]``, the coefficients into ``Q`` (INTERPOLATOR_POWER, d)."""
    d = y0.size
    for s in range(N_STAGES + 1, N_STAGES_EXTENDED):
        for j in range(d):
            tmp[j] = 0.0
        for r in range(s):
            a = A_DENSE[s, r]
            for j in range(d):
                tmp[j] += a * K[r, j]
        for j in range(d):
            tmp[j] = y0[j] + h * tmp[j]
        _rhs(sys_id, tmp, p, kout)
        for j in range(d):
            K[s, j] = kout[j]
    for j in range(d):
        dy = y1[j] - y0[j]
        Q[0, j] = dy
        Q[1, j] = h * K[0, j] - dy
        Q[2, j] = 2.0 * dy - h * (K[N_STAGES, j] + K[0, j])
    for k in range(INTERPOLATOR_POWER - 3):
        for j in range(d):
            tmp[j] = 0.0
        for s in range(N_STAGES_EXTENDED):
            c = D[k, s]
            for j in range(d):
                tmp[j] += c * K[s, j]
        for j in range(d):
            Q[3 + k, j] = h * tmp[j]


@functools.cache
def _runner(sys_id: int, d: int):
    """The loop compiled for system ``sys_id`` and states of ``d`` components (see
    :func:`run_dop853`). Both are integers the closure holds, constants of its machine code, and
    numba keys its disk cache on them."""

    @njit()  # not cached: the benchmark keeps no kernel in the cache
    def run(
        Y,
        p,
        t0,
        t1,
        rtol,
        atol,
        H,
        F,
        stats,
        status,
        base,
        span,
        Y0,
        Y1,
        Q,
        dense,
        last,
        tableau,
        land,
    ):
        """Advance every row of ``Y`` (N, d) from ``t0`` to ``t1`` in place; ``_rhs(sys_id, y, p, out)``.

        ``H`` (N,) carries each member's next step size between calls (0: choose one, as scipy does
        at start-up) and ``F`` (N, d) the derivative at the end of its last step (first-same-as-
        last). ``stats`` (N, 3) accumulates evaluations, accepted and rejected steps. ``status``
        as in ``run_fixed``, with code ``TOO_SMALL_STEP`` when the controller needs a step below
        10 ulp of ``t``. ``base``, ``span``, ``Y0``, ``Y1``, ``Q``, ``dense`` and ``last`` are a
        :class:`Dop853Carry`'s arrays: the last step of each member, carried to the next call.
        ``tableau`` is :data:`TABLEAU`. ``land``: cut the step that would pass ``t1`` to end there.
        """
        A, B, E3, E5, A_DENSE, D = tableau
        n = Y.shape[0]
        K = np.empty((N_STAGES_EXTENDED, d))
        tmp = np.empty(d)
        y_new = np.empty(d)
        err3 = np.empty(d)
        # Each stage is evaluated into kout and copied into its row of K: passing the row view
        # K[s] to rhs instead would create (and reference count) a new array object per stage,
        # which cost more than the hoop's whole right-hand side.
        kout = np.empty(d)
        status[0] = OK
        for i in range(n):
            y = Y[i]
            end = base[i] + span[i]
            # Q exists whenever a call stopped inside the kept step (t0 < end)
            same = span[i] > 0.0 and base[i] <= t0 <= end and (t0 == end or dense[i])
            if same:
                for j in range(d):
                    if y[j] != last[i, j]:
                        same = False
            if same and t1 <= end:  # the kept step covers t1: no step at all
                if t1 == end:
                    for j in range(d):
                        y[j] = Y1[i, j]
                else:  # t0 < t1 < end: the previous call stopped inside, so Q is there
                    _interpolate(Q[i], Y0[i], (t1 - base[i]) / span[i], y)
            else:
                if same:  # go on from the kept step's end; F[i] is its derivative
                    t = end
                    for j in range(d):
                        y[j] = Y1[i, j]
                else:  # a fresh start, or a state changed since the last call
                    t = t0
                    _rhs(sys_id, y, p, F[i])
                    stats[i, 0] += 1
                    if H[i] <= 0.0:
                        H[i] = _initial_step(
                            sys_id, y, F[i], p, abs(t1 - t0), rtol, atol, tmp, K[1]
                        )
                        stats[i, 0] += 1
                h_abs = H[i]
                while True:
                    min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
                    if h_abs < min_step:
                        h_abs = min_step
                    rejected = False
                    while True:
                        if h_abs < min_step:
                            report(status, TOO_SMALL_STEP, stats[i, 1], i)
                            return
                        # No clipping at t1 unless landing: the step the controller chose,
                        # interpolated at t1.
                        t_new = t + h_abs
                        if land and t_new > t1:
                            t_new = t1
                        h = t_new - t
                        h_abs = abs(h)
                        # Stages (scipy's rk_step). Sums run stage-outer, component-inner: with d
                        # a constant the inner loop is one vector operation, and each component's
                        # sum still adds its terms in scipy's order (same rounding as a loop
                        # over r).
                        for j in range(d):
                            K[0, j] = F[i, j]
                        for s in range(1, N_STAGES + 1):
                            for j in range(d):
                                tmp[j] = 0.0
                            if s < N_STAGES:
                                for r in range(s):
                                    a = A[s, r]
                                    for j in range(d):
                                        tmp[j] += a * K[r, j]
                            else:  # the 8th-order solution; its derivative is the FSAL stage
                                for r in range(N_STAGES):
                                    b = B[r]
                                    for j in range(d):
                                        tmp[j] += b * K[r, j]
                            for j in range(d):
                                tmp[j] = y[j] + h * tmp[j]
                            _rhs(sys_id, tmp, p, kout)
                            for j in range(d):
                                K[s, j] = kout[j]
                        for j in range(d):
                            y_new[j] = tmp[j]
                        stats[i, 0] += N_STAGES
                        # Error estimate (scipy's DOP853._estimate_error_norm).
                        for j in range(d):
                            tmp[j] = 0.0
                            err3[j] = 0.0
                        for r in range(N_STAGES + 1):
                            c5 = E5[r]
                            c3 = E3[r]
                            for j in range(d):
                                tmp[j] += c5 * K[r, j]
                                err3[j] += c3 * K[r, j]
                        e5 = 0.0
                        e3 = 0.0
                        finite = True
                        for j in range(d):
                            sc = atol + max(abs(y[j]), abs(y_new[j])) * rtol
                            e5 += (tmp[j] / sc) ** 2
                            e3 += (err3[j] / sc) ** 2
                            if not math.isfinite(y_new[j]):
                                finite = False
                        if not finite:
                            report(status, NONFINITE, stats[i, 1], i)
                            return
                        if e5 == 0.0 and e3 == 0.0:
                            err = 0.0
                        else:
                            err = h_abs * e5 / math.sqrt((e5 + 0.01 * e3) * d)
                        if err < 1.0:
                            if err == 0.0:
                                factor = MAX_FACTOR
                            else:
                                factor = min(MAX_FACTOR, SAFETY * err**ERROR_EXPONENT)
                            if rejected:
                                factor = min(1.0, factor)
                            h_abs *= factor
                            break
                        h_abs *= max(MIN_FACTOR, SAFETY * err**ERROR_EXPONENT)
                        rejected = True
                        stats[i, 2] += 1
                    stats[i, 1] += 1
                    for j in range(d):
                        F[i, j] = K[N_STAGES, j]
                    if t_new < t1:
                        for j in range(d):
                            y[j] = y_new[j]
                        t = t_new
                        continue
                    # The step that reaches t1: keep it, and hand back its value at t1.
                    base[i] = t
                    span[i] = h
                    for j in range(d):
                        Y0[i, j] = y[j]
                        Y1[i, j] = y_new[j]
                    if t_new == t1:
                        dense[i] = False
                        for j in range(d):
                            y[j] = y_new[j]
                    else:
                        _dense_coefficients(
                            sys_id, p, Y0[i], y_new, K, h, Q[i], tmp, kout, A_DENSE, D
                        )
                        stats[i, 0] += N_STAGES_EXTENDED - N_STAGES - 1
                        dense[i] = True
                        _interpolate(Q[i], Y0[i], (t1 - t) / h, y)
                    break
                H[i] = h_abs
            finite = True
            for j in range(d):
                last[i, j] = y[j]
                if not math.isfinite(y[j]):
                    finite = False
            if not finite:
                report(status, NONFINITE, stats[i, 1], i)
                return

    return run


class Dop853Carry:
    """What one run keeps between calls: each member's last step (module docstring).

    ``base`` [s] and ``span`` [s] (N,) its start and length (``span <= 0``: none kept), ``Y0`` and
    ``Y1`` (N, d) the states at its start and end, ``Q`` (N, INTERPOLATOR_POWER, d) its
    interpolation coefficients (valid where ``dense``), ``last`` (N, d) the state handed back.
    """

    def __init__(self, n: int, d: int) -> None:
        self.base = np.zeros(n)
        self.span = np.zeros(n)
        self.Y0 = np.zeros((n, d))
        self.Y1 = np.zeros((n, d))
        self.Q = np.zeros((n, INTERPOLATOR_POWER, d))
        self.dense = np.zeros(n, dtype=np.bool_)
        self.last = np.zeros((n, d))

    def forget(self) -> None:
        """Keep no step: the next call starts afresh from the state it is given."""
        self.span.fill(0.0)


def run_dop853(
    sys_id: int,
    Y,
    p,
    t0,
    t1,
    rtol,
    atol,
    H,
    F,
    stats,
    status,
    carry: Dop853Carry,
    land: bool = False,
) -> None:
    """Advance every row of ``Y`` (N, d) of system ``sys_id`` from ``t0`` to ``t1`` [s], going on
    from ``carry``'s kept steps and keeping the last ones there. ``land``: ``t1`` is a final time;
    the step that would pass it is cut to end there (module docstring).

    The loop is compiled for the system and for ``d`` as constants, and cached on disk: with the
    right-hand side an argument (a first-class function), or any compiled function held by the
    closure, numba would compile it afresh in every process (1.5-3 s), and with ``d`` read from
    the array every per-component loop would have an
    unknown length. Measured with ``time.thread_time`` over 500 members
    (``rtol = atol = 1e-10``), the known ``d`` took DOP853 from 63 to 44 ns per evaluation on the
    hoop, 48 to 35 on the disk and 38 to 27 on the charge.
    """
    _runner(int(sys_id), int(Y.shape[1]))(
        Y,
        p,
        t0,
        t1,
        rtol,
        atol,
        H,
        F,
        stats,
        status,
        carry.base,
        carry.span,
        carry.Y0,
        carry.Y1,
        carry.Q,
        carry.dense,
        carry.last,
        TABLEAU,
        bool(land),
    )
