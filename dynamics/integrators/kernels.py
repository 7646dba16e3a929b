"""Compiled fixed-step integrators.

Two kinds of step, each with one signature:

- a *direct* step ``step(y, p, h) -> evals`` is a system's own compiled step (RK4 in scalar
  locals, generated from the equations; Boris, Stormer-Verlet, the rotation splitting, the
  exact flow);
- a *composed* step ``step(inner, y, p, h, work) -> evals`` is generic over ``inner``: the
  system's right-hand side ``rhs(y, p, out)`` for explicit Euler and the implicit midpoint rule,
  or the system's symmetric second-order step for Yoshida's composition.

Each advances one state ``y`` (d,) by ``h`` in place and returns the number of evaluations
used, or -1 if an implicit solve failed. :func:`run_direct` and :func:`run_composed` advance a
batch ``Y`` (N, d), ensemble on the leading axis, by ``n_steps`` steps inside compiled code
(member outer: see :func:`run_direct`). numba specialises them for each step function they
receive, so the step is called directly; every extra call layer that passes arrays costs tens
of ns per step here (reference counting), which is why the direct steps are the physics
functions themselves.
Functions that receive compiled functions as arguments are compiled once per process (about
0.3-1 s each) and never cached on disk: numba keys such a cache entry on the argument's
dispatcher type, which differs in every process, so ``cache=True`` only appended a new entry per
process to an ever-growing index, and saving that index failed ("underlying object has
vanished") once it held a type whose dispatcher was gone.
"""

from __future__ import annotations

import math

import numpy as np

from .. import cyclotron, disk, hoop
from .._jit import njit
from ..codegen.product import product_module
from ..forms import SystemForms
from ..ids import CYCLOTRON, FREE_BODY, HOOP  # (also re-exported)
from .codes import (  # noqa: F401  (re-exported: the status codes and the methods' constants)
    MIDPOINT_MAX_ITER,
    MIDPOINT_TOL,
    NO_CONVERGENCE,
    NONFINITE,
    OK,
    TOO_SMALL_STEP,
    YOSHIDA_W0,
    YOSHIDA_W1,
)

# System ids (:mod:`mechviz.dynamics.ids`): index into the tables at the bottom.


@njit  # takes a compiled function: never disk-cached (see the module docstring)
def euler_step(rhs, y, p, h, work):
    """Explicit Euler, ``y += h f(y)``. First order; unstable on every undamped oscillation."""
    k = work[0]
    rhs(y, p, k)
    for j in range(y.size):
        y[j] += h * k[j]
    return 1


@njit  # takes a compiled function: never disk-cached (see the module docstring)
def midpoint_step(rhs, y, p, h, work):
    """Implicit midpoint ``y1 = y + h f((y + y1)/2)`` by fixed-point iteration from Euler's guess.

    Symmetric and symplectic; keeps every quadratic invariant. Returns the evaluations used, or
    -1 if the iteration did not converge (the step is too large for the fixed point to contract).
    """
    k, mid, y1 = work[0], work[1], work[2]
    d = y.size
    rhs(y, p, k)
    for j in range(d):
        y1[j] = y[j] + h * k[j]
    evals = 1
    for _ in range(MIDPOINT_MAX_ITER):
        for j in range(d):
            mid[j] = 0.5 * (y[j] + y1[j])
        rhs(mid, p, k)
        evals += 1
        change = 0.0
        size = 0.0
        for j in range(d):
            new = y[j] + h * k[j]
            change += abs(new - y1[j])
            size += abs(new)
            y1[j] = new
        # An iterate that overflowed is no fixed point (inf <= inf would pass): the iteration
        # diverged, which is the failure to report, not a step to a non-finite state.
        if change <= MIDPOINT_TOL * (1.0 + size) and size < math.inf:
            for j in range(d):
                y[j] = y1[j]
            return evals
    return -1


