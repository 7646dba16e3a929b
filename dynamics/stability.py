"""Where each fixed-step method stops being stable: closed-form amplification factors and limits.

Every method is judged on the test oscillation ``y' = i omega y`` (a gyration, or one normal mode
of a linearised system), with ``x = omega h`` the angle the exact flow turns through in one step.
The *amplification factor* is the spectral radius of the method's one-step map on that problem:
1 means the oscillation neither grows nor decays, above 1 it grows geometrically.

========== ===================================== ===========================================
method     amplification factor at ``x``         largest stable ``x``
========== ===================================== ===========================================
euler      ``sqrt(1 + x^2)``                     none: grows at every step size
rk4        ``sqrt(1 - x^6/72 + x^8/576)``        ``2 sqrt 2`` (decays below, grows above)
verlet     1 for ``x < 2``, else the larger root  2
           of ``l^2 - (2 - x^2) l + 1``
yoshida4   spectral radius of the Stormer-Verlet  about 1.5734 (found numerically)
           maps at ``w1 x, w0 x, w1 x``
midpoint   1 (Cayley map)                        the method: any; our fixed-point solve
                                                 (error x/2 per sweep, 100 sweeps to 1e-14)
                                                 only for ``x < 2 (1e-14)^(1/100) = 1.449``
boris,     1 (the velocity is rotated)            any
exact,
splitting
========== ===================================== ===========================================

:func:`stability_limit` turns these into the largest stable step ``dt`` for a system by dividing
by its fastest frequency (:func:`fastest_frequency`): the gyrofrequency of the charge, the higher
normal mode of the hoop, the spectral radius of the free body's Jacobian at its state. The
viewer's step-size control marks that value.

References: Hairer, Lubich & Wanner, *Geometric Numerical Integration* (2006), sections I.1
and VI.3; Hairer & Wanner, *Solving ODEs II*, section IV.2 (stability functions).
"""

from __future__ import annotations

import math

import numpy as np

from .integrators.kernels import MIDPOINT_MAX_ITER, MIDPOINT_TOL, YOSHIDA_W0, YOSHIDA_W1

SQRT8 = 2.0 * math.sqrt(2.0)


def _verlet_matrix(x: float) -> np.ndarray:
    """Kick-drift-kick Stormer-Verlet on ``q'' = -q`` in the variables ``(q, p / omega)``."""
    return np.array([[1.0 - 0.5 * x * x, x], [-x * (1.0 - 0.25 * x * x), 1.0 - 0.5 * x * x]])


def _spectral_radius(m: np.ndarray) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(m))))


def amplification(method: str, x: float) -> float:
    """Spectral radius of one step of ``method`` on the oscillation at ``x = omega h``."""
    x = abs(float(x))
    if method == "euler":
        return math.sqrt(1.0 + x * x)
    if method == "rk4":
        return math.sqrt(max(0.0, 1.0 - x**6 / 72.0 + x**8 / 576.0))
    if method == "verlet":
        return _spectral_radius(_verlet_matrix(x))
    if method == "yoshida4":
        m = _verlet_matrix(YOSHIDA_W1 * x) @ _verlet_matrix(YOSHIDA_W0 * x)
        return _spectral_radius(_verlet_matrix(YOSHIDA_W1 * x) @ m)
    if method in ("midpoint", "boris", "exact", "splitting"):
        return 1.0
    raise ValueError(f"no amplification factor for method {method!r}")


def _yoshida4_limit() -> float:
    """First ``x`` where the Yoshida composition of Verlet steps leaves the unit circle: the
    trace of its 2x2 (unit-determinant) map reaches -2 or 2. Bisection to round-off."""

    def excess(x: float) -> float:
        m = _verlet_matrix(YOSHIDA_W1 * x) @ _verlet_matrix(YOSHIDA_W0 * x)
        return abs(np.trace(_verlet_matrix(YOSHIDA_W1 * x) @ m)) - 2.0

    lo, hi = 0.5, 0.5
    while excess(hi) < 0.0:
        lo, hi = hi, hi + 0.01
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) < 0.0 else (lo, mid)
    return lo


