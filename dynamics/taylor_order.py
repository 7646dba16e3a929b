"""Taylor's method's order and step rule (:func:`order_for`), without the compiled code.

Kept apart from :mod:`mechviz.dynamics.integrators.taylor` so that code loading the method compiled ahead
of time (:mod:`mechviz.dynamics.aot`) can choose the order without importing numba.
"""

from __future__ import annotations

import functools
import math

from .forms import SystemForms
from .ids import COMPILED, HOOP

MAX_ORDER = 40

# Cost of one step [ns] as c0 + c1 p + c2 p^2 at order p, by compiled system (its entry in
# :data:`mechviz.dynamics.ids.COMPILED` says it); a dict, so a test may vary one.
STEP_COST = {c.sys_id: c.taylor_cost for c in COMPILED.values()}


# Systems whose solutions are entire functions with coefficients falling as 1/k! (the charge's
# sines and cosines): the last two coefficients put the radius of convergence at about
# (p!)^(1/p) / |Omega|, growing with the order, so the step grows with it (:func:`order_for`).
ENTIRE = frozenset(c.sys_id for c in COMPILED.values() if c.entire)
TIGHT_TOL = 1e-14
TIGHT_A_MIN = 1.25


@functools.lru_cache(maxsize=1024)
def order_for(rtol: float, atol: float, sys_id: int | SystemForms = HOOP) -> tuple[int, float]:
    """``(p, a)``: the order and the step ``rho exp(-a)`` that make the work over a span least.

    Jorba and Zou's argument: the error estimate is ``(h / rho)^(p-1) = tol``, so with
    ``h = rho e^-a`` the order is ``p = ln(1/tol)/a + 1`` and the work over a span is
    ``cost(p) e^a``. For ``cost ~ p^2`` that is least at ``a = 2``, their choice (and heyoka's);
    here ``cost(p)`` is the system's :data:`STEP_COST`, whose constant and linear parts favour
    higher orders and longer steps (``a`` between 1 and 2; only linear terms, the charge: about
    0.7). ``a`` is kept at least 1 (a step at most ``rho / e``): the estimate from the last two
    coefficients is trusted only well inside the radius of convergence. Below
    :data:`TIGHT_TOL` it is at least :data:`TIGHT_A_MIN`: there the round-off of the series' sum
    matters, and on a long step of an entire solution (the charge's sines, whose estimated radius
    grows with the order) the terms grow before they fall and cancel (the untuned charge's error
    stopped at 3e-12 with a = 1, 5e-13 with 1.25).

    ``sys_id``: a compiled id, or a registered system's forms, which state their own cost model
    (:class:`~mechviz.dynamics.forms.SystemForms`).
    """
    tol = min(rtol, atol)
    given = type(sys_id) is SystemForms
    c0, c1, c2 = sys_id.taylor_cost if given else STEP_COST[sys_id]
    entire = sys_id.entire if given else sys_id in ENTIRE
    L = -math.log(tol)
    a_min = 1.0 if tol >= TIGHT_TOL else TIGHT_A_MIN

    def work(p: int) -> float:
        steps = math.exp(max(a_min, L / (p - 1)))
        if entire:  # the radius estimate grows as (p!)^(1/p): longer steps
            steps /= math.exp(math.lgamma(p + 1.0) / p)
        return (c0 + c1 * p + c2 * p * p) * steps

    p = min(range(3, MAX_ORDER + 1), key=work)
    return p, max(a_min, L / (p - 1))
