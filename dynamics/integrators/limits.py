"""Each fixed-step method's behaviour on the test oscillation ``y' = i omega y``, as functions of
``x = omega h``: its amplification factor and the largest stable ``x``. The methods of
:mod:`.base` carry these; :mod:`mechviz.dynamics.stability` explains and applies them."""

from __future__ import annotations

import math

import numpy as np

from .codes import MIDPOINT_MAX_ITER, MIDPOINT_TOL, YOSHIDA_W0, YOSHIDA_W1

SQRT8 = 2.0 * math.sqrt(2.0)


def verlet_matrix(x: float) -> np.ndarray:
    """Kick-drift-kick Stormer-Verlet on ``q'' = -q`` in the variables ``(q, p / omega)``."""
    return np.array([[1.0 - 0.5 * x * x, x], [-x * (1.0 - 0.25 * x * x), 1.0 - 0.5 * x * x]])


def _spectral_radius(m: np.ndarray) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(m))))


def euler(x: float) -> float:
    return math.sqrt(1.0 + x * x)


def rk4(x: float) -> float:
    return math.sqrt(max(0.0, 1.0 - x**6 / 72.0 + x**8 / 576.0))


def verlet(x: float) -> float:
    return _spectral_radius(verlet_matrix(x))


def _yoshida4_map(x: float) -> np.ndarray:
    m = verlet_matrix(YOSHIDA_W1 * x) @ verlet_matrix(YOSHIDA_W0 * x)
    return verlet_matrix(YOSHIDA_W1 * x) @ m


def yoshida4(x: float) -> float:
    """The Yoshida composition of Stormer-Verlet steps (over Boris or the rotation splitting it
    keeps the norm, as they do: factor 1)."""
    return _spectral_radius(_yoshida4_map(x))


def unit(x: float) -> float:
    """Norm-preserving on the oscillation at every step: the exact flow, Boris, the splitting,
    the implicit midpoint rule (a Cayley map)."""
    return 1.0


def _yoshida4_limit() -> float:
    """First ``x`` where the Yoshida composition of Verlet steps leaves the unit circle: the
    trace of its 2x2 (unit-determinant) map reaches -2 or 2. Bisection to round-off."""

    def excess(x: float) -> float:
        return abs(np.trace(_yoshida4_map(x))) - 2.0

    lo, hi = 0.5, 0.5
    while excess(hi) < 0.0:
        lo, hi = hi, hi + 0.01
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) < 0.0 else (lo, mid)
    return lo


YOSHIDA4_LIMIT = _yoshida4_limit()
# Not the midpoint rule (A-stable) but its fixed-point solve: on the oscillation each sweep
# shrinks the error by x/2, and MIDPOINT_MAX_ITER sweeps must reach MIDPOINT_TOL.
MIDPOINT_SOLVE_LIMIT = 2.0 * MIDPOINT_TOL ** (1.0 / MIDPOINT_MAX_ITER)  # 1.449 for 1e-14, 100
