"""A Runge-Kutta pair from its exact coefficients: the tables of the Verner pairs are fractions
(and, for the 9(8) pair, numbers ``r + s sqrt(6)``); they are combined exactly (``E = b - b_hat``,
the nodes ``c``) and rounded once to float64 into a :class:`~.rk.Pair`. The tests read the same
tables in 60 digits to check the order conditions."""

from __future__ import annotations

import numpy as np

from .rk import Pair

#: Digits carried while exact coefficients are combined and rounded to float64.
EXACT_DIGITS = 60


def exact(v):
    """An exact coefficient as an ``mpmath.mpf`` of :data:`EXACT_DIGITS` digits: ``"p/q"`` (or an
    integer or a decimal string), or a pair ``(r, s)`` of those meaning ``r + s sqrt(6)``."""
    import mpmath  # deferred: only the exact tables need it

    def one(x: str):
        num, _, den = str(x).partition("/")
        return mpmath.mpf(num) / (mpmath.mpf(den) if den else 1)

    with mpmath.workdps(EXACT_DIGITS):
        if isinstance(v, tuple):
            r, s = v
            return one(r) + one(s) * mpmath.sqrt(6)
        return one(v)


def pair_from_exact(
    name: str,
    *,
    order: int,
    error_order: int,
    dense_order: int,
    n_stages: int,
    a: dict,
    b: dict,
    b_hat: dict,
    interpolant: dict,
    source: str = "",
) -> Pair:
    """A :class:`Pair` from exact coefficients keyed by 0-based stage: ``a[(i, j)]`` for every
    stage but the step's end (whose row is ``b``), ``b[j]``, ``b_hat[j]`` (the embedded
    solution's weights, which may use the step's end, stage ``n_stages``) and
    ``interpolant[j]`` the coefficients of ``x^1, x^2, ...`` in ``b_j(x)``; absent entries are 0.
    Values as :func:`exact` reads them. ``E = b - b_hat`` and ``c`` (the row sums of ``A``) are
    formed exactly; every number is then rounded once to float64."""
    import mpmath

    with mpmath.workdps(EXACT_DIGITS):
        ex_a = {k: exact(v) for k, v in a.items()}
        ex_b = {j: exact(v) for j, v in b.items()}
        for j, v in ex_b.items():
            ex_a[(n_stages, j)] = v
        n_all = 1 + max(max(i for i, _ in ex_a), max(interpolant))
        A = np.zeros((n_all, n_all))
        c = np.zeros(n_all)
        sums = [mpmath.mpf(0)] * n_all
        for (i, j), v in ex_a.items():
            A[i, j] = float(v)
            sums[i] += v
        c[:] = [float(x) for x in sums]
        E = np.zeros((1, n_stages + 1))
        for j in set(b) | set(b_hat):
            E[0, j] = float(ex_b.get(j, 0) - (exact(b_hat[j]) if j in b_hat else 0))
        power = max(len(v) for v in interpolant.values())
        P = np.zeros((power, n_all))
        for j, coefs in interpolant.items():
            for k, v in enumerate(coefs):
                P[k, j] = float(exact(v))
    bb = A[n_stages, :n_stages].copy()
    return Pair(
        name, order, error_order, dense_order, n_stages, A, bb, c, E, P, "power", source=source
    )
