"""One compiled runner for every embedded explicit Runge-Kutta pair, given its tableau.

A pair is data (:class:`Pair`): the stage matrix ``A`` and nodes ``c``, the weights ``b`` of the
propagated solution, the error weights ``E`` (``b - b_hat``, or DOP853's two estimators), and the
dense output (the extra stages' rows of ``A`` and the interpolant's coefficients). Each pair is a
short module beside this one (:mod:`.dop853`, :mod:`.vern6`, ...) that builds its :class:`Pair`;
:func:`run_rk` advances a batch of states with it. This is scipy's ``RungeKutta`` / ``rk_step``
split (``scipy/integrate/_ivp/rk.py``) with the whole time loop compiled.

Stage layout (scipy's): stages ``0 ... n_stages - 1`` make the step; stage ``n_stages`` is the
derivative at the step's end (its row of ``A`` is ``b``), which every pair needs as the next
step's first stage (first-same-as-last); stages after it exist only for the dense output and are
evaluated only for a step that passes a time asked for.

Steps are never cut at the requested time ``t1``: the step that reaches ``t1`` is taken at the
size the controller chose and kept (start time, length, start and end states, interpolation
coefficients), and the state handed back is the pair's interpolant at ``t1``. The next call goes
on from the kept step's end, so a run sampled at many times takes the steps an unsampled run
takes, and a sample inside a kept step costs one polynomial evaluation. The kept step is used
only if the state handed back is still the one written there: a state changed in between (a
kick) starts afresh from it, with one evaluation of its derivative.

A run that ends at a time (``land``: a final time, not a frame) cuts the step that would pass it
so that it ends there, as scipy's ``solve_ivp`` does, and hands back that step's own end point:
the interpolant errs by ``O(h^(q+1))`` inside a step (``q`` its order), a larger multiple of the
tolerance than the stepped solution's local error.

Step control is scipy's for every pair: initial step from ``select_initial_step``, controller
with safety 0.9, factors 0.2 ... 10 and exponent ``-1 / (error_order + 1)``; the error is the RMS
norm of the estimate scaled by ``atol + max(|y|, |y_new|) rtol``. With two rows of error weights
(DOP853) the estimate is Hairer's blend of the 5th- and 3rd-order ones, as in scipy.

Counts: ``stats[i] = (evaluations, accepted steps, rejected steps)``; evaluations include the
dense output's stages and the derivative of a fresh start.
"""

from __future__ import annotations

import functools
import importlib
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numba import types
from numba.extending import overload, register_jitable

from .._jit import njit
from ..forms import SystemForms
from .kernels import CYCLOTRON, FREE_BODY, HOOP, NONFINITE, OK, RHS, TOO_SMALL_STEP, report

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0

#: The pairs, each a module of this package defining ``PAIR``; a :class:`~.base.Method` names
#: its pair by one of these.
PAIRS = ("dop853", "vern6", "vern7", "vern8", "vern9")


@dataclass(frozen=True, eq=False)
class Pair:
    """An embedded explicit Runge-Kutta pair with its dense output, as float64 arrays.

    ``A`` (n_all, n_all) and ``c`` (n_all,) hold every stage: the ``n_stages`` of a step, the
    derivative at its end (row ``b``), then the interpolant's extra stages. ``E`` (1 or 2,
    n_stages + 1) are the error weights: one row ``b - b_hat`` (the estimate is ``h E . K``), or
    DOP853's two (``E5``, ``E3``: Hairer's blended estimate). The interpolant:

    - ``"power"``: ``y(t + x h) = y + h sum_k x^(k+1) sum_s P[k, s] K[s]`` (Verner's form);
    - ``"hairer"``: DOP853's nested form in ``x`` and ``1 - x`` (scipy's ``Dop853DenseOutput``),
      whose first three rows come from the step's ends and ``P`` holds the rest (scipy's ``D``).
    """

    name: str
    order: int
    error_order: int
    dense_order: int
    n_stages: int
    A: np.ndarray
    b: np.ndarray
    c: np.ndarray
    E: np.ndarray
    P: np.ndarray
    interpolant: Literal["power", "hairer"] = "power"
    source: str = ""

    def __post_init__(self) -> None:
        n_all = self.A.shape[0]
        if self.A.shape != (n_all, n_all) or self.c.shape != (n_all,):
            raise ValueError(f"{self.name}: A must be square and c match it")
        if n_all < self.n_stages + 1 or self.b.shape != (self.n_stages,):
            raise ValueError(f"{self.name}: b must have n_stages entries, A one row more")
        if not np.array_equal(self.A[self.n_stages, : self.n_stages], self.b):
            raise ValueError(f"{self.name}: stage n_stages must be the step's end (row b)")
        if np.any(np.triu(self.A) != 0.0):
            raise ValueError(f"{self.name}: A must be strictly lower triangular (explicit)")
        if self.E.ndim != 2 or self.E.shape[0] not in (1, 2):
            raise ValueError(f"{self.name}: E must have one or two rows")
        if self.E.shape[1] != self.n_stages + 1:
            raise ValueError(f"{self.name}: E must weigh the n_stages + 1 stages")
        if self.P.ndim != 2 or self.P.shape[1] != n_all:
            raise ValueError(f"{self.name}: P must weigh every stage")

    @property
    def n_all(self) -> int:
        """Stages with the dense output's: the step's, its end's derivative, the extra ones."""
        return self.A.shape[0]

    @property
    def rows(self) -> int:
        """Rows of interpolation coefficients a kept step holds."""
        return self.P.shape[0] + (3 if self.interpolant == "hairer" else 0)

    @property
    def dense_evaluations(self) -> int:
        """Extra right-hand sides for a step that a requested time falls inside (a step costs
        ``n_stages``: its end's derivative, which the next step starts from, included)."""
        return self.n_all - self.n_stages - 1

    def arrays(self) -> tuple:
        """What the compiled loop receives (:func:`run_rk`)."""
        return (
            np.ascontiguousarray(self.A),
            np.ascontiguousarray(self.b),
            np.ascontiguousarray(self.E),
            np.ascontiguousarray(self.P),
        )


