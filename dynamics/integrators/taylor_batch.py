"""Taylor's method on many problems at once: :data:`LANES` members advanced together.

Many short problems of one system (different starts, parameters, end times; one tolerance, so
one order) are solved in one compiled call. The members' series are expanded together by the
generated batch expansion (:mod:`mechviz.dynamics.codegen.batch`: the one-problem recurrences of
the same equations, written once per member side by side over ``A[row, k, b]``, ``b`` the
member's lane, contiguous), so that one vector instruction serves :data:`LANES` members.

Each lane then takes its own step by the one-problem loop's rule
(:func:`mechviz.dynamics.integrators.taylor._advance_member` from a fresh start): Jorba and
Zou's step from the last two coefficients (:func:`.taylor.controls`), the time summed with
Knuth's two-sum, the last step evaluated at the member's end by its series. A lane whose member
has ended takes the next member waiting (the lanes are a queue over the problems, so no lane
idles while problems wait; only the last few members of a call run with idle lanes beside them,
whose series are computed and thrown away). A member's result is therefore the one-problem
solve's, :func:`mechviz.dynamics.solver.solve_taylor`, to round-off: the step rule, the time
sums and Horner's rule are the same operations; the expansion's sums are in the same order but
may be contracted to fused multiply-adds where the one-problem form's were reassociated (the
tests compare the two to a relative 1e-12).

Failures are per member and spoil no other: ``steps[m] = -1`` when member ``m``'s state stopped
being finite or its step was lost in round-off (``out[m]`` then holds the last state reached),
``-2`` when its start, parameters or end time are not finite (``out[m]`` untouched, nothing
run); its lane goes on with the next member.

Only the systems with a generated batch expansion (:data:`BATCH_SYSTEMS`: the hoop and the
free body) run here; the charge takes its steps in closed form
(:mod:`.taylor_linear`) and a registered system has no batch form: callers fall back to the
one-problem loop for those.
"""

from __future__ import annotations

import contextlib
import math

import numba.core.config
import numpy as np

from .._jit import njit
from ..codegen.batch import batch_module
from .kernels import FREE_BODY, HOOP
from .taylor import controls
from .taylor_linear import two_sum

#: Members per batch: one AVX-512 vector of doubles (two AVX2 vectors). On the 1,000 two-second
#: hoops of ``mechviz bench --batch`` eight took 6.3 us a problem (0.47 of the one-problem
#: compiled loop's time), four 7.2 us (0.53).
LANES = 8


@contextlib.contextmanager
def _slp_on():
    was = numba.core.config.SLP_VECTORIZE
    numba.core.config.SLP_VECTORIZE = 1
    try:
        yield
    finally:
        numba.core.config.SLP_VECTORIZE = was


def slp_vectorised(dispatcher):
    """``dispatcher`` (a numba function), compiled with LLVM's superword-level vectoriser on.

    numba leaves it off by default (``NUMBA_SLP_VECTORIZE``); the batch expansion is written
    for it (the members' copies of a statement side by side: without it they stay scalar and a
    batch costs what the one-problem loop does). Every compilation of ``dispatcher`` (called
    from Python or typed from a compiled caller; loading from numba's cache included) runs with
    it on. It changes no result: a vector operation rounds each lane as the scalar one does."""
    compile_ = dispatcher.compile

    def compile_slp(sig):
        with _slp_on():
            return compile_(sig)

    dispatcher.compile = compile_slp
    return dispatcher


_hoop = batch_module(HOOP, LANES)
_free_body = batch_module(FREE_BODY, LANES)
BATCH_SYSTEMS = frozenset({HOOP, FREE_BODY})
ROWS = max(_hoop.ROWS, _free_body.ROWS)
hoop_batch = slp_vectorised(_hoop.expand)
free_body_batch = slp_vectorised(_free_body.expand)


def batched(sys_id) -> bool:
    """Whether ``sys_id`` (a compiled id, or a registered system's forms) runs here."""
    return isinstance(sys_id, (int, np.integer)) and int(sys_id) in BATCH_SYSTEMS


@slp_vectorised
@njit(cache=True)
def _expand_batch(sys_id, A, P, order):
    if sys_id == HOOP:
        hoop_batch(A, P, order)
    else:
        free_body_batch(A, P, order)


@njit(cache=True)
def _steps(A, d, order, ctl, member, norms, H):
    """:func:`.taylor._step_size` of every busy lane into ``H`` (the same operations; the
    norms of the state and the last two orders over the lanes at once, each lane's logarithms
    and exponential then on its own; an idle lane's step is 0)."""
    lanes = H.size
    for b in range(lanes):
        norms[0, b] = 0.0
        norms[1, b] = 0.0
        norms[2, b] = 0.0
    for j in range(d):
        for b in range(lanes):
            norms[0, b] = max(norms[0, b], abs(A[j, 0, b]))
            norms[1, b] = max(norms[1, b], abs(A[j, order - 1, b]))
            norms[2, b] = max(norms[2, b], abs(A[j, order, b]))
    for b in range(lanes):
        H[b] = 0.0
        if member[b] < 0:
            continue
        na, nb = norms[1, b], norms[2, b]
        ls = math.log(max(ctl[1], ctl[0] * norms[0, b]))
        e = math.inf
        if na > 0.0:
            e = (ls - math.log(na)) * ctl[2]
        if nb > 0.0:
            e = min(e, (ls - math.log(nb)) * ctl[3])
        H[b] = math.exp(e) * ctl[4]