YOSHIDA4_LIMIT = _yoshida4_limit()
MIDPOINT_SOLVE_LIMIT = 2.0 * MIDPOINT_TOL ** (1.0 / MIDPOINT_MAX_ITER)  # 1.449 for 1e-14, 100

# Largest stable x = omega h per method: 0.0 = never stable, None = stable at every step.
LIMITS: dict[str, float | None] = {
    "euler": 0.0,
    "rk4": SQRT8,
    "verlet": 2.0,
    "yoshida4": YOSHIDA4_LIMIT,
    # Not the method (A-stable) but its fixed-point solve: on the oscillation each sweep shrinks
    # the error by x/2, and MIDPOINT_MAX_ITER sweeps must reach MIDPOINT_TOL.
    "midpoint": MIDPOINT_SOLVE_LIMIT,
    "boris": None,
    "exact": None,
    "splitting": None,
}

# Why the limit is where it is (shown beside the marker in the viewer and the chart).
REASONS = {
    "euler": "explicit Euler amplifies every oscillation by sqrt(1 + (omega dt)^2) per step",
    "rk4": "RK4 is stable on an oscillation for omega dt <= 2 sqrt 2",
    "verlet": "Stormer-Verlet is stable for omega_max dt < 2",
    "yoshida4": "the Yoshida composition of Verlet steps is stable for omega dt < 1.5734",
    "midpoint": (
        "the implicit midpoint rule's fixed-point solve reaches 1e-14 in 100 sweeps only for "
        "omega dt < 1.449"
    ),
    "boris": "Boris rotates the velocity exactly: stable at any step",
    "exact": "the exact flow: stable at any step",
    "splitting": "exact rotations keep |L|: stable at any step",
}


def limit_omega_dt(method: str, system=None) -> float | None:
    """Largest stable ``omega h`` for ``method`` (``None``: no limit; ``0``: none stable).

    ``yoshida4`` composes ``system``'s own symmetric step (a :mod:`mechviz.dynamics.systems` adapter or
    its class): where that step keeps the norm at any step (Boris on the charge, the rotation
    splitting on the free body) so does the composition; only over Verlet (the hoop) is there a
    limit.
    """
    if method not in LIMITS:
        raise ValueError(f"no stability limit known for method {method!r}")
    if method == "yoshida4" and system is not None and LIMITS.get(system.symmetric_step) is None:
        return None
    return LIMITS[method]


def fastest_frequency(system, state: np.ndarray | None = None) -> float:
    """The highest angular frequency [rad/s] a step has to resolve in ``system`` from ``state``
    (default: its initial state): each adapter's ``fastest_frequency`` says how it is found."""
    return system.fastest_frequency(state)


def stability_limit(method_name: str, system, state: np.ndarray | None = None) -> float | None:
    """Largest stable ``dt`` [s] for ``method_name`` on ``system`` (a :mod:`mechviz.dynamics.systems`
    adapter, or its name for the default parameters).

    ``None`` when the method is stable at any step (or adaptive, or exact); ``0.0`` when it is
    stable at none (explicit Euler on an oscillation).
    """
    from .integrators.base import get_method

    if isinstance(system, str):
        system = _default_system(system)
    method = get_method(method_name)
    if not method.applies_to(system):
        raise ValueError(f"method {method_name!r} does not apply to {system.name}")
    if method.adaptive or method.backend == "exact":
        return None
    x = limit_omega_dt(method_name, system)
    if x is None or x == 0.0:
        return x
    return x / fastest_frequency(system, state)


def _default_system(name: str):
    """The adapter called ``name`` in :data:`mechviz.dynamics.systems.SYSTEMS`, default parameters."""
    from .systems import SYSTEMS

    try:
        return SYSTEMS[name]()
    except KeyError:
        raise ValueError(f"unknown system {name!r}; choose one of {', '.join(SYSTEMS)}") from None