@functools.cache
def load_pair(name: str) -> Pair:
    """The :class:`Pair` called ``name`` (one of :data:`PAIRS`), built once per process."""
    if name not in PAIRS:
        raise ValueError(f"no Runge-Kutta pair {name!r}; pairs: {', '.join(PAIRS)}")
    return importlib.import_module(f".{name}", __package__).PAIR


@njit(cache=True)
def _rms(x):
    return math.sqrt(np.sum(x * x) / x.size)


# The product's right-hand sides (generated from the equations: :data:`.kernels.RHS`), each a
# global of its own so that a compiled branch calls it directly (a tuple of them would have to
# be indexed at run time, and its items are of different types).
_CHARGE_RHS, _HOOP_RHS, _FREE_BODY_RHS = (RHS[i] for i in (CYCLOTRON, HOOP, FREE_BODY))


def _rhs(sys_id, y, p, out):
    """The right-hand side of system ``sys_id``: one of :mod:`.kernels`' ids, or a compiled
    ``rhs(y, p, out)`` itself (a system known only by its equations: a generated right-hand
    side, :mod:`mechviz.dynamics.codegen.rhs`). Compiled by :func:`_rhs_compiled`; this is the
    interpreter's version (a helper below called from Python)."""
    (sys_id if callable(sys_id) else RHS[sys_id])(y, p, out)


@overload(_rhs, jit_options={"error_model": "numpy"})
def _rhs_compiled(sys_id, y, p, out):
    """:func:`_rhs` in compiled code, chosen by the type of ``sys_id``. Called with a constant
    id, the compiled loop keeps only its branch. An overload rather than a jitted function: it
    is compiled into each caller, so a loop given a right-hand side (whose type names a
    function object of this process) leaves no entry in a disk cache of its own."""
    if isinstance(sys_id, types.Integer):

        def by_id(sys_id, y, p, out):
            if sys_id == CYCLOTRON:
                _CHARGE_RHS(y, p, out)
            elif sys_id == HOOP:
                _HOOP_RHS(y, p, out)
            else:
                _FREE_BODY_RHS(y, p, out)

        return by_id

    def given(sys_id, y, p, out):
        sys_id(y, p, out)

    return given


@register_jitable(error_model="numpy")  # compiled into the runner (see _rhs_compiled)
def _initial_step(sys_id, y0, f0, p, interval, rtol, atol, tmp, f1, error_order):
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
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (error_order + 1.0))
    return min(100.0 * h0, h1, interval)


@njit(cache=True)
def interpolate(Q, y0, x, out, hairer):
    """The interpolant at the fraction ``x`` of the step (0: its start, 1: its end) into
    ``out``: ``Q`` (rows, d) from :func:`dense_coefficients`; ``hairer``: DOP853's nested form
    in ``x`` and ``1 - x``, else the power series ``x (Q0 + x (Q1 + ...))``."""
    d = y0.size
    rows = Q.shape[0]
    for j in range(d):
        v = 0.0
        if hairer:
            for k in range(rows - 1, -1, -1):
                v += Q[k, j]
                if (rows - 1 - k) % 2 == 0:
                    v *= x
                else:
                    v *= 1.0 - x
        else:
            for k in range(rows - 1, -1, -1):
                v = v * x + Q[k, j]
            v *= x
        out[j] = v + y0[j]