@njit(cache=True)
def _horner_lanes(A, d, order, H, Y):
    """:func:`.taylor._horner` of every lane ``b`` at ``H[b]`` into ``Y[:, b]`` (the same
    operations, the lanes side by side)."""
    lanes = H.size
    for j in range(d):
        for b in range(lanes):
            Y[j, b] = A[j, order, b]
        for k in range(order - 1, -1, -1):
            for b in range(lanes):
                Y[j, b] = Y[j, b] * H[b] + A[j, k, b]


@njit(cache=True)
def _finite_member(Y0, P, T, m):
    if not math.isfinite(T[m]):
        return False
    for v in Y0[m]:
        if not math.isfinite(v):
            return False
    for v in P[m]:
        if not math.isfinite(v):
            return False
    return True


@njit(cache=True)
def _take(b, nxt, Y0, P, T, A, Pl, member, t, c, count, steps):
    """Put the next member with a finite start into lane ``b`` (``member[b] = -1``: none left;
    its state is then zero, whose series is zero, so the idle lane costs no special case).
    Returns the index of the member after it."""
    n, d = Y0.shape
    while nxt < n and not _finite_member(Y0, P, T, nxt):
        steps[nxt] = -2
        nxt += 1
    if nxt >= n:
        member[b] = -1
        for j in range(d):
            A[j, 0, b] = 0.0
        return nxt
    member[b] = nxt
    for j in range(d):
        A[j, 0, b] = Y0[nxt, j]
    for j in range(P.shape[1]):
        Pl[j, b] = P[nxt, j]
    t[b] = 0.0
    c[b] = 0.0
    count[b] = 0
    return nxt + 1


@slp_vectorised
@njit(cache=True)
def solve_batch(sys_id, Y0, P, T, rtol, atol, order, a, out, steps):
    """``out[m]`` = the state at ``T[m]`` from ``Y0[m]`` at 0 with parameters ``P[m]``, for every
    member ``m`` (``Y0``, ``out`` (N, d); ``P`` (N, parameters); ``T`` (N,) [s]), Taylor's
    method at ``order`` with steps ``rho exp(-a - 0.7 / (order - 1))``, :data:`LANES` members
    at a time (module docstring). ``steps[m]``: member ``m``'s steps, ``-1`` if its state
    stopped being finite, ``-2`` if its start, parameters or end are not finite. Returns the
    steps taken by all members (the expansions: that many divided by about :data:`LANES`)."""
    d = Y0.shape[1]
    lanes = LANES
    ctl = controls(rtol, atol, order, a)
    # every entry of A a lane reads is written first but the idle lanes' (zero states, zero
    # series); parameters of ones keep an idle lane's constants finite
    A = np.zeros((ROWS, order + 1, lanes))
    Pl = np.ones((P.shape[1], lanes))
    member = np.empty(lanes, np.int64)
    t = np.zeros(lanes)
    c = np.zeros(lanes)
    count = np.zeros(lanes, np.int64)
    H = np.zeros(lanes)  # each lane's step, or the rest of its span on its last step
    last = np.zeros(lanes, np.int64)  # 1: the lane's last step, 2: its member failed
    norms = np.zeros((3, lanes))
    Y = np.empty((d, lanes))
    nxt = 0
    busy = 0
    for b in range(lanes):
        nxt = _take(b, nxt, Y0, P, T, A, Pl, member, t, c, count, steps)
        if member[b] >= 0:
            busy += 1
    total = 0
    while busy > 0:
        _expand_batch(sys_id, A, Pl, order)
        _steps(A, d, order, ctl, member, norms, H)
        for b in range(lanes):
            m = member[b]
            last[b] = 0
            if m < 0:
                continue
            h = H[b]
            count[b] += 1
            total += 1
            if not (h > 0.0 and t[b] + h > t[b]):  # nan, or a step lost in round-off
                last[b] = 2
                H[b] = 0.0
            else:
                rest = (T[m] - t[b]) - c[b]
                if h >= rest:
                    last[b] = 1
                    H[b] = rest
        _horner_lanes(A, d, order, H, Y)
        for b in range(lanes):
            m = member[b]
            if m < 0:
                continue
            if last[b] == 0:
                for j in range(d):
                    A[j, 0, b] = Y[j, b]
                t[b], e = two_sum(t[b], H[b])
                c[b] += e
                continue
            finite = last[b] == 1
            for j in range(d):
                out[m, j] = Y[j, b] if last[b] == 1 else A[j, 0, b]
                if not math.isfinite(out[m, j]):
                    finite = False
            steps[m] = count[b] if finite else -1
            nxt = _take(b, nxt, Y0, P, T, A, Pl, member, t, c, count, steps)
            if member[b] < 0:
                busy -= 1
    # members left after the last lane fell idle can only be ones not finite (marked by _take)
    return total
