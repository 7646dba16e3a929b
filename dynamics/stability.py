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

import numpy as np

from .integrators.base import METHODS, Method, get_method
from .integrators.limits import MIDPOINT_SOLVE_LIMIT, SQRT8, YOSHIDA4_LIMIT  # noqa: F401


def _method(method: str | Method) -> Method:
    return method if isinstance(method, Method) else get_method(method)


def amplification(method: str | Method, x: float) -> float:
    """Spectral radius of one step of ``method`` on the oscillation at ``x = omega h`` (the
    method's own ``amplification``; ``ValueError`` for a method without one, an adaptive one)."""
    m = _method(method)
    if m.amplification is None:
        raise ValueError(f"no amplification factor for method {m.name!r}")
    return m.amplification(abs(float(x)))


def reason(method: str | Method) -> str:
    """Why the method's limit is where it is (shown beside the marker in the viewer and the
    chart); ``ValueError`` for a method without a fixed-step limit."""
    m = _method(method)
    if not m.limit_reason:
        raise ValueError(f"no stability limit known for method {m.name!r}")
    return m.limit_reason


def limit_omega_dt(method: str | Method, system=None) -> float | None:
    """Largest stable ``omega h`` for ``method`` (``None``: no limit; ``0``: none stable).

    ``yoshida4`` composes ``system``'s own symmetric step (a :mod:`mechviz.dynamics.systems` adapter or
    its class): where that step keeps the norm at any step (Boris on the charge, the rotation
    splitting on the free body) so does the composition; only over Verlet (the hoop) is there a
    limit.
    """
    m = _method(method)
    reason(m)  # raises for a method without a fixed-step limit
    if m.needs == "symmetric" and system is not None:
        # a composition of the system's own step (a method of that name): no limit where that
        # step has none
        own = METHODS.get(system.symmetric_step)
        if own is None or own.limit_omega_dt is None:
            return None
    return m.limit_omega_dt


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
    if method.adaptive or method.closed_form:
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