@register_jitable(error_model="numpy")  # compiled into the runner (see _rhs_compiled)
def dense_coefficients(sys_id, p, y0, y1, K, h, Q, tmp, kout, A, P, n_stages, hairer):
    """The interpolant of the step ``y0 -> y1`` of length ``h`` whose stages are
    ``K[0 ... n_stages]``: the extra stages into ``K[n_stages + 1:]``, the coefficients into
    ``Q`` (rows, d)."""
    d = y0.size
    n_all = A.shape[0]
    for s in range(n_stages + 1, n_all):
        for j in range(d):
            tmp[j] = 0.0
        for r in range(s):
            a = A[s, r]
            for j in range(d):
                tmp[j] += a * K[r, j]
        for j in range(d):
            tmp[j] = y0[j] + h * tmp[j]
        _rhs(sys_id, tmp, p, kout)
        for j in range(d):
            K[s, j] = kout[j]
    first = 0
    if hairer:
        first = 3
        for j in range(d):
            dy = y1[j] - y0[j]
            Q[0, j] = dy
            Q[1, j] = h * K[0, j] - dy
            Q[2, j] = 2.0 * dy - h * (K[n_stages, j] + K[0, j])
    for k in range(P.shape[0]):
        for j in range(d):
            tmp[j] = 0.0
        for s in range(n_all):
            c = P[k, s]
            for j in range(d):
                tmp[j] += c * K[s, j]
        for j in range(d):
            Q[first + k, j] = h * tmp[j]


@functools.cache
def _runner(
    sys_id, d: int, n_stages: int, n_all: int, blended: bool, hairer: bool, error_order: int
):
    """The loop compiled for system ``sys_id`` (an id, or a compiled right-hand side:
    :func:`_rhs`), states of ``d`` components and a pair of this shape (see :func:`run_rk`).
    Every argument is a constant of the machine code (the closure holds it, and numba keys its
    disk cache on it); the tableau's numbers are arguments, as a global array over about 1 kB
    is neither baked in nor disk-cached. A loop given a right-hand side is compiled once per
    process and right-hand side, not cached on disk."""
    exponent = -1.0 / (error_order + 1.0)
    dense_extra = n_all - n_stages - 1

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
        """Advance every row of ``Y`` (N, d) from ``t0`` to ``t1`` in place.

        ``H`` (N,) carries each member's next step size between calls (0: choose one, as scipy
        does at start-up) and ``F`` (N, d) the derivative at the end of its last step. ``stats``
        (N, 3) accumulates evaluations, accepted and rejected steps. ``status`` as in
        ``run_fixed``, with code ``TOO_SMALL_STEP`` when the controller needs a step below 10 ulp
        of ``t``. ``base`` ... ``last`` are an :class:`RKCarry`'s arrays. ``tableau`` is
        :meth:`Pair.arrays`. ``land``: cut the step that would pass ``t1`` to end there.
        """
        A, B, E, P = tableau
        n = Y.shape[0]
        K = np.empty((n_all, d))
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
                    interpolate(Q[i], Y0[i], (t1 - base[i]) / span[i], y, hairer)
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
                            sys_id, y, F[i], p, abs(t1 - t0), rtol, atol, tmp, K[1], error_order
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
                        for s in range(1, n_stages + 1):
                            for j in range(d):
                                tmp[j] = 0.0
                            if s < n_stages:
                                for r in range(s):
                                    a = A[s, r]
                                    for j in range(d):
                                        tmp[j] += a * K[r, j]
                            else:  # the propagated solution; its derivative starts the next step
                                for r in range(n_stages):
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
                        stats[i, 0] += n_stages
                        # Error estimate (scipy's _estimate_error_norm; DOP853's blended one).
                        for j in range(d):
                            tmp[j] = 0.0
                            err3[j] = 0.0
                        for r in range(n_stages + 1):
                            c5 = E[0, r]
                            if blended:
                                c3 = E[1, r]
                                for j in range(d):
                                    tmp[j] += c5 * K[r, j]
                                    err3[j] += c3 * K[r, j]
                            else:
                                for j in range(d):
                                    tmp[j] += c5 * K[r, j]
                        e5 = 0.0
                        e3 = 0.0
                        finite = True
                        for j in range(d):
                            sc = atol + max(abs(y[j]), abs(y_new[j])) * rtol
                            e5 += (tmp[j] / sc) ** 2
                            if blended:
                                e3 += (err3[j] / sc) ** 2
                            if not math.isfinite(y_new[j]):
                                finite = False
                        if not finite:
                            report(status, NONFINITE, stats[i, 1], i)
                            return
                        if blended:
                            if e5 == 0.0 and e3 == 0.0:
                                err = 0.0
                            else:
                                err = h_abs * e5 / math.sqrt((e5 + 0.01 * e3) * d)
                        else:
                            err = h_abs * math.sqrt(e5 / d)
                        if err < 1.0:
                            if err == 0.0:
                                factor = MAX_FACTOR
                            else:
                                factor = min(MAX_FACTOR, SAFETY * err**exponent)
                            if rejected:
                                factor = min(1.0, factor)
                            h_abs *= factor
                            break
                        h_abs *= max(MIN_FACTOR, SAFETY * err**exponent)
                        rejected = True
                        stats[i, 2] += 1
                    stats[i, 1] += 1
                    for j in range(d):
                        F[i, j] = K[n_stages, j]
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
                        dense_coefficients(
                            sys_id,
                            p,
                            Y0[i],
                            y_new,
                            K,
                            h,
                            Q[i],
                            tmp,
                            kout,
                            A,
                            P,
                            n_stages,
                            hairer,
                        )
                        stats[i, 0] += dense_extra
                        dense[i] = True
                        interpolate(Q[i], Y0[i], (t1 - t) / h, y, hairer)
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

    if callable(sys_id):  # a given right-hand side: its type is this process's (never cached)
        return njit(run)
    return njit(cache=True)(run)


