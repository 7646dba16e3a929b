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


@functools.lru_cache(maxsize=64)
def _work_model(sys_id: int | SystemForms):
    """``(work(p, L), a_min(L))``: the modelled work over a span at order ``p`` for
    ``L = ln(1/tol)``, and the least ``a`` allowed there (:func:`order_for`)."""
    given = type(sys_id) is SystemForms
    c0, c1, c2 = sys_id.taylor_cost if given else STEP_COST[sys_id]
    entire = sys_id.entire if given else sys_id in ENTIRE
    L_tight = -math.log(TIGHT_TOL)
    # log(cost(p)) less, for an entire solution, the log of the step's growth with the order:
    # the radius estimate grows as (p!)^(1/p), so the steps are longer.
    log_cost = [math.inf] * 3 + [
        math.log(c0 + c1 * p + c2 * p * p) - (math.lgamma(p + 1.0) / p if entire else 0.0)
        for p in range(3, MAX_ORDER + 1)
    ]

    def a_min(L: float) -> float:
        return 1.0 if L <= L_tight else TIGHT_A_MIN

    def work(p: int, L: float) -> float:  # the logarithm of the work: the same order of choices
        return log_cost[p] + max(1.0 if L <= L_tight else TIGHT_A_MIN, L / (p - 1))

    return work, a_min


def _best_order(work, L: float, start: int = 3) -> int:
    """The order of least modelled work at ``L``, by descent from ``start``: the work is
    unimodal in the order (a test checks it against the minimum over every order), so a few
    evaluations find it."""
    p = start
    while p < MAX_ORDER and work(p + 1, L) < work(p, L):
        p += 1
    while p > 3 and work(p - 1, L) <= work(p, L):
        p -= 1
    return p


@functools.lru_cache(maxsize=256)
def band_end(sys_id: int | SystemForms, p: int) -> float:
    """The largest ``L = ln(1/tol)`` at which the work model chooses order ``p < MAX_ORDER`` (the
    tight end of ``p``'s band). Found by bisection over a fixed bracket, so that it is the same
    number whatever tolerance asks for it."""
    work, _ = _work_model(sys_id)
    lo, hi = 0.0, 1024.0  # the choice moves up with L: p is chosen below the end, not above
    for _ in range(52):
        mid = 0.5 * (lo + hi)
        if _best_order(work, mid, p) <= p:
            lo = mid
        else:
            hi = mid
    return lo


# The work model's orders with their bands' ends, loosest first, by system, found as far as a
# tolerance has needed them (most tolerances need a few: the first answer should not wait for all).
_CHOSEN: dict = {}


def _chosen(sys_id: int | SystemForms, L: float) -> list[tuple[int, float]]:
    """The work model's orders and their bands' ends, at least until a level (every second one)
    ends at or beyond ``L``, or the last order (:func:`levels`)."""
    chosen = _CHOSEN.setdefault(sys_id, [])
    work, _ = _work_model(sys_id)
    while True:
        kept = chosen[1::2]
        if (kept and kept[-1][1] >= L) or (chosen and chosen[-1][0] == MAX_ORDER):
            return chosen
        if not chosen:
            p = _best_order(work, 1e-3)
        else:
            last, end = chosen[-1]
            p = max(last + 1, _best_order(work, end + 1e-9, last))
        chosen.append((p, band_end(sys_id, p) if p < MAX_ORDER else math.inf))


def levels(sys_id: int | SystemForms) -> tuple[tuple[int, float], ...]:
    """The tolerance levels: ``(p, L_end)`` pairs, loosest first, each the order used for
    ``L = ln(1/tol)`` up to ``L_end`` (after the previous level's), stepped at ``L_end``
    (:func:`order_for`). Every second order the work model chooses, its level covering its own
    band and the band below; the last level, :data:`MAX_ORDER`'s, has no end (``inf``)."""
    chosen = _chosen(sys_id, math.inf)
    kept = [level for level in chosen[1::2] if level[0] < MAX_ORDER]
    return (*kept, (MAX_ORDER, math.inf))


def forget() -> None:
    """Drop the cached choices (:func:`order_for`, :func:`levels`, :func:`band_end`): for a
    change of :data:`STEP_COST`."""
    for cached in (order_for, band_end, _work_model):
        cached.cache_clear()
    _CHOSEN.clear()


@functools.lru_cache(maxsize=1024)
def order_for(rtol: float, atol: float, sys_id: int | SystemForms = HOOP) -> tuple[int, float]:
    """``(p, a)``: the order that makes the work over a span least, and its step ``rho exp(-a)``.

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

    **Tolerance levels.** The tolerance asked is rounded down to a level, and every tolerance
    of a level takes the same steps (the same answer, bit for bit): the level's order ``p`` with
    ``a = L_end / (p - 1)``, ``L_end`` the level's tightest ``ln(1/tol)`` (:func:`levels`). The
    levels are the tight ends of every second order's band (the tolerances for which the work
    model chooses that order), one to two decades apart. Why: with ``a`` following the
    tolerance, the error falls smoothly inside one order's band, but where the order steps up
    the error's constant changes with it (each order's truncation error has its own size and
    sign along the run: the coefficients whose sizes set the step rise and fall with the
    order), and a tolerance tightened across the step could give a worse answer: at 33
    tolerances from 1e-3 to 1e-12, up to 4 times worse on the default hoop and up to 180 times
    on random hoops and disks. Levels whose tolerances are far apart make the error fall from
    level to level by more than the orders' constants differ (``tests/test_taylor_levels.py``).
    The price is the work of the tighter tolerance within a level: about 8 % more time at the
    same tolerance, summed over those 33 tolerances on 14 random hoops and disks (and each
    answer more accurate).
    The last level (:data:`MAX_ORDER`) has no tight end: there ``a`` follows the tolerance.

    ``sys_id``: a compiled id, or a registered system's forms, which state their own cost model
    (:class:`~mechviz.dynamics.forms.SystemForms`).
    """
    _, a_min = _work_model(sys_id)
    L = -math.log(min(rtol, atol))
    tiers = (*_chosen(sys_id, L)[1::2], (MAX_ORDER, math.inf))
    p, end = next((p, end) for p, end in tiers if L <= end)
    L = L if end == math.inf else end
    return p, max(a_min(L), L / (p - 1))