@njit  # takes a compiled function: never disk-cached (see the module docstring)
def yoshida4_step(base, y, p, h, work):
    """Yoshida's fourth-order triple jump of a symmetric second-order ``base(y, p, h)`` step."""
    e1 = base(y, p, YOSHIDA_W1 * h)
    if e1 < 0:
        return -1
    e2 = base(y, p, YOSHIDA_W0 * h)
    if e2 < 0:
        return -1
    e3 = base(y, p, YOSHIDA_W1 * h)
    if e3 < 0:
        return -1
    return e1 + e2 + e3


@njit(cache=True)
def _failed(y, e):
    """True if the step failed (-1) or left a non-finite number (inf and NaN survive a sum)."""
    total = 0.0
    for j in range(y.size):
        total += y[j]
    return e < 0 or not math.isfinite(total)


@njit(cache=True)
def report(status, code, k, i):
    """Record a failure: ``code`` at step ``k`` of member ``i``."""
    status[0] = code
    status[1] = k
    status[2] = i


@njit(cache=True)
def _report(status, e, k, i):
    report(status, NO_CONVERGENCE if e < 0 else NONFINITE, k, i)


@njit  # takes a compiled function: never disk-cached (see the module docstring)
def run_direct(step, Y, p, h, n_steps, status):
    """Advance every row of ``Y`` (N, d) by ``n_steps`` direct steps of ``h``, in place.

    Returns the total number of evaluations. On failure stops and fills
    ``status = [code, step index, member index]`` with the earliest failure in time (the
    lowest member index among failures at the same step); the caller restores the states.

    The members are independent, so each is taken through all its steps before the next
    (member outer): the row view ``Y[i]`` is then made once per member instead of once per
    step. That view is reference counted, and making it every step can cost more than a
    whole cheap step (docs/bench has the figures); the states are bit for bit those of a
    time-outer loop. A member only needs stepping up to the earliest failure found so far.
    """
    nfev = 0
    status[0] = OK
    limit = n_steps
    for i in range(Y.shape[0]):
        y = Y[i]
        for k in range(limit):
            e = step(y, p, h)
            if _failed(y, e):
                _report(status, e, k, i)
                limit = k
                break
            nfev += e
    return nfev


@njit  # takes a compiled function: never disk-cached (see the module docstring)
def run_composed(step, inner, Y, p, h, n_steps, status):
    """As :func:`run_direct` for a composed ``step(inner, y, p, h, work)``."""
    work = np.empty((3, Y.shape[1]))
    nfev = 0
    status[0] = OK
    limit = n_steps
    for i in range(Y.shape[0]):
        y = Y[i]
        for k in range(limit):
            e = step(inner, y, p, h, work)
            if _failed(y, e):
                _report(status, e, k, i)
                limit = k
                break
            nfev += e
    return nfev


# Per system (index = system id): right-hand side, own symmetric second-order step, RK4.
# The right-hand sides and RK4 steps are generated from the equations written once
# (:mod:`..codegen`: loaded from the cache folder, without sympy once written); per step they
# cost what the hand-written ones they replaced did (``mechviz bench --generated-cost``).
_IDS = (CYCLOTRON, HOOP, FREE_BODY)
RHS = tuple(product_module(i, "rhs").rhs for i in _IDS)
SYMMETRIC2 = (cyclotron.boris_step, hoop.verlet_step, disk.splitting_step)
RK4 = tuple(product_module(i, "step").rk4_step for i in _IDS)
#: The compiled exact flows ``step(y, p, h)``, by id: the charge's only (None: none).
EXACT = (cyclotron.exact_step, None, None)


def rhs_of(sys_id: int | SystemForms):
    """The compiled right-hand side of system ``sys_id``: a compiled id's from :data:`RHS`, a
    registered system's from its own forms (:class:`~mechviz.dynamics.forms.SystemForms`)."""
    return sys_id.rhs if type(sys_id) is SystemForms else RHS[sys_id]