class RKCarry:
    """What one run keeps between calls: each member's last step (module docstring).

    ``base`` [s] and ``span`` [s] (N,) its start and length (``span <= 0``: none kept), ``Y0`` and
    ``Y1`` (N, d) the states at its start and end, ``Q`` (N, rows, d) its interpolation
    coefficients (valid where ``dense``), ``last`` (N, d) the state handed back.
    """

    def __init__(self, n: int, d: int, pair: Pair) -> None:
        self.pair = pair
        self.base = np.zeros(n)
        self.span = np.zeros(n)
        self.Y0 = np.zeros((n, d))
        self.Y1 = np.zeros((n, d))
        self.Q = np.zeros((n, pair.rows, d))
        self.dense = np.zeros(n, dtype=np.bool_)
        self.last = np.zeros((n, d))

    def forget(self) -> None:
        """Keep no step: the next call starts afresh from the state it is given."""
        self.span.fill(0.0)


@functools.cache
def _arrays(pair: Pair) -> tuple:
    return pair.arrays()


def runner_for(pair: Pair, sys_id, d: int):
    """The compiled loop of ``pair`` for system ``sys_id`` (an id, a compiled
    ``rhs(y, p, out)``, or a registered system's :class:`~mechviz.dynamics.forms.SystemForms`,
    whose right-hand side it takes) and states of ``d`` components."""
    if type(sys_id) is SystemForms:
        sys_id = sys_id.rhs
    return _runner(
        sys_id if callable(sys_id) else int(sys_id),
        int(d),
        pair.n_stages,
        pair.n_all,
        pair.E.shape[0] == 2,
        pair.interpolant == "hairer",
        pair.error_order,
    )


def run_rk(
    pair: Pair,
    sys_id,
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
    carry: RKCarry,
    land: bool = False,
) -> None:
    """Advance every row of ``Y`` (N, d) of system ``sys_id`` from ``t0`` to ``t1`` [s] with
    ``pair``, going on from ``carry``'s kept steps and keeping the last ones there. ``land``:
    ``t1`` is a final time; the step that would pass it is cut to end there (module docstring).

    The loop is compiled for the system, for ``d`` and for the pair's shape as constants, and
    cached on disk: with the right-hand side an argument (a first-class function), or any
    compiled function held by the closure, numba would compile it afresh in every process
    (1.5-3 s), and with ``d`` read from the array every per-component loop would have an unknown
    length (DOP853 took 63 instead of 44 ns per evaluation on the hoop, 48 instead of 35 on the
    disk and 38 instead of 27 on the charge, over 500 members at ``rtol = atol = 1e-10``).
    ``sys_id`` may also be a compiled ``rhs(y, p, out)`` (a system known only by its equations,
    :mod:`mechviz.dynamics.codegen.rhs`): its loop is compiled once per process.
    """
    runner_for(pair, sys_id, Y.shape[1])(
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
        _arrays(pair),
        bool(land),
    )
